"""Batches of files over Dask's distributed scheduler (``clpde batch``, ``clpde.batch``).

One task per input: a worker runs the same code as the single-file command (``clpde
inpaint``, ``denoise``, ``diffuse``, ``track`` or ``surface``) on a path and writes its output
atomically into OUTDIR. Only paths, option strings and small result records travel between
the client and the workers; every worker process builds its own OpenCL runtime on first use
(clpde.runtime caches it per process), so nothing holding an OpenCL object is pickled.

By default a ``distributed.LocalCluster`` is started on this machine: spawned worker
processes, one Python thread each, and PoCL's thread count per worker set (through
POCL_MAX_PTHREAD_COUNT, before OpenCL loads in the worker) so that workers x threads =
cores. On a machine with GPUs there is one worker per GPU instead, pinned to it through
CLPDE_DEVICE and advertising the resource ``GPU=1`` that every task asks for. Give
``scheduler="tcp://HOST:8786"`` to use a cluster started with ``dask scheduler`` and
``dask worker`` instead; the inputs and OUTDIR must then be at the same paths on every
machine (a shared file system).

Nothing is lost: OUTDIR/clpde-manifest.json records, for every output written, the hash of
its input (and mask) and the options; a rerun skips the outputs whose record matches. A
worker that dies has its task run elsewhere by the scheduler. A failing input is reported
by name in the result and does not stop the others. Ctrl-C cancels the batch, stops the
cluster it started and removes any temporary file a stopped worker left behind.
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import io
import json
import os
import platform
import shutil
import sys
import tempfile
import time
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .imagedata import InputError
from .io import IMAGE_FORMATS, PathLike, atomic_output, replace_folder

COMMANDS = ("inpaint", "denoise", "diffuse", "track", "surface", "restore")
FOLDER_OUTPUTS = ("track", "surface")  # one output folder per input, named by its stem
MASKED = ("inpaint", "track")  # commands that take a mask per input (track: --init)
MAY_MASK = ("restore",)  # commands that take a mask per input if given (restore: else detects)
TILED = ("diffuse", "denoise")
MANIFEST = "clpde-manifest.json"
MANIFEST_EVERY_S = 1.0


# ---- results ------------------------------------------------------------------------------
@dataclass
class TaskResult:
    """One input's outcome: status 'done', 'skipped' (complete from an earlier run) or
    'failed' (error says why); seconds is the worker's time on it."""

    input: str
    output: str
    status: str
    error: str | None = None
    seconds: float = 0.0
    worker: str | None = None


@dataclass
class BatchResult:
    """The outcome of a batch: one TaskResult per input, in the order of the inputs."""

    results: list[TaskResult]
    seconds: float = 0.0
    cluster_seconds: float = 0.0  # time to start (or join) the cluster
    workers: int = 0
    threads: int | None = None  # PoCL threads per worker, when clpde started the cluster

    def _with(self, status):
        return [r for r in self.results if r.status == status]

    @property
    def done(self) -> list[TaskResult]:
        return self._with("done")

    @property
    def skipped(self) -> list[TaskResult]:
        return self._with("skipped")

    @property
    def failed(self) -> list[TaskResult]:
        return self._with("failed")

    @property
    def ok(self) -> bool:
        return not self.failed

    def __iter__(self):
        return iter(self.results)

    def __len__(self) -> int:
        return len(self.results)


# ---- the tasks, as they run on a worker -------------------------------------------------------
@functools.lru_cache(maxsize=1)
def _parser():
    from .cli import build_parser

    return build_parser()


def _parse(command: str, argv: list[str]):
    """The command's own parser on argv; its usage errors as an InputError."""
    err = io.StringIO()
    try:
        with contextlib.redirect_stderr(err):
            return _parser().parse_args([command, *argv])
    except SystemExit:
        lines = [ln for ln in err.getvalue().splitlines() if ln.strip()]
        detail = lines[-1].split("error: ", 1)[-1] if lines else "invalid options"
        raise InputError(f"clpde {command}: {detail}") from None


def _command_argv(spec: dict, output: str) -> list[str]:
    """The single-file command line that this task runs, writing to `output`."""
    command, source, mask, options = spec["command"], spec["input"], spec["mask"], spec["argv"]
    if command == "inpaint":
        return [source, mask, "-o", output, *options]
    if command == "track":
        return [source, "--init", mask, "-o", output, *options]
    if command == "surface":
        return [spec["flow"], source, "-o", output, *options]
    if command == "restore":
        return [source, "-o", output, *(["--mask", mask] if mask else []), *options]
    return [source, output, *options]


def _message(exc: BaseException) -> str:
    from .cli import _message as cli_message

    return cli_message(exc)


def run_task(spec: dict) -> dict:
    """Run one input's command on this process (a worker); a record of what happened.

    Errors are caught and returned, so a bad input is reported instead of retried; only a
    dying worker makes the scheduler run the task again, elsewhere.
    """
    start = time.perf_counter()
    record = {"worker": f"{platform.node()}:{os.getpid()}"}
    try:
        output = spec["output"]
        if spec["mask_error"]:
            raise InputError(spec["mask_error"])
        # The command's messages and progress bars are the client's business, not the
        # worker's terminal: capture them (tqdm then sees no terminal and draws nothing).
        with contextlib.redirect_stderr(io.StringIO()), contextlib.redirect_stdout(io.StringIO()):
            if spec["command"] in FOLDER_OUTPUTS:
                _run_into_folder(spec, output)
            else:
                _run_to_file(spec, output)
        record.update(status="done", output_sha256=_hash_path(output))
    except Exception as exc:  # noqa: BLE001  (any failure is this input's, reported by name)
        record.update(status="failed", error=_message(exc))
    record["seconds"] = time.perf_counter() - start
    return record


def _run_to_file(spec: dict, output: str) -> None:
    args = _parse(spec["command"], _command_argv(spec, output))
    if spec["command"] in TILED:
        from .tiled import may_exceed_device, run_tiled_command

        # The header is enough to rule tiling out; only then is the image read twice.
        if (spec["tile"] or may_exceed_device(args.input, args.device)) and \
                run_tiled_command(args, force=spec["tile"]):
            return
    status = args.run(args)
    if status:
        raise InputError(f"clpde {spec['command']} exited with status {status}")


def _run_into_folder(spec: dict, output: str) -> None:
    """Commands that write a folder: into a staging folder beside it, then renamed in, so
    that the output folder is either complete or absent."""
    final = Path(output)
    staging = Path(tempfile.mkdtemp(dir=final.parent, prefix=f".{final.name}.", suffix=".part"))
    try:
        args = _parse(spec["command"], _command_argv(spec, str(staging)))
        status = args.run(args)
        if status:
            raise InputError(f"clpde {spec['command']} exited with status {status}")
        replace_folder(staging, final)  # a rerun with other options: the old result goes only now
    except BaseException:
        shutil.rmtree(staging, ignore_errors=True)
        raise


def dask_setup(worker) -> None:
    """Worker preload (``preload=["clpde.batch"]``, ``dask worker --preload clpde.batch``).

    Ctrl-C in a terminal reaches every process of the group, but only the client should
    act on it: it cancels the batch and stops the workers it started, whose temporary
    files it then removes. And the worker's malloc is set for image-sized arrays
    (_malloc_for_arrays)."""
    import signal

    with contextlib.suppress(ValueError):  # not the main thread: nothing to do
        signal.signal(signal.SIGINT, signal.SIG_IGN)
    _malloc_for_arrays()


def _malloc_for_arrays() -> None:
    """Serve arrays of up to 32 MiB from glibc's heap, and keep up to 64 MiB of it free.

    Dask's nanny starts workers with MALLOC_TRIM_THRESHOLD_=65536, which also turns off
    glibc's adaptive mmap threshold: every numpy temporary over 128 kB is then mmapped,
    page-faulted in and unmapped again, 10 000 extra page faults and 25-35 ms of system time
    per 512x512 inpainting (docs/batch.md). These two settings bring it back to 1-2 ms,
    whatever the worker's environment (a `dask worker` started by hand too). Not glibc:
    nothing to do."""
    import ctypes

    try:
        libc = ctypes.CDLL("libc.so.6")
    except OSError:
        return
    m_trim_threshold, m_mmap_threshold = -1, -3  # glibc's malloc.h
    libc.mallopt(m_mmap_threshold, 32 << 20)
    libc.mallopt(m_trim_threshold, 64 << 20)


# ---- hashes and the manifest ------------------------------------------------------------------
def _hash_path(path) -> str | None:
    """sha256 of a file, or of a folder's files (names and contents, sorted); None if absent."""
    path = Path(path)
    if path.is_file():
        files = [path]
    elif path.is_dir():
        files = sorted(p for p in path.rglob("*") if p.is_file())
    else:
        return None
    digest = hashlib.sha256()
    for p in files:
        if path.is_dir():
            digest.update(p.relative_to(path).as_posix().encode() + b"\0")
        with open(p, "rb") as f:
            for block in iter(lambda: f.read(1 << 20), b""):
                digest.update(block)
    return digest.hexdigest()


def _read_manifest(outdir: Path) -> dict:
    path = outdir / MANIFEST
    if not path.is_file():
        return {}
    try:
        data = json.loads(path.read_text())
        return dict(data.get("outputs", {}))
    except (OSError, ValueError, AttributeError):
        return {}  # unreadable: every output is redone, which is safe


def _write_manifest(outdir: Path, records: dict) -> None:
    from . import __version__

    data = {"clpde": __version__, "outputs": dict(sorted(records.items()))}
    with atomic_output(outdir / MANIFEST) as tmp:
        tmp.write_text(json.dumps(data, indent=1) + "\n")


def _sweep_temporaries(outdir: Path, names) -> None:
    """Remove the temporary files and folders that killed workers left for these outputs."""
    for name in names:
        for stray in outdir.glob(f".{name}.*.part"):
            if stray.is_dir():
                shutil.rmtree(stray, ignore_errors=True)
            else:
                with contextlib.suppress(OSError):
                    stray.unlink()


# ---- planning the tasks on the client ---------------------------------------------------------
def _find_mask(masks_dir: Path, source: Path) -> Path | None:
    """The mask named like its image: the same file name, or the same stem as any image."""
    same = masks_dir / source.name
    if same.is_file():
        return same
    if (masks_dir / source.stem).is_dir():  # a film's folder of per-frame masks
        return masks_dir / source.stem
    for suffix in IMAGE_FORMATS:
        candidate = masks_dir / f"{source.stem}{suffix}"
        if candidate.is_file():
            return candidate
    return None


def options_argv(options: dict) -> list[str]:
    """Python keyword options as the command's flags: steps=50 -> --steps 50, no_gif=True ->
    --no-gif (False and None are left out)."""
    argv = []
    for key, value in options.items():
        flag = "--" + key.replace("_", "-")
        if value is None or value is False:
            continue
        if value is True:
            argv.append(flag)
        else:
            argv += [flag, str(value)]
    return argv


def _command_options(command, argv, options, flow):
    """(argv, flow): the command's flags; `flow` is surface's positional FLOW and diffuse's
    --flow."""
    argv = list(argv or []) + options_argv(options)
    if flow is not None and command != "surface":
        return ["--flow", str(flow), *argv], None
    return argv, flow


def _plan(command, inputs, outdir: Path, mask, masks, argv, flow, tile) -> list[dict]:
    if command not in COMMANDS:
        raise InputError(f"unknown batch command {command!r}; choose one of {', '.join(COMMANDS)}")
    if not inputs:
        raise InputError("give at least one input")
    if command in MASKED:
        if (mask is None) == (masks is None):
            what = "--init mask" if command == "track" else "mask"
            raise InputError(f"batch {command} needs one {what}: --mask FILE (one for all "
                             "inputs) or --masks DIR (one per input, named like it)")
    elif (mask is not None or masks is not None) and command not in MAY_MASK:
        raise InputError(f"--mask and --masks apply to inpaint, track and restore, not {command}")
    if tile and command not in TILED:
        raise InputError(f"--tile applies to diffuse and denoise, not {command}")
    if command == "surface" and not flow:
        raise InputError("batch surface needs --flow FLOW (heat, tv, denoise, ...)")
    if masks is not None and not Path(masks).is_dir():
        raise InputError(f"--masks {masks} is not a folder; give the folder of masks")
    if mask is not None and not (Path(mask).is_file()
                                 or (command in MAY_MASK and Path(mask).is_dir())):
        raise InputError(f"mask {mask} does not exist")
    if outdir.exists() and not outdir.is_dir():
        raise InputError(f"output {outdir} exists and is not a folder")
    specs, names = [], {}
    for item in inputs:
        source = Path(item)
        (name,) = _output_names(command, [source])
        if not name or name == MANIFEST:
            raise InputError(f"input {source} gives no usable output name")
        if name in names:
            raise InputError(f"inputs {names[name]} and {source} would both write {outdir / name}; "
                             "rename one or run them into separate folders")
        names[name] = source
        if outdir.resolve() == source.resolve().parent and command not in FOLDER_OUTPUTS:
            raise InputError(f"output folder {outdir} holds the input {source}; clpde never "
                             "overwrites its inputs, choose another folder")
        mask_path, mask_error = mask, None
        if masks is not None:
            found = _find_mask(Path(masks), source)
            mask_path = str(found) if found else None
            if found is None:
                mask_error = f"no mask for {source.name} in {masks} (expected {source.name})"
        specs.append({"command": command, "input": str(source), "output": str(outdir / name),
                      "name": name, "mask": None if mask_path is None else str(mask_path),
                      "mask_error": mask_error, "argv": list(argv), "flow": flow,
                      "tile": bool(tile)})
    # The options are checked by the command's own parser here, before any work is done.
    first = specs[0]
    _parse(command, _command_argv({**first, "mask": first["mask"] or "MASK"}, first["output"]))
    return specs


def _output_names(command, inputs) -> list[str]:
    return [Path(p).stem if command in FOLDER_OUTPUTS else Path(p).name for p in inputs]


def _fingerprint(spec: dict) -> dict:
    """What makes an output what it is: the inputs' contents and the command line."""
    digest = _hash_path(spec["input"])
    if digest is None and spec["command"] == "surface":  # a shape name (sphere, torus...)
        digest = hashlib.sha256(f"shape:{spec['input']}".encode()).hexdigest()
    return {"command": spec["command"], "argv": spec["argv"], "flow": spec["flow"],
            "tile": spec["tile"], "input_sha256": digest,
            "mask_sha256": None if spec["mask"] is None else _hash_path(spec["mask"])}


def _is_complete(record: dict | None, fingerprint: dict, output: str) -> bool:
    if not record or any(record.get(k) != v for k, v in fingerprint.items()):
        return False
    if fingerprint["input_sha256"] is None:
        return False
    return record.get("output_sha256") is not None and record["output_sha256"] == _hash_path(output)


# ---- the cluster ------------------------------------------------------------------------------
def cores() -> int:
    """CPU cores this process may use."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:
        return os.cpu_count() or 1


def plan_workers(workers=None, threads=None, tasks=None) -> tuple[int, int]:
    """(workers, PoCL threads per worker) with workers x threads = cores by default."""
    n = cores()
    for name, value in (("workers", workers), ("threads", threads)):
        if value is not None and (isinstance(value, bool) or int(value) != value or value < 1):
            raise InputError(f"--{name} must be a positive whole number, not {value!r}")
    if workers is None:
        workers = n if threads is None else max(1, n // int(threads))
        if tasks:
            workers = max(1, min(workers, int(tasks)))
    workers = int(workers)
    threads = int(threads) if threads is not None else max(1, n // workers)
    return workers, threads


def _gpu_indices(device) -> list[int]:
    """clpde's device indices of the GPUs, when the batch should use one worker per GPU."""
    if device is None:
        device = os.environ.get("CLPDE_DEVICE") or None
    if device is not None and str(device).strip().lower() != "gpu":
        return []  # a device was chosen: every worker uses it
    try:
        from .runtime import _build_problem, devices

        return [d.index for d in devices() if d.type == "gpu" and _build_problem(d.index) is None]
    except Exception:  # noqa: BLE001  (no OpenCL here: the workers use their default device)
        return []


# The local cluster's Dask settings, measured on 512x512 photo inpaintings (docs/batch.md):
# - spawn: a forked OpenCL context is unusable.
# - No MALLOC_TRIM_THRESHOLD_ (the nanny sets 65536 before spawning a worker): fixing any of
#   glibc's malloc thresholds turns off its adaptive mmap threshold, so every large numpy
#   temporary is mmapped, page-faulted in and unmapped again; that cost 25-35 ms of system
#   time per task (10 000 extra page faults), a fifth of a task's CPU.
# - No statistical profiler (it samples the task's stack every 10 ms for the dashboard,
#   which clpde's clusters do not run): about 40 ms of CPU per second of a running task on
#   the worker's event loop, 10-30 ms per task here.
# - The event loops' health tick every 500 ms, not 20 ms: an idle 2-worker cluster then
#   takes about 40 ms of CPU a second instead of 110 (client and scheduler 60 -> 20-30, each
#   worker 20-38 -> 5-15), CPU that the tasks of a busy machine would otherwise lose.
WORKER_CONFIG = {
    "distributed.worker.multiprocessing-method": "spawn",
    "distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None,
    "distributed.worker.profile.enabled": False,
    "distributed.admin.tick.interval": "500ms",
}


def start_cluster(workers=None, threads=None, *, device=None, tasks=None, gpus=None):
    """A local cluster for clpde: one worker per GPU, else workers x PoCL threads = cores.

    Returns (cluster, workers, threads per worker); close it with cluster.close().
    """
    import dask
    from distributed import LocalCluster, Nanny, Scheduler, SpecCluster

    if gpus is None and threads is None:
        gpus = _gpu_indices(device)
    common = {"nthreads": 1, "silence_logs": 50, "preload": ["clpde.batch"]}
    with dask.config.set(WORKER_CONFIG):
        if gpus:
            # One worker per GPU (or `workers` of them, spread round robin), each pinned
            # through clpde's device choice before it loads OpenCL.
            count = len(gpus) if workers is None else plan_workers(workers, 1)[0]
            specs = {f"gpu{k}": {"cls": Nanny, "options": {
                **common, "resources": {"GPU": 1}, "host": "127.0.0.1", "dashboard": False,
                "env": {"CLPDE_DEVICE": str(gpus[k % len(gpus)]), "POCL_MAX_PTHREAD_COUNT": "1"}}}
                for k in range(count)}
            cluster = SpecCluster(
                workers=specs, scheduler={"cls": Scheduler, "options": {
                    "dashboard": False, "dashboard_address": ":0", "host": "127.0.0.1"}},
                silence_logs=50)
            return cluster, count, None
        workers, threads = plan_workers(workers, threads, tasks)
        env = {"POCL_MAX_PTHREAD_COUNT": str(threads), "OMP_NUM_THREADS": "1"}
        cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                               # No dashboard; its HTTP server (always started) on any
                               # free port, so that clusters side by side do not clash.
                               dashboard_address=":0", scheduler_kwargs={"dashboard": False},
                               silence_logs=50, env=env,
                               preload=["clpde.batch"])
        return cluster, workers, threads


@contextlib.contextmanager
def connect(workers=None, scheduler=None, client=None, threads=None, *, device=None, tasks=None):
    """A distributed.Client: the given one, one joined to `scheduler`, or one on a local
    cluster started here (and closed on leaving). Yields (client, info dict)."""
    from distributed import Client

    given = [x is not None for x in (scheduler, client)]
    if sum(given) > 1 or (any(given) and (workers is not None or threads is not None)):
        raise InputError("give one of --workers/--threads (a local cluster), --scheduler "
                         "ADDRESS (an existing cluster) or client")
    start = time.perf_counter()
    info = {"workers": 0, "threads": None}
    if client is not None:
        info["workers"] = len(client.scheduler_info()["workers"])
        info["seconds"] = 0.0
        yield client, info
        return
    if scheduler is not None:
        try:
            client = Client(scheduler, timeout="20s", set_as_default=False)
        except OSError as exc:
            raise InputError(f"cannot reach the Dask scheduler at {scheduler}: {exc}; start "
                             "one with `dask scheduler` (see docs/batch.md)") from None
        info["workers"] = len(client.scheduler_info()["workers"])
        info["seconds"] = time.perf_counter() - start
        try:
            yield client, info
        finally:
            client.close()
        return
    cluster, n, per_worker = start_cluster(workers, threads, device=device, tasks=tasks)
    try:
        client = Client(cluster, set_as_default=False)
        try:
            client.wait_for_workers(n, timeout=120)
            info.update(workers=n, threads=per_worker, seconds=time.perf_counter() - start)
            yield client, info
        finally:
            client.close()
    finally:
        cluster.close()


def _wants_gpu(client) -> bool:
    workers = client.scheduler_info().get("workers", {}).values()
    return any("GPU" in (w.get("resources") or {}) for w in workers)


# ---- the batch --------------------------------------------------------------------------------
class _Progress:
    """One bar over the batch: done, running, failed (and skipped), redrawn on each event."""

    def __init__(self, total: int, skipped: int, enabled):
        from ._progress import progress_bar

        self.bar = progress_bar(enabled, total, "clpde batch", initial=skipped, unit="file",
                                dynamic_ncols=True)
        self.failed = 0
        self.skipped = skipped

    def update(self, running: int, failed_now: bool) -> None:
        self.failed += failed_now
        self.bar.update(1)
        self.bar.set_postfix_str(f"running {running}, failed {self.failed}"
                                 + (f", skipped {self.skipped}" if self.skipped else ""),
                                 refresh=True)

    def note(self, line: str) -> None:
        self.bar.write(line, file=sys.stderr)

    def close(self) -> None:
        self.bar.close()


class BatchFutures:
    """A batch submitted to a cluster: its futures, and results() to wait for them, record
    them in the manifest and get the BatchResult."""

    def __init__(self, client, specs, futures, prepared, manifest, outdir, start):
        self.client, self.specs, self.futures = client, specs, futures
        self._prepared, self._manifest, self._outdir = prepared, manifest, outdir
        self._start = start

    def results(self, progress=None) -> BatchResult:
        from distributed import as_completed

        results = dict(self._prepared)
        pending = {f.key: (i, f) for i, f in self.futures}
        bar = _Progress(len(self.specs), len(results), progress)
        saved_at, unsaved = float("-inf"), 0  # the first output is recorded at once
        workers = self.client.scheduler_info()["workers"].values()
        slots = sum(w.get("nthreads", 1) for w in workers)  # tasks that can run at once
        try:
            for future in as_completed([f for _, f in self.futures], loop=self.client.loop):
                index, _ = pending.pop(future.key)
                spec = self.specs[index]
                try:
                    record = future.result()
                except Exception as exc:  # noqa: BLE001  (e.g. KilledWorker too often)
                    record = {"status": "failed", "error": _message(exc), "seconds": 0.0}
                result = TaskResult(spec["input"], spec["output"], record["status"],
                                    record.get("error"), record.get("seconds", 0.0),
                                    record.get("worker"))
                results[index] = result
                if result.status == "done":
                    self._manifest[spec["name"]] = {
                        **spec["fingerprint"], "input": spec["input"], "mask": spec["mask"],
                        "output_sha256": record["output_sha256"],
                        "seconds": round(result.seconds, 4)}
                    unsaved += 1
                    # Rewriting the whole manifest per output would make a large batch
                    # quadratic: at most once a second, and at the end or on an interrupt.
                    if time.monotonic() - saved_at >= MANIFEST_EVERY_S:
                        _write_manifest(self._outdir, self._manifest)
                        saved_at, unsaved = time.monotonic(), 0
                else:
                    bar.note(f"clpde batch: {spec['input']} failed: {result.error}")
                bar.update(min(len(pending), slots), result.status == "failed")
        except BaseException:
            self.client.cancel([f for _, f in self.futures], force=True)
            raise
        finally:
            if unsaved:
                _write_manifest(self._outdir, self._manifest)
            bar.close()
        # A worker killed while writing leaves its temporary file; its task ran again elsewhere.
        _sweep_temporaries(self._outdir, [s["name"] for s in self.specs])
        ordered = [results[i] for i in range(len(self.specs))]
        return BatchResult(ordered, seconds=time.perf_counter() - self._start)



def submit(command, inputs, output_dir, *, client, mask=None, masks=None, flow=None,
           tile=False, force=False, argv=None, **options) -> BatchFutures:
    """Submit a batch to `client`'s cluster without waiting: a BatchFutures (its .futures,
    and .results() to wait). The arguments are those of batch()."""
    start = time.perf_counter()
    outdir = Path(output_dir)
    argv, flow = _command_options(command, argv, options, flow)
    specs = _plan(command, list(inputs), outdir, mask, masks, argv, flow, tile)
    outdir.mkdir(parents=True, exist_ok=True)
    _sweep_temporaries(outdir, [s["name"] for s in specs])
    manifest = _read_manifest(outdir)
    prepared, futures = {}, []
    resources = {"GPU": 1} if _wants_gpu(client) else None
    for index, spec in enumerate(specs):
        spec["fingerprint"] = _fingerprint(spec)
        if spec["fingerprint"]["input_sha256"] is None and not spec["mask_error"]:
            spec["mask_error"] = f"input {spec['input']} does not exist"
        if not force and _is_complete(manifest.get(spec["name"]), spec["fingerprint"],
                                      spec["output"]):
            prepared[index] = TaskResult(spec["input"], spec["output"], "skipped")
            continue
        task = {k: v for k, v in spec.items() if k != "fingerprint"}
        key = f"clpde-{command}-{spec['name']}-{hashlib.sha1(os.urandom(8)).hexdigest()[:8]}"
        futures.append((index, client.submit(run_task, task, key=key, pure=False,
                                             resources=resources)))
    return BatchFutures(client, specs, futures, prepared, manifest, outdir, start)


def batch(command: str, inputs: Iterable[PathLike], output_dir: PathLike, *,
          mask: PathLike | None = None, masks: PathLike | None = None,
          workers: int | None = None, threads: int | None = None, scheduler: str | None = None,
          client: Any = None, flow: str | None = None, tile: bool = False, force: bool = False,
          futures: bool = False, progress: bool | None = None, argv: list[str] | None = None,
          **options: Any) -> BatchResult | BatchFutures:
    """Run `command` ('inpaint', 'denoise', 'diffuse', 'track' or 'surface') on every input,
    over Dask workers, writing one output per input into the folder `output_dir`.

    Options are those of the single-file command, as keywords (``steps=50, flow="tv"``) or
    as its command-line flags (``argv=["--steps", "50"]``). inpaint takes ``mask`` (one mask
    for every input) or ``masks`` (a folder with a mask named like each input); track takes
    its first-frame mask the same way; surface needs ``flow``. diffuse and denoise run tiled
    (bitwise equal to an untiled run) with ``tile=True``, or by themselves when an image is
    larger than the device's largest allocation.

    The cluster: ``workers``/``threads`` for a local one (default: workers x PoCL threads =
    cores, or one worker per GPU), ``scheduler="tcp://host:8786"`` to join one, or an open
    ``client``. A rerun skips outputs that the manifest shows complete (``force=True`` redoes
    them). Returns a BatchResult; with ``futures=True`` (which needs ``client``) a
    BatchFutures at once, whose .results() waits.
    """
    if futures:
        if client is None:
            raise InputError("futures=True needs an open distributed.Client as client=; "
                             "without one, batch() waits and returns the results")
        return submit(command, inputs, output_dir, client=client, mask=mask, masks=masks,
                      flow=flow, tile=tile, force=force, argv=argv, **options)
    inputs = list(inputs)
    # Bad options fail here, before a cluster is started.
    _plan(command, inputs, Path(output_dir), mask, masks,
          *_command_options(command, argv, options, flow), tile)
    device = options.get("device")
    if argv and "--device" in argv[:-1]:
        device = argv[argv.index("--device") + 1]
    try:
        with connect(workers, scheduler, client, threads, device=device,
                     tasks=len(inputs)) as (live, info):
            run = submit(command, inputs, output_dir, client=live, mask=mask, masks=masks,
                         flow=flow, tile=tile, force=force, argv=argv, **options)
            result = run.results(progress)
    except BaseException:
        # Ctrl-C or a lost scheduler: the cluster started here is gone by now, so the
        # temporary files of the tasks it was running can go too; complete outputs stay.
        if Path(output_dir).is_dir():
            _sweep_temporaries(Path(output_dir), _output_names(command, inputs))
        raise
    result.cluster_seconds = info.get("seconds", 0.0)
    result.workers, result.threads = info["workers"], info["threads"]
    return result


def result_table(result: BatchResult) -> str:
    """One line per failure and a summary line, as the command line prints them."""
    lines = [f"  {r.input}: {r.error}" for r in result.failed]
    summary = (f"clpde batch: {len(result.done)} done, {len(result.skipped)} skipped, "
               f"{len(result.failed)} failed in {result.seconds:.1f} s on {result.workers} "
               f"worker(s)")
    if result.failed:
        return "\n".join([summary, "failed:", *lines])
    return summary


__all__ = ["BatchFutures", "BatchResult", "TaskResult", "batch", "connect", "plan_workers",
           "start_cluster", "submit"]
