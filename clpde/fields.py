"""Ghost-padded device fields, ghost filling, ping-pong pairs, index lists and reductions.

A field of `nc` channels on an ny x nx grid lives on the device as one buffer of shape
(nc, ny + 2G, nx + 2G). Stencil kernels update interior cells with no border test; the
ghost layer is refreshed by `Field.fill_ghosts` between steps.
"""

from __future__ import annotations

import copyreg
import pickle
from abc import ABC, abstractmethod
from dataclasses import dataclass

import numpy as np
import pyopencl as cl
import pyopencl.array as cla

from .errors import ClpdeError
from .runtime import (
    Kernel,
    Runtime,
    check_not_forked,
    runtime_named,
    runtime_of_context,
)

# The kernels/ files this module's kernel lookups name (tests/core/test_kernel_names.py checks).
KERNEL_FILES = ("common/fields.cl",)

NEUMANN, DIRICHLET = 0, 1
FLOAT32 = np.dtype(np.float32)
_REDUCE_OPS = {
    "sum": 0,
    "sumsq": 1,
    "maxabsdiff": 2,
    "sumsqdiff": 3,
    "maxabs": 4,
    "min": 5,
    "max": 6,
}


class BaseGrid(ABC):
    """What the 2D and 3D grids share (Grid here, clpde.grid3d.Grid3D): kernel
    lookups in the grid's dtype, scalars, the interior of padded arrays and launches over
    index lists. A subclass is a frozen dataclass with `runtime`, `dtype` and `ghost`, and
    says its interior's `shape` (slowest axis first), the cells of one padded channel
    (`channel_stride`, the kernels' `plane`) and how many channels a list launch covers
    unless told (`list_channels`)."""

    runtime: Runtime
    dtype: np.dtype
    ghost: int

    @property
    @abstractmethod
    def shape(self) -> tuple[int, ...]: ...

    @property
    @abstractmethod
    def channel_stride(self) -> int: ...

    @property
    def list_channels(self) -> int:
        return 1

    def kernel(self, filename: str, name: str, **defines) -> Kernel:
        """Kernel `name` of kernels/<filename> in this grid's dtype."""
        return self.runtime.kernel(filename, name, self.dtype, **defines)

    def scalar(self, value) -> np.generic:
        return self.dtype.type(value)

    def interior(self, padded: np.ndarray) -> np.ndarray:
        """The interior of a padded host array (leading channel axes kept)."""
        g = self.ghost
        return padded[(Ellipsis,) + tuple(slice(g, g + n) for n in self.shape)]

    def launch_list(
        self, kernel: Kernel, index_list: IndexList, *args, channels: int | None = None
    ) -> cl.Event | None:
        """Run a LIST_RANGE kernel over the cells of an index list, `channels` work-items per
        cell (default `list_channels`)."""
        if index_list.n == 0:
            return None
        channels = self.list_channels if channels is None else channels
        (gsize,), (lsize,), run = self.runtime.list_launch(index_list.n)
        return kernel(
            self.runtime.queue,
            (gsize, channels),
            (lsize, 1),
            *args,
            index_list.indices.data,
            np.int32(index_list.n),
            np.int32(self.channel_stride),
            np.int32(run),
        )


@dataclass(frozen=True)
class Grid(BaseGrid):
    """Geometry of a padded 2D multi-channel field on one device."""

    runtime: Runtime
    nx: int
    ny: int
    nc: int = 1
    ghost: int = 1
    dtype: np.dtype = FLOAT32

    @property
    def shape(self) -> tuple[int, int]:
        return (self.ny, self.nx)

    @property
    def channel_stride(self) -> int:
        return self.plane

    @property
    def list_channels(self) -> int:
        """A list launch covers every channel."""
        return self.nc

    @property
    def sx(self) -> int:
        return self.nx + 2 * self.ghost

    @property
    def plane(self) -> int:
        return self.sx * (self.ny + 2 * self.ghost)

    @property
    def padded_shape(self) -> tuple[int, int, int]:
        return (self.nc, self.ny + 2 * self.ghost, self.sx)

    def args(self, xrun: int) -> tuple:
        """The GRID_ARGS of common.h."""
        return tuple(np.int32(v) for v in (self.nx, self.ny, self.sx, self.plane, self.ghost, xrun))

    def launch(self, kernel: Kernel, *args, wait_for=None) -> cl.Event:
        """Run a FOR_EACH_CELL kernel over every interior cell of every channel."""
        gsize, lsize, xrun = self.runtime.grid_launch(self.nx, self.ny, self.nc)
        return kernel(self.runtime.queue, gsize, lsize, *args, *self.args(xrun), wait_for=wait_for)


def check_fits(
    runtime: Runtime,
    shape,
    what: str,
    fields: float,
    ghost: int = 1,
    dtype=FLOAT32,
    largest: float = 1.0,
) -> None:
    """Refuse, before any work, a computation on (nc, ny, nx) data (or (nc, nz, ny, nx)
    volumes) that keeps about `fields` padded fields of that shape on the device, the
    largest buffer `largest` fields."""
    one = shape[0] * np.dtype(dtype).itemsize
    for n in shape[1:]:
        one *= n + 2 * ghost
    total, biggest = int(fields * one), int(largest * one)
    if total > runtime.global_mem or biggest > runtime.max_alloc:  # (the message only then)
        dims = "x".join(str(n) for n in shape[:0:-1]) + (f"x{shape[0]}" if shape[0] > 1 else "")
        runtime.check_fits(total, biggest, f"{what} of {dims} values")


class Field:
    """A padded device array on a Grid."""

    def __init__(self, grid: Grid, data: cla.Array):
        self.grid = grid
        self.data = data

    @classmethod
    def empty(cls, grid: Grid) -> Field:
        nbytes = int(np.prod(grid.padded_shape)) * grid.dtype.itemsize
        grid.runtime.check_alloc(nbytes)
        return cls(grid, cla.empty(grid.runtime.queue, grid.padded_shape, grid.dtype))

    @classmethod
    def from_host(
        cls, grid: Grid, values: np.ndarray, boundary: str = "neumann", value=0.0
    ) -> Field:
        """Upload (nc, ny, nx) values and fill the ghosts."""
        values = np.asarray(values)
        if values.shape != (grid.nc, grid.ny, grid.nx):
            raise ClpdeError(
                f"expected values of shape {(grid.nc, grid.ny, grid.nx)}, got {values.shape}"
            )
        field = cls.empty(grid)
        padded = np.zeros(grid.padded_shape, grid.dtype)
        grid.interior(padded)[...] = values
        field.data.set(padded)
        field.fill_ghosts(boundary, value)
        return field

    def copy(self) -> Field:
        return Field(self.grid, self.data.copy())

    def assign(self, other: Field) -> None:
        """Copy another field of the same grid into this one, on the device."""
        cl.enqueue_copy(self.grid.runtime.queue, self.data.data, other.data.data)

    def to_host(self) -> np.ndarray:
        """The interior as an (nc, ny, nx) numpy array (one device-to-host copy)."""
        check_not_forked()  # a forked child would wait forever for the copy
        return np.ascontiguousarray(self.grid.interior(self.data.get()))

    def fill_ghosts(self, boundary: str = "neumann", value=0.0) -> None:
        """Neumann: mirror the interior across the border; Dirichlet: the fixed value."""
        mode = {"neumann": NEUMANN, "dirichlet": DIRICHLET}.get(boundary)
        if mode is None:
            raise ClpdeError(f"boundary must be 'neumann' or 'dirichlet', not {boundary!r}")
        g = self.grid
        q = g.runtime.queue
        args = (self.data.data, np.int32(mode), g.scalar(value), *g.args(g.nx))
        g.kernel("common/fields.cl", "fields_fill_ghost_cols")(
            q, *g.runtime.items(g.ny, g.nc), *args
        )
        g.kernel("common/fields.cl", "fields_fill_ghost_rows")(
            q, *g.runtime.items(g.sx, g.nc), *args
        )

    def reduce(self, op: str, other: Field | None = None) -> np.ndarray:
        """A per-channel reduction over the interior, computed on the device.

        op: 'sum', 'sumsq', 'maxabsdiff', 'sumsqdiff', 'maxabs', 'min' or 'max'. Only the
        per-row partials (nc * ny numbers) come back to the host.
        """
        g = self.grid
        partial = cla.empty(g.runtime.queue, (g.nc, g.ny), g.dtype)
        b = (other if other is not None else self).data.data
        g.kernel("common/fields.cl", "fields_row_reduce")(
            g.runtime.queue,
            (1, g.ny, g.nc),
            (1, 1, 1),  # a fixed work-group (Runtime.items)
            self.data.data,
            b,
            np.int32(_REDUCE_OPS[op]),
            partial.data,
            *g.args(g.nx),
        )
        rows = partial.get().astype(np.float64)
        if op in ("maxabsdiff", "maxabs", "max"):
            return rows.max(axis=1)
        if op == "min":
            return rows.min(axis=1)
        return rows.sum(axis=1)

    def max_abs_diff(self, other: Field) -> float:
        return float(self.reduce("maxabsdiff", other).max())

    def total(self) -> np.ndarray:
        return self.reduce("sum")

    def norm(self) -> np.ndarray:
        return np.sqrt(self.reduce("sumsq"))


class PingPong:
    """Two fields a step reads from (`cur`) and writes every interior cell of (`nxt`)."""

    def __init__(self, field: Field):
        self.cur = field
        self.nxt = field.copy()

    def swap(self) -> None:
        self.cur, self.nxt = self.nxt, self.cur


@dataclass
class IndexList:
    """Flat padded indices of the cells a sparse kernel visits, built on the device."""

    indices: cla.Array
    n: int


def compact(runtime: Runtime, mask: cla.Array) -> IndexList:
    """The flat indices where a device uint8 array is nonzero, in increasing order."""
    n = mask.size
    q = runtime.queue
    chunk = 4096
    nchunks = max(1, -(-n // chunk))
    counts = cla.empty(q, nchunks, np.int32)
    total = cla.empty(q, 1, np.int32)
    flat = mask.reshape(n)

    launch = runtime.items(nchunks)
    runtime.kernel("common/fields.cl", "fields_count_chunks")(
        q, *launch, flat.data, np.int32(n), np.int32(chunk), counts.data
    )
    runtime.kernel("common/fields.cl", "fields_exclusive_scan_serial")(
        q, (1,), (1,), counts.data, np.int32(nchunks), total.data
    )
    count = int(total.get()[0])  # the list's length sizes the launches: one read per build
    indices = cla.empty(q, max(count, 1), np.int32)
    if count:
        runtime.kernel("common/fields.cl", "fields_write_chunks")(
            q, *launch, flat.data, np.int32(n), np.int32(chunk), counts.data, indices.data
        )
    return IndexList(indices, count)


def index_list(grid: Grid, mask: np.ndarray) -> IndexList:
    """Index list of the interior cells where a host (ny, nx) mask is true."""
    mask = np.asarray(mask, bool)
    if mask.shape != (grid.ny, grid.nx):
        raise ClpdeError(f"mask shape {mask.shape} differs from the grid's {(grid.ny, grid.nx)}")
    g = grid.ghost
    padded = np.zeros(grid.padded_shape[1:], np.uint8)
    padded[g : g + grid.ny, g : g + grid.nx] = mask
    return compact(grid.runtime, cla.to_device(grid.runtime.queue, padded))


# ---- pickling ----------------------------------------------------------------------------
# Device buffers pickle as their bytes, read back from the device, and arrays as views of
# their buffers (pickle's memo keeps two references to one buffer one buffer); the runtime
# pickles as its device's name and is rebuilt where the object is unpickled. So clpde's
# objects that hold device state (PlanarFlow, ImplicitSurface, ...) pickle by value.


def _reduce_runtime(runtime: Runtime):
    # by device name: the process that unpickles builds (or reuses) its own runtime
    return runtime_named, (runtime.platform.name.strip(), runtime.device.name.strip())


def _reduce_kernel(kernel: Kernel):
    # by its lookup: the receiving process builds (or reuses) its own
    return _receive_kernel, (kernel.runtime, *kernel.key)


def _receive_kernel(runtime: Runtime, filename, name, dtype, defines) -> Kernel:
    return runtime.kernel(filename, name, np.dtype(dtype), **dict(defines))


def _runtime_of(obj) -> Runtime:
    runtime = runtime_of_context(obj.context)
    if runtime is not None:
        return runtime
    raise pickle.PicklingError(
        f"cannot pickle {type(obj).__name__} of a context clpde did not make"
    )


def _reduce_buffer(buf: cl.Buffer):
    runtime = _runtime_of(buf)
    host = np.empty(buf.size, np.uint8)
    cl.enqueue_copy(runtime.queue, host, buf)  # in order: after every enqueued step
    return _receive_buffer, (runtime, host)


def _receive_buffer(runtime: Runtime, host: np.ndarray) -> cl.Buffer:
    buf = cl.Buffer(runtime.ctx, cl.mem_flags.READ_WRITE, max(host.size, 1))
    cl.enqueue_copy(runtime.queue, buf, host)
    return buf


def _reduce_array(a):
    return _receive_array, (_runtime_of(a), a.shape, a.dtype, a.strides, a.offset, a.base_data)


def _receive_array(runtime: Runtime, shape, dtype, strides, offset, base):
    return cla.Array(runtime.queue, shape, dtype, strides=strides, data=base, offset=offset)


def _register_picklers() -> None:
    copyreg.pickle(Runtime, _reduce_runtime)
    copyreg.pickle(Kernel, _reduce_kernel)
    copyreg.pickle(cl.Buffer, _reduce_buffer)
    copyreg.pickle(cla.Array, _reduce_array)
    copyreg.pickle(cl.CommandQueue, lambda q: (getattr, (_runtime_of(q), "queue")))
    copyreg.pickle(cl.Context, lambda c: (getattr, (_runtime_of(c), "ctx")))


_register_picklers()
