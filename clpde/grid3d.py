"""Ghost-padded 3D volumes on the device and narrow-band index lists over them.

A volume of `nc` channels on an nz x ny x nx grid lives on the device as one buffer of shape
(nc, nz + 2G, ny + 2G, nx + 2G), x fastest. Band kernels visit a compacted list of flat
padded indices (built on the device with clpde.fields.compact) and never test for borders:
bands are kept at least G cells away from the buffer's edge.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pyopencl.array as cla

from .errors import ClpdeError
from .fields import BaseGrid, IndexList, compact
from .runtime import Runtime

# The kernels/ files this module's kernel lookups name (tests/core/test_kernel_names.py checks).
KERNEL_FILES = ("common/grid3d.cl",)


@dataclass(frozen=True)
class BandRuns:
    """A band list cut into runs of consecutive cells along x (kernels' RUN_ARGS).

    Run r covers cells [start[r], end[r]) (device arrays): the band's cells, on CPUs each run
    lengthened to a multiple of the vector width where room allows (those extra cells get
    stepped values nobody reads). On GPUs every cell is a run of its own."""

    band: IndexList
    start: cla.Array
    end: cla.Array
    n: int


@dataclass(frozen=True)
class Grid3D(BaseGrid):
    """Geometry of a padded 3D volume on one device (kernel, scalar, interior and
    launch_list come from fields.BaseGrid; a list launch covers one channel unless told).

    Parameters
    ----------
    runtime : Runtime
        The device (`clpde.get_runtime`).
    nx, ny, nz : int
        The volume's cells along x, y and z (without the ghost cells).
    ghost : int, optional
        Ghost cells on each side of each axis.
    dtype : numpy.dtype, optional
        The device's arithmetic, float32 or float64.

    Examples
    --------
    >>> import numpy as np
    >>> from clpde import get_runtime
    >>> from clpde.surface import Grid3D
    >>> g = Grid3D(get_runtime(), nx=8, ny=6, nz=4)
    >>> g.shape, g.padded_shape
    ((4, 6, 8), (10, 12, 14))
    >>> volume = np.arange(4 * 6 * 8, dtype=np.float32).reshape(1, 4, 6, 8)
    >>> bool(np.array_equal(g.download(g.upload(volume)), volume))
    True
    """

    runtime: Runtime
    nx: int
    ny: int
    nz: int
    ghost: int = 3
    dtype: np.dtype = np.dtype(np.float32)  # noqa: RUF009  (immutable, as in fields.Grid)

    @property
    def shape(self) -> tuple[int, int, int]:
        return (self.nz, self.ny, self.nx)

    @property
    def channel_stride(self) -> int:
        return self.volume

    @property
    def padded_shape(self) -> tuple[int, int, int]:
        g2 = 2 * self.ghost
        return (self.nz + g2, self.ny + g2, self.nx + g2)

    @property
    def sx(self) -> int:
        return self.nx + 2 * self.ghost

    @property
    def sxy(self) -> int:
        return self.sx * (self.ny + 2 * self.ghost)

    @property
    def volume(self) -> int:
        """Cells of one padded channel (the channel stride)."""
        return self.sxy * (self.nz + 2 * self.ghost)

    def strides(self) -> tuple[np.int32, np.int32]:
        return np.int32(self.sx), np.int32(self.sxy)

    def padded_dims(self) -> tuple[np.int32, np.int32, np.int32]:
        """Padded sizes along x, y, z (the interpolation clamps its nodes into these)."""
        pz, py, px = self.padded_shape
        return np.int32(px), np.int32(py), np.int32(pz)

    # ---- host <-> device --------------------------------------------------------------------
    def pad(self, values: np.ndarray, mode: str = "edge") -> np.ndarray:
        """Pad (nc, nz, ny, nx) host values by the ghost width on every spatial side."""
        g = self.ghost
        width = ((0, 0), (g, g), (g, g), (g, g))
        if mode == "linear":
            # Odd reflection continues the values linearly: right for distance functions.
            return np.pad(values, width, mode="reflect", reflect_type="odd")
        return np.pad(values, width, mode=mode)

    def upload(self, values: np.ndarray, mode: str = "edge") -> cla.Array:
        """Upload (nc, nz, ny, nx) values as a padded device volume."""
        values = np.asarray(values)
        if values.ndim != 4 or values.shape[1:] != (self.nz, self.ny, self.nx):
            raise ClpdeError(
                f"expected values of shape (channels, {self.nz}, {self.ny}, {self.nx}), "
                f"got {values.shape}"
            )
        # Values beyond the storage type's range (a far-away distance of 1e300) are clipped
        # to its largest finite value rather than cast to inf, which would poison stencils.
        big = float(np.finfo(self.dtype).max)
        values = np.clip(values.astype(np.float64), -big, big)  # so the padding stays finite
        padded = np.clip(self.pad(values, mode), -big, big)
        padded = np.ascontiguousarray(padded, self.dtype)
        self.runtime.check_alloc(padded.nbytes, "surface volume")
        return cla.to_device(self.runtime.queue, padded)

    def download(self, data: cla.Array) -> np.ndarray:
        """The interior of a device volume as an (nc, nz, ny, nx) host array."""
        return np.ascontiguousarray(self.interior(data.get()))

    # ---- bands and launches ----------------------------------------------------------------
    def band(self, psi: cla.Array, width: float) -> IndexList:
        """Interior cells with |psi| < width (psi in the units of `width`), on the device."""
        mask = cla.zeros(self.runtime.queue, self.padded_shape, np.uint8)
        self.kernel("common/grid3d.cl", "grid3d_band_mask")(
            self.runtime.queue,
            *self.runtime.items(self.ny, self.nz),
            psi.data,
            mask.data,
            self.scalar(width),
            np.int32(self.nx),
            np.int32(self.ny),
            np.int32(self.nz),
            *self.strides(),
            np.int32(self.ghost),
        )
        return compact(self.runtime, mask)

    def runs(self, band: IndexList, pad: int = 16) -> BandRuns:
        """The band's runs of consecutive cells, lengthened to multiples of `pad` cells (on
        CPUs; single cells on GPUs), on the device."""
        q = self.runtime.queue
        n = band.n
        if n == 0 or not self.runtime.is_cpu:
            offsets, nruns, pad = cla.arange(q, 0, max(n, 1), dtype=np.int32), n, 1
        else:
            flags = cla.empty(q, n, np.uint8)
            self.kernel("common/grid3d.cl", "grid3d_band_run_starts")(
                q, *self.runtime.items(n), band.indices.data, np.int32(n), flags.data
            )
            starts = compact(self.runtime, flags)
            offsets, nruns = starts.indices, starts.n
        start = cla.empty(q, max(nruns, 1), np.int32)
        end = cla.empty(q, max(nruns, 1), np.int32)
        if nruns:
            self.kernel("common/grid3d.cl", "grid3d_band_run_bounds")(
                q,
                *self.runtime.items(nruns),
                band.indices.data,
                offsets.data,
                np.int32(nruns),
                np.int32(n),
                np.int32(pad),
                np.int32(self.nx),
                np.int32(self.sx),
                np.int32(self.ghost),
                start.data,
                end.data,
            )
        return BandRuns(band, start, end, nruns)

    def launch_runs(self, kernel, runs: BandRuns, *args, channels: int = 1):
        """Run a RUN_RANGE kernel over a band's runs, `channels` work-items per run."""
        if runs.n == 0:
            return None
        (gsize,), (lsize,), per_item = self.runtime.list_launch(runs.n)
        return kernel(
            self.runtime.queue,
            (gsize, channels),
            (lsize, 1),
            *args,
            runs.start.data,
            runs.end.data,
            np.int32(runs.n),
            np.int32(self.volume),
            np.int32(per_item),
        )
