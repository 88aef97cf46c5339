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
its input (and mask) and the options (clpde.scale.manifest); a rerun skips the outputs whose
record matches. A
worker that dies has its task run elsewhere by the scheduler. A failing input is reported
by name in the result and does not stop the others. Ctrl-C cancels the batch, stops the
cluster it started and removes any temporary file a stopped worker left behind. The tasks
are planned and checked on the client before anything runs (clpde.scale.plan).
"""

from __future__ import annotations

import contextlib
import hashlib
import inspect
import io
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

from .._progress import progress_bar
from ..errors import InputError, error_message
from ..io.images import (
    PathLike,
    replace_folder,
)
from .cluster import connect, wants_gpu
from .file_tasks import TASKS, TRANSPORT_OPTIONS, inpaint_options
from .manifest import (
    fingerprint,
    hash_path,
    is_complete,
    read_manifest,
    sweep_temporaries,
    write_manifest,
)
from .plan import (
    FOLDER_OUTPUTS,
    MASKED,
    TILED,
    expand_inputs,
    plan_tasks,
)

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
def _options(command: str, options: dict, flow) -> dict:
    """The task's keyword options: `flow` is surface's flow and diffuse's; unknown names are
    an InputError (before any work), with the task's own names."""
    options = dict(options)
    if flow is not None:
        options["flow"] = flow
    task = TASKS[command]
    accepted = [
        n
        for n, p in inspect.signature(task).parameters.items()
        if p.kind is p.KEYWORD_ONLY and n not in ("mask", "progress")
    ]
    unknown = sorted(set(options) - set(accepted))
    if unknown:
        raise InputError(
            f"batch {command}: unknown option(s) {', '.join(unknown)}; its options "
            f"are {', '.join(accepted)}"
        )
    if command == "inpaint":  # the method's options, checked as the task builds them
        inpaint_options(
            options.get("method"),
            gif=bool(options.get("gif")),
            levels=options.get("levels"),
            **{name: options.get(name) for name in TRANSPORT_OPTIONS},
        )
    return options


def run_task(spec: dict) -> dict:
    """Run one input's task on this process (a worker); a record of what happened.

    Errors are caught and returned, so a bad input is reported instead of retried; only a
    dying worker makes the scheduler run the task again, elsewhere.
    """
    start = time.perf_counter()
    record = {"worker": f"{platform.node()}:{os.getpid()}"}
    try:
        output = spec["output"]
        if spec["mask_error"]:
            raise InputError(spec["mask_error"])
        # The task's messages and progress bars are the client's business, not the
        # worker's terminal: capture them (tqdm then sees no terminal and draws nothing).
        with contextlib.redirect_stderr(io.StringIO()), contextlib.redirect_stdout(io.StringIO()):
            if spec["command"] in FOLDER_OUTPUTS:
                _run_into_folder(spec, output)
            else:
                _run(spec, output)
        record.update(status="done", output_sha256=hash_path(output))
    except Exception as exc:  # noqa: BLE001  (any failure is this input's, reported by name)
        record.update(status="failed", error=error_message(exc))
    record["seconds"] = time.perf_counter() - start
    return record


def _run(spec: dict, output: str) -> None:
    options = dict(spec["options"])
    if spec["command"] in MASKED:
        options["mask"] = spec["mask"]
    if spec["command"] in TILED:
        options["tile"] = True if spec["tile"] else None  # None: when the device needs it
    TASKS[spec["command"]](spec["input"], output, progress=False, **options)


def _run_into_folder(spec: dict, output: str) -> None:
    """Commands that write a folder: into a staging folder beside it, then renamed in, so
    that the output folder is either complete or absent."""
    final = Path(output)
    staging = Path(tempfile.mkdtemp(dir=final.parent, prefix=f".{final.name}.", suffix=".part"))
    try:
        _run(spec, str(staging))
        replace_folder(staging, final)  # a rerun with other options: the old result goes only now
    except BaseException:
        shutil.rmtree(staging, ignore_errors=True)
        raise


# ---- the batch --------------------------------------------------------------------------------
class _Progress:
    """One bar over the batch: done, running, failed (and skipped), redrawn on each event."""

    def __init__(self, total: int, skipped: int, enabled):

        self.bar = progress_bar(
            enabled, total, "clpde batch", initial=skipped, unit="file", dynamic_ncols=True
        )
        self.failed = 0
        self.skipped = skipped

    def update(self, running: int, failed_now: bool) -> None:
        self.failed += failed_now
        self.bar.update(1)
        self.bar.set_postfix_str(
            f"running {running}, failed {self.failed}"
            + (f", skipped {self.skipped}" if self.skipped else ""),
            refresh=True,
        )

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
                    record = {"status": "failed", "error": error_message(exc), "seconds": 0.0}
                result = TaskResult(
                    spec["input"],
                    spec["output"],
                    record["status"],
                    record.get("error"),
                    record.get("seconds", 0.0),
                    record.get("worker"),
                )
                results[index] = result
                if result.status == "done":
                    self._manifest[spec["name"]] = {
                        **spec["fingerprint"],
                        "input": spec["input"],
                        "mask": spec["mask"],
                        "output_sha256": record["output_sha256"],
                        "seconds": round(result.seconds, 4),
                    }
                    unsaved += 1
                    # Rewriting the whole manifest per output would make a large batch
                    # quadratic: at most once a second, and at the end or on an interrupt.
                    if time.monotonic() - saved_at >= MANIFEST_EVERY_S:
                        write_manifest(self._outdir, self._manifest)
                        saved_at, unsaved = time.monotonic(), 0
                else:
                    bar.note(f"clpde batch: {spec['input']} failed: {result.error}")
                bar.update(min(len(pending), slots), result.status == "failed")
        except BaseException:
            self.client.cancel([f for _, f in self.futures], force=True)
            raise
        finally:
            if unsaved:
                write_manifest(self._outdir, self._manifest)
            bar.close()
        # A worker killed while writing leaves its temporary file; its task ran again elsewhere.
        sweep_temporaries(self._outdir, [s["name"] for s in self.specs])
        ordered = [results[i] for i in range(len(self.specs))]
        return BatchResult(ordered, seconds=time.perf_counter() - self._start)


@dataclass
class _Plan:
    """A batch's tasks checked against the manifest, before any cluster: the specs, the
    manifest read, the results of the outputs already complete and the tasks to run."""

    command: str
    outdir: Path
    specs: list
    manifest: dict
    skipped: dict
    pending: list


def _plan(command, inputs, outdir, mask, masks, flow, tile, force, options) -> _Plan:
    outdir = Path(outdir)
    specs = plan_tasks(
        command,
        expand_inputs(inputs),
        outdir,
        mask,
        masks,
        _options(command, options, flow) if command in TASKS else options,
        tile,
    )
    manifest = read_manifest(outdir)
    skipped, pending = {}, []
    for index, spec in enumerate(specs):
        spec["fingerprint"] = fingerprint(spec)
        if spec["fingerprint"]["input_sha256"] is None and not spec["mask_error"]:
            spec["mask_error"] = f"input {spec['input']} does not exist"
        if not force and is_complete(
            manifest.get(spec["name"]), spec["fingerprint"], spec["output"]
        ):
            skipped[index] = TaskResult(spec["input"], spec["output"], "skipped")
        else:
            pending.append(index)
    return _Plan(command, outdir, specs, manifest, skipped, pending)


def _submit(plan: _Plan, client, start: float) -> BatchFutures:
    plan.outdir.mkdir(parents=True, exist_ok=True)
    sweep_temporaries(plan.outdir, [s["name"] for s in plan.specs])
    resources = {"GPU": 1} if wants_gpu(client) else None
    futures = []
    for index in plan.pending:
        spec = plan.specs[index]
        task = {k: v for k, v in spec.items() if k != "fingerprint"}
        name = f"clpde-{plan.command}-{spec['name']}"
        key = f"{name}-{hashlib.sha1(os.urandom(8)).hexdigest()[:8]}"
        futures.append(
            (index, client.submit(run_task, task, key=key, pure=False, resources=resources))
        )
    return BatchFutures(
        client, plan.specs, futures, plan.skipped, plan.manifest, plan.outdir, start
    )


def submit(
    command,
    inputs,
    output_dir,
    *,
    client,
    mask=None,
    masks=None,
    flow=None,
    tile=False,
    force=False,
    **options,
) -> BatchFutures:
    """Submit a batch to `client`'s cluster without waiting: a BatchFutures (its .futures,
    and .results() to wait). The arguments are those of batch()."""
    start = time.perf_counter()
    plan = _plan(command, inputs, output_dir, mask, masks, flow, tile, force, options)
    return _submit(plan, client, start)


def batch(
    command: str,
    inputs: Iterable[PathLike],
    output_dir: PathLike,
    *,
    mask: PathLike | None = None,
    masks: PathLike | None = None,
    workers: int | None = None,
    threads: int | None = None,
    scheduler: str | None = None,
    client: Any = None,
    flow: str | None = None,
    tile: bool = False,
    force: bool = False,
    futures: bool = False,
    progress: bool | None = None,
    **options: Any,
) -> BatchResult | BatchFutures:
    """Run `command` ('inpaint', 'denoise', 'diffuse', 'track' or 'surface') on every input,
    over Dask workers, writing one output per input into the folder `output_dir`.

    A rerun skips outputs that the manifest (OUTDIR/clpde-manifest.json) shows complete. A
    failing input is reported by name in the result and does not stop the others.

    Parameters
    ----------
    command : {'inpaint', 'denoise', 'diffuse', 'track', 'surface'}
        The task of `clpde.scale.file_tasks.TASKS` to run on each input.
    inputs : iterable of path
        The input files (surface: meshes or shape names).
    output_dir : path
        The output folder, created if missing.
    mask : path, optional
        inpaint: one mask for every input; track: the first-frame mask.
    masks : path, optional
        A folder with a mask named like each input (instead of `mask`).
    workers : int, optional
        Local worker processes (default: workers x PoCL threads = cores, or one per GPU).
    threads : int, optional
        PoCL threads per local worker.
    scheduler : str, optional
        The address of a running cluster to join, e.g. "tcp://host:8786".
    client : distributed.Client, optional
        An open client to use instead.
    flow : str, optional
        surface: the flow (needed); diffuse: the flow.
    tile : bool, optional
        diffuse, denoise: run in tiles (bitwise equal to untiled); tiles are used by
        themselves when an image exceeds the device's largest allocation.
    force : bool, optional
        Redo outputs that the manifest shows complete.
    futures : bool, optional
        Return a BatchFutures at once (needs `client`), whose .results() waits.
    progress : bool, optional
        Draw a progress bar; by default on a terminal.
    **options
        The keywords of the command's task (``steps=50``, ``max_steps=2000``), the Python
        spelling of its flags.

    Returns
    -------
    BatchResult or BatchFutures
        One TaskResult per input, in order (done, skipped or failed, with the reason).

    Raises
    ------
    InputError
        For an unknown command or option, missing masks, or outputs that would collide;
        before any cluster is started.

    Examples
    --------
    >>> import clpde
    >>> clpde.batch("diffuse", [], "out")
    Traceback (most recent call last):
    ...
    clpde.errors.InputError: give at least one input
    """
    if futures:
        if client is None:
            raise InputError(
                "futures=True needs an open distributed.Client as client=; "
                "without one, batch() waits and returns the results"
            )
        return submit(
            command,
            inputs,
            output_dir,
            client=client,
            mask=mask,
            masks=masks,
            flow=flow,
            tile=tile,
            force=force,
            **options,
        )
    start = time.perf_counter()  # the time reported is the wall time of the whole call
    outdir = Path(output_dir)
    existed = outdir.exists()
    # Bad options fail here, and the manifest is read, before a cluster is started: a rerun
    # whose outputs are all complete starts none.
    plan = _plan(command, inputs, outdir, mask, masks, flow, tile, force, options)
    if not plan.pending:
        skipped = [plan.skipped[i] for i in range(len(plan.specs))]
        return BatchResult(skipped, seconds=time.perf_counter() - start)
    device = options.get("device")
    try:
        with connect(
            workers, scheduler, client, threads, device=device, tasks=len(plan.pending)
        ) as (live, info):
            result = _submit(plan, live, start).results(progress)
    except BaseException:
        # Ctrl-C or a lost scheduler: the cluster started here is gone by now, so the
        # temporary files of the tasks it was running can go too; complete outputs stay,
        # and a folder this call created and left empty goes.
        if outdir.is_dir():
            sweep_temporaries(outdir, [s["name"] for s in plan.specs])
            if not existed and not any(outdir.iterdir()):
                outdir.rmdir()
        raise
    result.cluster_seconds = info.get("seconds", 0.0)
    result.workers, result.threads = info["workers"], info["threads"]
    result.seconds = time.perf_counter() - start
    return result


def result_table(result: BatchResult, seconds: float | None = None) -> str:
    """One line per failure and a summary line, as the command line prints them; `seconds`
    (the command's whole time) in place of the batch call's, if given."""
    lines = [f"  {r.input}: {r.error}" for r in result.failed]
    seconds = result.seconds if seconds is None else seconds
    summary = (
        f"clpde batch: {len(result.done)} done, {len(result.skipped)} skipped, "
        f"{len(result.failed)} failed in {seconds:.1f} s"
        + (f" on {result.workers} worker(s)" if result.workers else " (no worker needed)")
    )
    if result.failed:
        return "\n".join([summary, "failed:", *lines])
    return summary


__all__ = ["BatchFutures", "BatchResult", "TaskResult", "batch", "submit"]
