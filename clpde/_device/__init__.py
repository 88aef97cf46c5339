"""What clpde.runtime needs of pyopencl beyond its own state: the device record that
clpde.devices() lists, the kernel wrapper whose launches hold the runtime's lock, builds
that keep the compiler's output away from users, and PYOPENCL_CTX as pyopencl reads it.
Imported by clpde.runtime only once it has set POCL_CACHE_DIR (PoCL reads it when pyopencl
loads the ICD)."""

from __future__ import annotations

import atexit
import os
import re
import sys
import tempfile
import threading
import warnings
from dataclasses import dataclass

import numpy as np
import pyopencl as cl

from ..errors import ClpdeError, DeviceLimitError, KernelBuildError


@dataclass(frozen=True)
class DeviceInfo:
    index: int
    platform: str
    name: str
    type: str
    compute_units: int
    global_mem_bytes: int
    max_alloc_bytes: int
    fp64: bool
    in_use: bool = False
    local_mem_bytes: int = 0
    max_group: int = 0
    constant_mem_bytes: int = 0
    images: bool = False

    def describe(self) -> str:
        gib = 1024**3
        mark = "*" if self.in_use else " "
        return (
            f"{mark} [{self.index}] {self.name} ({self.type}, {self.platform}): "
            f"{self.compute_units} compute units, {self.global_mem_bytes / gib:.1f} GiB, "
            f"largest allocation {self.max_alloc_bytes / gib:.2f} GiB, "
            f"fp64 {'yes' if self.fp64 else 'no'}, "
            f"local memory {self.local_mem_bytes // 1024} KB, "
            f"work-groups up to {self.max_group}, "
            f"constant memory {self.constant_mem_bytes // 1024} KB, "
            f"images {'yes' if self.images else 'no'}"
        )


def type_name(device: cl.Device) -> str:
    """'gpu', 'cpu', 'accelerator' or 'other'."""
    if device.type & cl.device_type.GPU:
        return "gpu"
    if device.type & cl.device_type.CPU:
        return "cpu"
    if device.type & cl.device_type.ACCELERATOR:
        return "accelerator"
    return "other"


def has_fp64(device: cl.Device) -> bool:
    return "cl_khr_fp64" in device.extensions or bool(getattr(device, "double_fp_config", 0))


def not_pocl(platform: cl.Platform) -> bool:
    """Sort key that puts PoCL's devices before another runtime's of the same type."""
    return "portable computing language" not in platform.name.lower()


# ---- the compiler's own output ---------------------------------------------------------------
# PoCL's compiler prints "1 error generated." (or "N warnings generated.") straight to the
# process's stderr, and pyopencl turns any non-empty build log into a "Non-empty compiler
# output" warning (Intel's runtime logs every build). Neither means anything to a user whose
# build worked, and a build interrupted by Ctrl-C printed the first before clpde's own line.
# So every build runs with stderr (the file descriptor, which native code writes to) held in
# a file and pyopencl's CompilerWarning held back: shown in the error when the build really
# failed, dropped otherwise. PYOPENCL_COMPILER_OUTPUT=1 lets both through, for debugging.
_quiet_lock = threading.Lock()
_COUNT_LINE = re.compile(r"^\d+ (errors?|warnings?)( and \d+ warnings?)? generated\.\s*$", re.M)


# pyopencl's own kernels (array fills, reductions) are built by pyopencl, outside _quietly:
# its hint that a log exists, without the log, is dropped for them too (with
# PYOPENCL_COMPILER_OUTPUT=1 pyopencl warns with the log itself, which this does not match).
warnings.filterwarnings(
    "ignore", message="Non-empty compiler output encountered", category=cl.CompilerWarning
)


def _compiler_output_wanted() -> bool:
    return os.environ.get("PYOPENCL_COMPILER_OUTPUT", "").strip().lower() in ("1", "true", "yes")


def quietly(build):
    """``build()``, with the compiler's stderr and pyopencl's CompilerWarning held back.

    Returns (result, None), or (None, (exception, the captured text)) when the build raised
    a cl.Error; any other exception (KeyboardInterrupt) propagates with the output dropped.
    Other threads' writes to stderr during the build are dropped too (a progress bar's
    refresh at most: builds take a fraction of a second, and one at a time).
    """
    if _compiler_output_wanted():
        try:
            return build(), None
        except cl.Error as exc:
            return None, (exc, "")
    with _quiet_lock:
        try:
            sys.stderr.flush()
        except (AttributeError, OSError, ValueError):
            pass
        try:
            saved = os.dup(2)
        except OSError:  # no stderr at all: nothing to hold back
            saved = None
        sink = tempfile.TemporaryFile()
        try:
            if saved is not None:
                os.dup2(sink.fileno(), 2)
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always", cl.CompilerWarning)
                try:
                    result, failure = build(), None
                except cl.Error as exc:
                    result, failure = None, exc
        finally:
            if saved is not None:
                os.dup2(saved, 2)
                os.close(saved)
            sink.seek(0)
            text = sink.read().decode("utf-8", "replace")
            sink.close()
    for w in caught:  # other threads' warnings meanwhile go on as they came
        if not issubclass(w.category, cl.CompilerWarning):
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    if failure is None:
        return result, None
    return None, (failure, _COUNT_LINE.sub("", text).strip())


def _pick(part: str, names: list[str], what: str) -> int:
    """Index of the entry of `names` that one part of PYOPENCL_CTX names: its index, or a
    substring of its name (pyopencl's create_some_context reads it the same way)."""
    part = part.strip()
    if part.isdigit() and int(part) < len(names):
        return int(part)
    hits = [i for i, n in enumerate(names) if part and part.lower() in n.lower()]
    if not hits:
        raise ClpdeError(
            f"no {what} matches {part!r}; there are: "
            + "; ".join(f"[{i}] {n}" for i, n in enumerate(names))
        )
    return hits[0]


def pyopencl_ctx(spec: str, found: list) -> int:
    """Index into `found` ((platform, device) pairs) of the device PYOPENCL_CTX names,
    "platform[:device]" as pyopencl reads it."""
    platforms = list(dict.fromkeys(p.name.strip() for p, _ in found))
    plat, _, dev = spec.partition(":")
    platform = platforms[_pick(plat, platforms, "platform")]
    on_it = [i for i, (p, _) in enumerate(found) if p.name.strip() == platform]
    if not dev.strip():
        return on_it[0]
    return on_it[_pick(dev, [found[i][1].name.strip() for i in on_it], "device")]


# ---- per-kernel profiling (CLPDE_PROFILE=1) -------------------------------------------------
# Every launch passes Kernel.__call__, so the device time of each kernel is summed there from
# the OpenCL events (the queues are then made with profiling enabled, see QUEUE_PROPERTIES)
# and printed at exit, slowest first. Off by default: reading an event's times waits for it.
PROFILING = os.environ.get("CLPDE_PROFILE", "").strip() not in ("", "0")
QUEUE_PROPERTIES = cl.command_queue_properties.PROFILING_ENABLE if PROFILING else 0
_PENDING_LIMIT = 256  # launches held before their events are read (each holds a pyopencl event)


class _Profile:
    """Device seconds and launches per kernel, from the launches' events."""

    def __init__(self):
        self.lock = threading.Lock()
        self.pending: list[tuple[str, cl.Event]] = []
        self.seconds: dict[str, float] = {}
        self.launches: dict[str, int] = {}

    def add(self, name: str, event) -> None:
        with self.lock:
            self.pending.append((name, event))
            if len(self.pending) >= _PENDING_LIMIT:
                self._read()

    def _read(self) -> None:
        for name, event in self.pending:
            self.launches[name] = self.launches.get(name, 0) + 1
            try:
                event.wait()
                elapsed = (event.profile.end - event.profile.start) * 1e-9
            except (cl.Error, AttributeError):  # a queue made without profiling
                continue
            self.seconds[name] = self.seconds.get(name, 0.0) + elapsed
        self.pending.clear()

    def report(self, file=None) -> None:
        with self.lock:
            self._read()
            if not self.launches:
                return
            total = sum(self.seconds.values())
            lines = [f"clpde profile: {total:.3f} s of kernel time (CLPDE_PROFILE=1)"]
            lines += [
                f"  {self.seconds.get(n, 0.0):9.4f} s {self.launches[n]:8d} launches  {n}"
                for n in sorted(self.launches, key=lambda n: -self.seconds.get(n, 0.0))
            ]
            print("\n".join(lines), file=file or sys.stderr)


PROFILE = _Profile()
if PROFILING:
    atexit.register(PROFILE.report)


def enqueue_bare(queue, kernel: cl.Kernel, global_size, local_size, filename: str) -> cl.Event:
    """Enqueue a kernel instance whose arguments were set once (Runtime.new_kernel), counted
    by the profiler as `filename:name` like every launch through Kernel."""
    event = cl.enqueue_nd_range_kernel(queue, kernel, global_size, local_size)
    if PROFILING:
        PROFILE.add(f"{filename}:{kernel.function_name}", event)
    return event


class Kernel:
    """A pyopencl kernel whose launches hold the runtime's lock.

    pyopencl's Kernel.__call__ sets the arguments on the shared kernel object and then
    enqueues it; two threads in between would run one thread's step on the other's buffers.
    Once enqueued, a launch keeps its arguments, so only the two calls need the lock.
    """

    __slots__ = ("_lock", "cl_kernel", "key", "runtime")

    def __init__(self, cl_kernel: cl.Kernel, runtime, key: tuple):
        self.cl_kernel = cl_kernel
        self._lock = runtime.lock
        self.runtime, self.key = runtime, key

    def __call__(self, queue, global_size, local_size, *args, **kwargs) -> cl.Event:
        with self._lock:
            try:
                event = self.cl_kernel(queue, global_size, local_size, *args, **kwargs)
            except cl.Error as exc:
                raise self._launch_error(exc, local_size) from None
        if PROFILING:
            PROFILE.add(f"{self.key[0]}:{self.key[1]}", event)
        return event

    def _launch_error(self, exc: cl.Error, local_size) -> ClpdeError:
        """A launch the device refused, as clpde's error: which limit, and the way out.
        (The paths that need local memory or large work-groups check before any work;
        this is the net under every other launch.)"""
        group = int(np.prod(local_size)) if local_size else 0
        problem = self.runtime.group_problem(self, group) if group else None
        name = self.runtime.device.name.strip()
        detail = problem or f"{name} refused kernel {self.cl_kernel.function_name}: {exc}"
        return DeviceLimitError(
            f"{detail}; choose another device (clpde devices, CLPDE_DEVICE) or a smaller "
            "input, and report it at clpde's issue tracker with the output of clpde devices"
        )

    def __getattr__(self, name):
        if name == "cl_kernel":  # not set yet: no recursion through this method
            raise AttributeError(name)
        return getattr(self.cl_kernel, name)


def group_problem(device: cl.Device, kernel, group: int) -> str | None:
    """Why `kernel` (a Kernel or a pyopencl kernel) cannot run on `device` in work-groups of
    `group` items (its local memory, or the work-group size the device allows for it), or
    None when it can."""
    k = kernel.cl_kernel if isinstance(kernel, Kernel) else kernel
    info = cl.kernel_work_group_info
    local = k.get_work_group_info(info.LOCAL_MEM_SIZE, device)
    largest = k.get_work_group_info(info.WORK_GROUP_SIZE, device)
    name = device.name.strip()
    if local > device.local_mem_size:
        return (
            f"kernel {k.function_name} needs {local // 1024} KB of local memory, but "
            f"{name} has {device.local_mem_size // 1024} KB"
        )
    if group > largest:
        return (
            f"kernel {k.function_name} runs in work-groups of {group} items, but {name} "
            f"allows at most {largest} for it"
        )
    return None


def build_failure(platform: cl.Platform, device: cl.Device, source: str) -> str | None:
    """Why `device` cannot build the OpenCL C program `source`, or None when it can."""
    try:
        ctx = cl.Context([device])
    except cl.Error as exc:
        return f"{device.name.strip()} ({platform.name.strip()}) cannot be opened: {exc}"
    _, failure = quietly(lambda: cl.Program(ctx, source).build())
    if failure is None:
        return None
    log = str(failure[0])
    if "unknown target CPU" in log:
        return (
            f"{device.name.strip()} ({platform.name.strip()}) cannot compile kernels: "
            "its LLVM does not know this CPU; install your system's PoCL "
            "(e.g. apt install pocl-opencl-icd) or the CPU vendor's OpenCL runtime"
        )
    first = next((ln for ln in log.splitlines() if "error" in ln.lower()), log)
    return (
        f"{device.name.strip()} ({platform.name.strip()}) cannot compile "
        f"kernels: {first.strip()[:200]}"
    )


def fetch_kernel(program: cl.Program, filename: str, name: str, platform: str) -> cl.Kernel:
    """Kernel `name` of a built program, or one line that says why the device has none:
    with PoCL a build killed half-way can leave its cache entry without the kernels (seen
    2026-12-07: every later run then failed with CL_INVALID_KERNEL_NAME)."""
    try:
        return cl.Kernel(program, name)
    except cl.LogicError:
        text = f"kernels/{filename} built, but the device finds no kernel {name!r} in it"
        cache = os.environ.get("POCL_CACHE_DIR")
        if cache and "portable computing language" in platform.lower():
            text += (
                f"; where the file defines it, PoCL's kernel cache holds a broken build (a "
                f"run stopped while building): delete {cache} and run again"
            )
        raise KernelBuildError(text) from None
