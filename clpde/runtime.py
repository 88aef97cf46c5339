"""OpenCL runtime: device choice, program building and caching, launch geometry.

Everything that talks to pyopencl's platform layer lives here, so the flows only ask for a
kernel by its file under kernels/ and its name (the Runtime's ``kernel`` method) and
launch it.
Runtimes and kernels pickle by their device's name and their lookup; fields.py registers
how, beside the device buffers and arrays, which pickle by value.
"""

from __future__ import annotations

import os
import tempfile
import threading
import time
import warnings
from importlib import resources
from pathlib import Path

import numpy as np

from .errors import ClpdeError, DeviceMemoryError, KernelBuildError, NoDeviceError

ITEM_GROUP = 64  # the work-group of Runtime.items


MEMORY_WAY_OUT = (
    "use a smaller input (crop or downsample it) or process it in tiles, or "
    "choose a device with more memory (clpde devices)"
)


def _mib(nbytes: float) -> str:
    return f"{nbytes / 2**30:.2f} GiB" if nbytes >= 2**30 else f"{nbytes / 2**20:.1f} MiB"


INSTALL_HINT = (
    'install the CPU runtime with  pip install "clpde[pocl]"  or your GPU vendor\'s OpenCL driver'
)


# The kernels are the package clpde.kernels: in a wheel, kernels/ installed there; in a
# source checkout, the same folder through the link clpde/kernels. The compiler reads them
# (and their #includes) from a folder, so the package must be one on disk, not in a zip.
KERNEL_DIR = Path(str(resources.files("clpde.kernels")))


def _ensure_pocl_cache_dir() -> None:
    """PoCL silently reports zero devices when it cannot write its kernel cache."""
    current = os.environ.get("POCL_CACHE_DIR")
    candidates = [current] if current else []
    candidates += [
        os.path.join(os.path.expanduser("~"), ".cache", "clpde", "pocl"),
        os.path.join(
            tempfile.gettempdir(), f"clpde-pocl-{os.getuid() if hasattr(os, 'getuid') else 0}"
        ),
    ]
    for path in candidates:
        try:
            os.makedirs(path, exist_ok=True)
            with tempfile.NamedTemporaryFile(dir=path):
                pass
        except OSError:
            continue
        if current and path != current:
            warnings.warn(
                f"POCL_CACHE_DIR={current!r} is not writable; PoCL would show no devices. "
                f"Using {path!r} instead.",
                stacklevel=3,
            )
        os.environ["POCL_CACHE_DIR"] = path
        return
    os.environ["POCL_CACHE_DIR"] = tempfile.mkdtemp(prefix="clpde-pocl-")


_ensure_pocl_cache_dir()

import pyopencl as cl  # noqa: E402  (imported here: PoCL reads POCL_CACHE_DIR when the ICD loads)

from ._device import (  # noqa: E402
    QUEUE_PROPERTIES,
    DeviceInfo,
    Kernel,
    build_failure,
    fetch_kernel,
    group_problem,
    has_fp64,
    not_pocl,
    pyopencl_ctx,
    quietly,
    type_name,
)
from ._device import enqueue_bare as enqueue_bare  # noqa: E402  (transport.py's bare launches)

_found: list[tuple[cl.Platform, cl.Device]] = []  # the devices, listed once per process


def _all_devices() -> list[tuple[cl.Platform, cl.Device]]:
    """Every (platform, device), in the order the indices count; asked of OpenCL once
    (every get_runtime() call needs the list, and the ICD loader takes milliseconds)."""
    global _used_opencl
    check_not_forked()
    _used_opencl = True
    if _found:
        return _found
    try:
        platforms = cl.get_platforms()
    except cl.Error as exc:  # PLATFORM_NOT_FOUND_KHR when no ICD is installed
        raise NoDeviceError(f"no OpenCL platform found ({exc}); {INSTALL_HINT}") from None
    found = []
    for platform in platforms:
        try:
            found += [(platform, d) for d in platform.get_devices()]
        except cl.Error:
            continue  # a platform with no usable device
    if not found:
        raise NoDeviceError(
            f"OpenCL platforms exist but show no device (for PoCL, check that "
            f"POCL_CACHE_DIR={os.environ.get('POCL_CACHE_DIR')!r} is writable); {INSTALL_HINT}"
        )
    _found[:] = found
    return _found


def _resolve(spec) -> int:
    """Index into _all_devices() of the device a spec names."""
    found = _all_devices()
    names = [f"{d.name} ({p.name})" for p, d in found]
    if isinstance(spec, (int, np.integer)) or (isinstance(spec, str) and spec.strip().isdigit()):
        index = int(spec)
        if not 0 <= index < len(found):
            raise ClpdeError(
                f"device index {index} is out of range; there are {len(found)} devices: "
                + "; ".join(f"[{i}] {n}" for i, n in enumerate(names))
            )
        return index
    if not isinstance(spec, str) or not spec.strip():
        raise ClpdeError(f"device must be 'cpu', 'gpu', an index or a name substring, not {spec!r}")
    wanted = spec.strip().lower()
    if wanted in ("cpu", "gpu", "accelerator"):
        of_type = sorted(
            (i for i, (_, d) in enumerate(found) if type_name(d) == wanted),
            key=lambda i: not_pocl(found[i][0]),
        )
        # The first of that type whose compiler works; else the first, whose error then says
        # why. One of its type is not probed: nothing to skip to (a failing build asks).
        if len(of_type) == 1:
            return of_type[0]
        for i in of_type:
            if build_problem(i) is None:
                return i
        if of_type:
            return of_type[0]
        raise ClpdeError(
            f"no {wanted.upper()} OpenCL device found; available: {'; '.join(names)}"
            + (f". {INSTALL_HINT}" if wanted == "cpu" else "")
        )
    for i, (p, d) in enumerate(found):
        if wanted in d.name.lower() or wanted in p.name.lower():
            return i
    raise ClpdeError(
        f"no OpenCL device matches {spec!r}; available: "
        + "; ".join(f"[{i}] {n}" for i, n in enumerate(names))
        + ". Run `clpde devices` to list them."
    )


# Guards the module's caches (devices probed, runtimes made): two threads making their first
# call at once must share one context, or buffers of one would meet kernels of the other.
_lock = threading.RLock()

_build_problems: dict[int, str | None] = {}


def build_problem(index: int) -> str | None:
    """Why device ``index`` cannot compile OpenCL C, or None when it can.

    An OpenCL platform can list a device whose compiler does not work: PoCL 3.0's LLVM 14
    (the one pip installs) does not know CPUs newer than itself, such as AMD's Zen 5, and
    fails every build with "unknown target CPU 'generic'". Probing once per device lets the
    default choice skip such a device when another one works.
    """
    with _lock:
        if index not in _build_problems:
            _build_problems[index] = _probe(index)
        return _build_problems[index]


PROBE_SOURCE = KERNEL_DIR / "common/probe.cl"  # fixed here: a test may point KERNEL_DIR elsewhere


def _probe(index: int) -> str | None:
    """Build a tiny program on device ``index``: None, or why it fails."""
    platform, device = _all_devices()[index]
    return build_failure(platform, device, PROBE_SOURCE.read_text())


def _default_index() -> int:
    check_not_forked()  # a forked child's error is not the setting's fault: raise it bare
    env = os.environ.get("CLPDE_DEVICE")
    if env:
        try:
            return _resolve(env)
        except ClpdeError as exc:
            raise ClpdeError(f"CLPDE_DEVICE={env!r}: {exc}") from None
    # pyopencl's own setting, for users who already steer every pyopencl program with it
    ctx = os.environ.get("PYOPENCL_CTX")
    if ctx and ctx.strip():
        try:
            return pyopencl_ctx(ctx, _all_devices())
        except ClpdeError as exc:
            raise ClpdeError(
                f"PYOPENCL_CTX={ctx!r}: {exc}; set it to 'platform:device' indices from "
                "`clpde devices`, or unset it"
            ) from None
    found = _all_devices()
    order = [i for i, (_, d) in enumerate(found) if type_name(d) == "gpu"]
    # Among CPU runtimes PoCL comes first, whatever order the ICD loader lists them in: the
    # kernels are shaped for its vectoriser, and Intel's oneAPI runtime, the other one
    # measured, was slower on the tracking and surface defaults (benchmarks/runtimes.py,
    # docs/portability.md)
    order += sorted(
        (i for i in range(len(found)) if i not in order), key=lambda i: not_pocl(found[i][0])
    )
    if len(order) == 1:
        # nothing to skip to: the probe (0.6 s of a cold start with PoCL) would only word the
        # error, which a failing build asks it for then (Runtime._build)
        return order[0]
    problems = []
    for i in order:
        problem = build_problem(i)
        if problem is None:
            return i
        problems.append(problem)
    raise NoDeviceError("no OpenCL device can compile kernels: " + "; ".join(problems))


_chosen_spec = None
_runtimes: dict[int, Runtime] = {}


def use_device(spec: str | int | Runtime | None) -> Runtime:
    """Make ``spec`` the default device of every later call in this process.

    Parameters
    ----------
    spec : str, int, Runtime or None
        'cpu', 'gpu', an index from :func:`devices`, or a substring of a device's name.
        None returns to the automatic choice (CLPDE_DEVICE, else PYOPENCL_CTX, else a GPU,
        else a CPU).

    Returns
    -------
    Runtime
        The device's runtime (its context, queue and kernel cache).

    Examples
    --------
    >>> import clpde
    >>> clpde.use_device("cpu").type
    'cpu'
    >>> clpde.diffuse(np.zeros((8, 8), np.float32), steps=1).dtype
    dtype('float32')
    >>> _ = clpde.use_device(None)   # back to the automatic choice
    """
    global _chosen_spec
    runtime = get_runtime(spec)
    _chosen_spec = spec
    return runtime


def get_runtime(device: str | int | Runtime | None = None) -> Runtime:
    """The runtime of one device, built once per process and shared by threads.

    Parameters
    ----------
    device : str, int, Runtime or None
        As for :func:`use_device`; None means use_device's choice, else CLPDE_DEVICE, else
        PYOPENCL_CTX ("platform:device"), else a GPU, else a CPU (PoCL's before another
        runtime's), skipping devices whose compiler cannot build a kernel.

    Returns
    -------
    Runtime

    Examples
    --------
    >>> rt = get_runtime("cpu")
    >>> rt is get_runtime("cpu")
    True
    >>> rt.type
    'cpu'
    """
    if isinstance(device, Runtime):
        return device
    if device is None:
        device = _chosen_spec
    with _lock:
        # a named device is not probed: its first failing build asks (Runtime._build)
        index = _default_index() if device is None else _resolve(device)
        runtime = _runtimes.get(index)
        if runtime is None:
            platform, dev = _all_devices()[index]
            runtime = _runtimes[index] = Runtime(index, platform, dev)
        return runtime


def runtime_named(platform_name: str, device_name: str) -> Runtime:
    """The runtime of the device so named, or the default one where this machine has no such
    device: how a Runtime pickled by its device's name is received (see clpde.fields)."""
    with _lock:
        for i, (p, d) in enumerate(_all_devices()):
            if p.name.strip() == platform_name and d.name.strip() == device_name:
                return get_runtime(i)
    return get_runtime()


def runtime_of_context(ctx: cl.Context) -> Runtime | None:
    """The runtime made in this process whose context is `ctx`, or None."""
    check_not_forked()
    with _lock:
        return next((r for r in _runtimes.values() if r.ctx == ctx), None)


def devices() -> list[DeviceInfo]:
    """Every OpenCL device on every platform, in the order the indices count.

    Returns
    -------
    list of DeviceInfo
        One record per device; ``in_use`` marks the default device (the one
        :func:`get_runtime` returns with no argument).

    Examples
    --------
    >>> found = devices()
    >>> any(d.type == "cpu" for d in found)
    True
    >>> sum(d.in_use for d in found)
    1
    """
    try:
        current = get_runtime().index
    except ClpdeError:
        current = -1
    return [
        DeviceInfo(
            index=i,
            platform=p.name.strip(),
            name=d.name.strip(),
            type=type_name(d),
            compute_units=d.max_compute_units,
            global_mem_bytes=d.global_mem_size,
            max_alloc_bytes=d.max_mem_alloc_size,
            fp64=has_fp64(d),
            in_use=(i == current),
            local_mem_bytes=d.local_mem_size,
            max_group=d.max_work_group_size,
            constant_mem_bytes=d.max_constant_buffer_size,
            images=bool(d.image_support),
        )
        for i, (p, d) in enumerate(_all_devices())
    ]


class Runtime:
    """A device with its context, queue, built programs and launch geometry."""

    def __init__(self, index: int, platform: cl.Platform, device: cl.Device):
        self.index = index
        self.platform = platform
        self.device = device
        self.type = type_name(device)
        self.is_cpu = self.type == "cpu"
        self.fp64 = has_fp64(device)
        self.global_mem = device.global_mem_size
        self.max_alloc = device.max_mem_alloc_size
        self.ctx = cl.Context([device])
        self.queue = cl.CommandQueue(self.ctx, properties=QUEUE_PROPERTIES)
        self._programs: dict[tuple, cl.Program] = {}
        self.build_seconds = 0.0  # spent building programs so far (callers leave it out)
        self._kernels: dict[tuple, Kernel] = {}
        # Held while a kernel's arguments are set and it is enqueued (see Kernel), and
        # around pyopencl's own array kernels (Array.fill, arithmetic), which share kernel
        # objects per context; re-entrant so that the caches may be filled under it.
        self.lock = threading.RLock()

    def _forked(self) -> None:
        """In a forked child: every later launch raises (see _after_fork_in_child)."""
        self.lock = _ForkedLock()
        for k in self._kernels.values():
            k._lock = self.lock

    def __repr__(self) -> str:
        return f"<clpde Runtime [{self.index}] {self.device.name.strip()} ({self.type})>"

    # ---- programs -------------------------------------------------------------------------
    def program(self, filename: str, dtype=np.float32, **defines) -> cl.Program:
        """Build kernels/<filename> once per (file, dtype, defines). An absolute path builds a
        file of one's own (the benchmarks' kernels) with the same include path."""
        dtype = np.dtype(dtype)
        key = (filename, dtype.str, tuple(sorted(defines.items())))
        prog = self._programs.get(key)
        if prog is None:
            with self.lock:  # one build per key, even when threads ask at once
                prog = self._programs.get(key)
                if prog is None:
                    start = time.perf_counter()
                    prog = self._programs[key] = self._build(filename, dtype, defines)
                    self.build_seconds += time.perf_counter() - start
        return prog

    def new_kernel(self, filename: str, name: str, dtype=np.float32, **defines) -> cl.Kernel:
        """A pyopencl kernel instance of its own (not the shared one `kernel` returns), for
        code that sets its arguments once and enqueues it bare (with `enqueue_bare`, which
        the profiler counts)."""
        return cl.Kernel(self.program(filename, dtype, **defines), name)

    def kernel(self, filename: str, name: str, dtype=np.float32, **defines) -> Kernel:
        """A kernel, fetched once and reused (fetching per call is slow in pyopencl);
        calling it launches it as pyopencl's Kernel.__call__ does, safely from any thread."""
        key = (filename, name, np.dtype(dtype).str, tuple(sorted(defines.items())))
        k = self._kernels.get(key)
        if k is None:
            with self.lock:
                k = self._kernels.get(key)
                if k is None:
                    program = self.program(filename, dtype, **defines)
                    fetched = fetch_kernel(program, filename, name, self.platform.name)
                    k = self._kernels[key] = Kernel(fetched, self, key)
        return k

    def _build(self, filename: str, dtype: np.dtype, defines: dict) -> cl.Program:
        path = KERNEL_DIR / filename
        if not path.is_file():
            raise KernelBuildError(f"kernel file {path} does not exist")
        if dtype == np.float64:
            if not self.fp64:
                raise ClpdeError(
                    f"{self.device.name.strip()} has no double precision (cl_khr_fp64); "
                    "use dtype=float32 or another device"
                )
            real = "double"
        elif dtype == np.float32:
            real = "float"
        else:
            raise ClpdeError(f"kernels compute in float32 or float64, not {dtype}")
        # The #line directive makes compiler messages name the real file and line.
        source = f'#line 1 "{path}"\n' + path.read_text()
        # kernels/<capability>/<file> include shared code as "<capability>/<file>", and the
        # ground floor's (kernels/common/) by its bare name
        options = [
            f"-I{KERNEL_DIR}",
            f"-I{KERNEL_DIR / 'common'}",
            f"-DREAL={real}",
            "-cl-std=CL1.2",
        ]
        if real == "double":
            options.append("-DREAL_IS_DOUBLE=1")
        if "portable computing language" in self.platform.name.lower():
            options.append("-DCLPDE_POCL=1")
        if self.platform.name.strip() == "Oclgrind":
            # Oclgrind (21.10, Debian's) cannot run the llvm.experimental.noalias.scope.decl
            # intrinsic that inlining a helper with restrict parameters leaves in a kernel,
            # and then reports the kernel as missing ("morph_adaptive was not found");
            # restrict only licenses optimisations, so the simulator checks the kernels
            # without it (Oclgrind issue 223).
            options.append("-Drestrict=")
        options += [f"-D{k}={v}" for k, v in sorted(defines.items())]
        program, failure = quietly(lambda: cl.Program(self.ctx, source).build(options=options))
        if failure is not None:
            problem = build_problem(self.index)  # a compiler that builds nothing at all
            if problem is not None:
                raise NoDeviceError(problem)
            exc, output = failure
            more = f"\n{output}" if output else ""
            raise KernelBuildError(f"building {path} failed:\n{exc}{more}") from None
        return program

    # ---- work-group limits ----------------------------------------------------------------
    def group_problem(self, kernel, group: int) -> str | None:
        """Why `kernel` cannot run in work-groups of `group` items here (its local memory,
        or the work-group size the device allows for it), or None when it can."""
        return group_problem(self.device, kernel, group)

    # ---- memory ---------------------------------------------------------------------------
    def check_alloc(self, nbytes: int, what: str = "field") -> None:
        """Refuse an allocation the device cannot make, before trying it."""
        self.check_fits(nbytes, nbytes, f"the {what}")

    def check_fits(
        self, total: int, largest: int, what: str, way_out: str = MEMORY_WAY_OUT
    ) -> None:
        """Refuse, before any work, a request whose buffers cannot fit the device: `total`
        bytes in all, the largest single buffer `largest` bytes."""
        check_not_forked()
        name = self.device.name.strip()
        if largest > self.max_alloc:
            raise DeviceMemoryError(
                f"{what} needs {_mib(largest)} in one buffer, but {name} allows at most "
                f"{_mib(self.max_alloc)} per allocation; {way_out}"
            )
        if total > self.global_mem:
            raise DeviceMemoryError(
                f"{what} needs {_mib(total)} of device memory, but {name} has "
                f"{_mib(self.global_mem)}; {way_out}"
            )

    # ---- launch geometry ------------------------------------------------------------------
    def grid_launch(self, nx: int, ny: int, nz: int = 1):
        """(global size, local size, xrun) for a kernel that walks `xrun` cells along x.

        On CPUs one work-item walks a whole row, which PoCL vectorises into a loop running
        at memory bandwidth; on GPUs one work-item takes one cell.
        """
        if self.is_cpu:
            return (1, ny, nz), (1, 1, 1), nx
        lx, ly = 64, 4
        gx = -(-nx // lx) * lx
        gy = -(-ny // ly) * ly
        return (gx, gy, nz), (lx, ly, 1), 1

    def items(self, n: int, *rest: int):
        """(global size, local size) for a kernel of n work-items along its first axis, each
        checking its own index, and `rest` along the others.

        The work-group is fixed, ITEM_GROUP items along the first axis, and the global size
        rounded up to it: PoCL compiles a kernel anew for every work-group size it meets, and
        the one it picks by itself follows the global size (docs/reliability.md has the cost).
        """
        return (-(-n // ITEM_GROUP) * ITEM_GROUP, *rest), (ITEM_GROUP,) + (1,) * len(rest)

    def brick_items(self, n: int) -> tuple[int, int]:
        """(work-items, bricks each) for n bricks walked whole by one work-item each (CPUs):
        16 work-items per compute unit, so the threads share the bricks evenly."""
        per = max(1, -(-n // (16 * self.device.max_compute_units)))
        return -(-n // per), per

    def list_launch(self, n: int):
        """(global size, local size, run) for a kernel over a compacted list of n items."""
        if self.is_cpu:
            groups = 8 * self.device.max_compute_units
            run = max(256, -(-n // groups))
            return (-(-n // run),), (1,), run
        return (-(-n // 64) * 64,), (64,), 1


# ---- processes ------------------------------------------------------------------------------
# OpenCL drivers do not survive fork(): PoCL's worker threads stay in the parent, so a child
# that enqueues anything, even on a fresh context, waits forever (a fork pool of diffuse
# calls hung). A forked child therefore gets a clear error instead, unless its
# parent never touched OpenCL, in which case it starts its own runtimes as usual.
_used_opencl = False  # this process has asked OpenCL for its devices
_forked_from: int | None = None  # the parent whose OpenCL state a forked child inherited


# What every `device=` takes: a name part ('cpu', 'gpu', ...), an index, a Runtime, or None
# for the default choice (see clpde.devices).
DeviceLike = str | int | Runtime | None


def _fork_message() -> str:
    return (
        f"this process was forked from process {_forked_from}, which had already used "
        "OpenCL; OpenCL drivers do not survive a fork (the child would hang). Start worker "
        "processes with the 'spawn' method: multiprocessing.get_context('spawn').Pool(...) or "
        "ProcessPoolExecutor(mp_context=multiprocessing.get_context('spawn')); or create the "
        "pool before the first clpde call"
    )


def check_not_forked() -> None:
    if _forked_from is not None:
        raise ClpdeError(_fork_message())


class _ForkedLock:
    """Stands for a runtime's lock in a forked child: entering it raises the fork error."""

    def __enter__(self):
        raise ClpdeError(_fork_message())

    def __exit__(self, *exc):
        return False


def _after_fork_in_child() -> None:
    global _lock, _forked_from
    _lock = threading.RLock()  # another thread may have held it at the fork
    if _used_opencl and _forked_from is None:
        _forked_from = os.getppid()
    for runtime in _runtimes.values():
        runtime._forked()
    _runtimes.clear()
    _build_problems.clear()
    _found.clear()


if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=_after_fork_in_child)
