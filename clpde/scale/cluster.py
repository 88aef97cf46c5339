"""The Dask cluster that clpde's batches and films run on: a local one sized to the cores (or
one worker per GPU), or a running one joined by address; and the workers' preload
(``preload=["clpde.scale.cluster"]``, ``dask worker --preload clpde.scale.cluster``)."""

from __future__ import annotations

import contextlib
import os
import time

from .._interrupt import children_stderr, held
from ..errors import InputError
from ..runtime import build_problem, devices


def dask_setup(worker) -> None:
    """Worker preload (``dask worker --preload clpde.scale.cluster``).

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
    page-faulted in and unmapped again, a cost in system time per task that these two
    settings remove (measured in docs/batch.md), whatever the worker's environment (a
    `dask worker` started by hand too). Not glibc: nothing to do."""
    import ctypes

    try:
        libc = ctypes.CDLL("libc.so.6")
    except OSError:
        return
    m_trim_threshold, m_mmap_threshold = -1, -3  # glibc's malloc.h
    libc.mallopt(m_mmap_threshold, 32 << 20)
    libc.mallopt(m_trim_threshold, 64 << 20)


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
        return [d.index for d in devices() if d.type == "gpu" and build_problem(d.index) is None]
    except Exception:  # noqa: BLE001  (no OpenCL here: the workers use their default device)
        return []


# The local cluster's Dask settings (each one's cost is measured in docs/batch.md):
# - spawn: a forked OpenCL context is unusable.
# - No MALLOC_TRIM_THRESHOLD_ (the nanny sets 65536 before spawning a worker): fixing any of
#   glibc's malloc thresholds turns off its adaptive mmap threshold, so every large numpy
#   temporary is mmapped, page-faulted in and unmapped again, in system time on every task.
# - No statistical profiler: it samples the running task's stack for the dashboard, which
#   clpde's clusters do not run, at a cost in CPU on the worker's event loop.
# - The event loops' health tick every 500 ms, not Dask's 20 ms: the idle ticks take CPU
#   that the tasks of a busy machine would otherwise lose.
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
    common = {"nthreads": 1, "silence_logs": 50, "preload": ["clpde.scale.cluster"]}
    with dask.config.set(WORKER_CONFIG):
        if gpus:
            # One worker per GPU (or `workers` of them, spread round robin), each pinned
            # through clpde's device choice before it loads OpenCL.
            count = len(gpus) if workers is None else plan_workers(workers, 1)[0]
            specs = {
                f"gpu{k}": {
                    "cls": Nanny,
                    "options": {
                        **common,
                        "resources": {"GPU": 1},
                        "host": "127.0.0.1",
                        "dashboard": False,
                        "env": {
                            "CLPDE_DEVICE": str(gpus[k % len(gpus)]),
                            "POCL_MAX_PTHREAD_COUNT": "1",
                        },
                    },
                }
                for k in range(count)
            }
            cluster = SpecCluster(
                workers=specs,
                scheduler={
                    "cls": Scheduler,
                    "options": {"dashboard": False, "dashboard_address": ":0", "host": "127.0.0.1"},
                },
                silence_logs=50,
            )
            return cluster, count, None
        workers, threads = plan_workers(workers, threads, tasks)
        env = {"POCL_MAX_PTHREAD_COUNT": str(threads), "OMP_NUM_THREADS": "1"}
        cluster = LocalCluster(
            n_workers=workers,
            threads_per_worker=1,
            processes=True,
            # No dashboard; its HTTP server (always started) on any
            # free port, so that clusters side by side do not clash.
            dashboard_address=":0",
            scheduler_kwargs={"dashboard": False},
            silence_logs=50,
            env=env,
            preload=["clpde.scale.cluster"],
        )
        return cluster, workers, threads


@contextlib.contextmanager
def connect(workers=None, scheduler=None, client=None, threads=None, *, device=None, tasks=None):
    """A distributed.Client: the given one, one joined to `scheduler`, or one on a local
    cluster started here (and closed on leaving). Yields (client, info dict)."""
    from distributed import Client

    given = [x is not None for x in (scheduler, client)]
    if sum(given) > 1 or (any(given) and (workers is not None or threads is not None)):
        raise InputError(
            "give one of --workers/--threads (a local cluster), --scheduler "
            "ADDRESS (an existing cluster) or client"
        )
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
            raise InputError(
                f"cannot reach the Dask scheduler at {scheduler}: {exc}; start "
                "one with `dask scheduler` (see docs/batch.md)"
            ) from None
        info["workers"] = len(client.scheduler_info()["workers"])
        info["seconds"] = time.perf_counter() - start
        try:
            yield client, info
        finally:
            client.close()
        return
    # Ctrl-C is held while the cluster starts and stops (clpde/_interrupt.py): a cluster
    # stopped half-started, or workers interrupted while they start, print pages of
    # tracebacks; it arrives once the cluster is up (or down) again.
    cluster = client = None
    try:
        with held() as state:
            try:
                with children_stderr(state):
                    cluster, n, per_worker = start_cluster(
                        workers, threads, device=device, tasks=tasks
                    )
            except Exception:
                if state.pressed.is_set():  # a worker that Ctrl-C stopped while it started
                    raise KeyboardInterrupt from None
                raise
            client = Client(cluster, set_as_default=False)
            if not state.pressed.is_set():
                client.wait_for_workers(n, timeout=120)
        # (held() raises a Ctrl-C that came meanwhile here, into the clean-up below)
    except BaseException:
        with held():
            _close(client, cluster)
        raise
    try:
        info.update(workers=n, threads=per_worker, seconds=time.perf_counter() - start)
        yield client, info
    finally:
        with held():
            _close(client, cluster)


def _close(client, cluster) -> None:
    try:
        if client is not None:
            client.close()
    finally:
        if cluster is not None:
            cluster.close()


def wants_gpu(client) -> bool:
    workers = client.scheduler_info().get("workers", {}).values()
    return any("GPU" in (w.get("resources") or {}) for w in workers)
