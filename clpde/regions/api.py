"""Region tracking's entry points: `track_region` (thesis section 2.2) checks the user's
surface, regions, speed and times, builds the tracker and runs it to each saved time;
`region_tracker` builds the tracker of a storage (STORAGE_CLASSES: the lists of tracker.py,
the bricks of bricks.py)."""

from __future__ import annotations

from collections.abc import Callable, Iterable

import numpy as np
from numpy.typing import ArrayLike, DTypeLike

from .._progress import progress_bar
from ..bricks import StorageTable
from ..errors import InputError
from ..imagedata import positive as _positive
from ..runtime import DeviceLike
from .bricks import BrickRegionTracker
from .mesh import _region_functions
from .region_frame import RegionFrame
from .speed import surface_motion
from .tracker import RegionTracker

__all__ = ["region_tracker", "track_region"]

# storage name -> the tracker that keeps the level sets in it; STORAGE_CLASSES.choose checks a name
STORAGE_CLASSES = StorageTable(lists=RegionTracker, bricks=BrickRegionTracker)


def region_tracker(
    phi: np.ndarray, phihat: np.ndarray, spacing: float, *, storage: str = "lists", **options
) -> RegionTracker:
    """The tracker of `storage` ("lists" or "bricks"; the bricks take brick=(BX, BY, BZ) too)
    on these level sets, built with RegionTracker's options."""
    return STORAGE_CLASSES.choose(storage)(phi, phihat, spacing, **options)


def _checked_phi(phi: ArrayLike, dtype: DTypeLike) -> np.ndarray:
    """phi as float64 (nz, ny, nx), or InputError: a volume with a surface whose squared
    gradients fit the arithmetic."""
    phi = np.asarray(phi)
    if phi.ndim != 3 or min(phi.shape) < 8:
        raise InputError(
            f"phi must be a 3D (nz, ny, nx) volume with at least 8 cells a side, got {phi.shape}"
        )
    if not np.issubdtype(phi.dtype, np.number) or not np.all(np.isfinite(phi)):
        raise InputError("phi must hold finite real numbers")
    phi = phi.astype(np.float64)
    if not (phi.min() < 0 < phi.max()):
        raise InputError("phi never changes sign: it has no surface to track regions on")
    limit = np.sqrt(np.finfo(np.dtype(dtype)).max)  # squared gradients must not overflow
    if np.abs(phi).max() > limit:
        raise InputError(
            f"phi reaches {np.abs(phi).max():.3g}, beyond what {np.dtype(dtype)} "
            f"arithmetic squares ({limit:.3g}); phi is a distance: rescale it"
        )
    return phi


def _final_time(t: float) -> float:
    t_end = float(t)
    if not np.isfinite(t_end) or t_end < 0:
        raise InputError(f"t must be a non-negative time, not {t!r}")
    return t_end


def _save_times(saves: int | Iterable[float], t_end: float) -> list[float]:
    """The saved times: `saves` intervals of [0, t_end], or the given times, ascending."""
    if np.ndim(saves) == 0:
        n = int(saves)
        if n < 1:
            raise InputError(f"saves must be at least 1, not {saves!r}")
        return [t_end * k / n for k in range(n + 1)]
    times = sorted(float(s) for s in saves)
    if not times or times[0] < 0 or times[-1] > t_end + 1e-12:
        raise InputError(f"save times must lie in [0, t={t_end:g}], got {saves!r}")
    return times


def track_region(
    phi: ArrayLike,
    region: ArrayLike | list,
    beta: float | str | ArrayLike | Callable = 1.0,
    t: float = 1.0,
    spacing: float = 1.0,
    saves: int | Iterable[float] = 1,
    *,
    origin: ArrayLike = (0.0, 0.0, 0.0),
    mesh: object = None,
    palette: ArrayLike | None = None,
    target: ArrayLike | None = None,
    velocity: ArrayLike | None = None,
    weight: float = 1.0,
    band_width: float = 5.0,
    reinit_every: int = 4,
    reinit_iterations: int = 6,
    cfl: float = 0.4,
    max_speed: float | None = None,
    keep_volumes: bool = False,
    device: DeviceLike = None,
    dtype: DTypeLike = np.float32,
    progress: bool | None = None,
    storage: str = "lists",
) -> list[RegionFrame]:
    """Track regions painted on a surface while the surface deforms (thesis section 2.2).

    Parameters
    ----------
    phi : array_like
        (nz, ny, nx) signed distance of the surface (world units, negative inside; other
        level-set functions are reinitialised first).
    region : array_like or list
        A bool mask over the vertices of the starting mesh (`surface_mesh(phi, spacing,
        origin)`, or of `mesh`), integer vertex labels (one region per label), an implicit
        function Phi-hat of phi's shape (the region is where Phi-hat < 0 on the surface;
        off the surface it is replaced by its value at the closest surface point), or a
        list of such functions.
    beta : float or str or array_like or callable, optional
        Outward normal speed of the surface: a number; 'mean-curvature' (speed -weight
        (k1 + k2)); 'gaussian' (speed -weight max(K, 0) sign(k1 + k2): folds flatten);
        'morph' (toward `target`: -weight (target - phi)); an array of phi's shape; a
        callable f(x, y, z) (world coordinates); or f(x, y, z, t), re-evaluated once per
        block of `reinit_every` steps at the block's middle time (the midpoint rule).
    t : float, optional
        The final time.
    spacing : float, optional
        The grid spacing of phi (world units).
    saves : int or iterable of float, optional
        The number of saved intervals (frames at t * k / saves, k = 0..saves), or a
        sequence of times in [0, t].
    origin : array_like, optional
        World (x, y, z) of phi[0, 0, 0].
    mesh : trimesh.Trimesh, optional
        Any mesh of the same surface in world coordinates (the one phi was made from, say)
        that a vertex mask or labels in `region` refer to.
    palette : array_like, optional
        (L, 3) RGB in [0, 1], the colour of each region in the frames' meshes (default:
        clpde's palette; grey where no region is).
    target : array_like, optional
        The signed distance volume that beta='morph' moves toward.
    velocity : array_like, optional
        (vx, vy, vz): translate the surface instead of moving it by beta.
    weight : float, optional
        The factor of the curvature and morph speeds.
    band_width : float, optional
        Half-width in cells of the band that is stepped.
    reinit_every : int, optional
        Steps per block; the level sets are reinitialised once the surface may have moved
        that many CFL steps.
    reinit_iterations : int, optional
        Iterations of a reinitialisation.
    cfl : float, optional
        The CFL number of the steps.
    max_speed : float, optional
        Clamp |beta| (world units) where creases finer than the grid would set a tiny step.
    keep_volumes : bool, optional
        Keep the level sets Phi and Phi-hat in each frame.
    device : str or int or Runtime, optional
        The OpenCL device, as for `clpde.use_device`.
    dtype : {float32, float64}, optional
        The device's arithmetic.
    progress : bool, optional
        Draw a progress bar (of simulated time); by default only on a terminal.
    storage : {'lists', 'bricks'}, optional
        Dense padded volumes with the band as index lists, or dense bricks of the band only
        (memory in proportion to the band; docs/regions.md).

    Returns
    -------
    list of RegionFrame
        One per saved time: the mesh (trimesh, per-vertex region colours), face_labels,
        boundary points and (keep_volumes) the level sets.

    Raises
    ------
    InputError
        For a phi without a surface, regions or speeds that cannot be used, or a surface
        that reaches the volume's border.

    Examples
    --------
    >>> import numpy as np
    >>> import clpde
    >>> ax = (np.arange(40) - 19.5) * 0.1
    >>> z, y, x = np.meshgrid(ax, ax, ax, indexing="ij")
    >>> phi = np.sqrt(x**2 + y**2 + z**2) - 0.6
    >>> frames = clpde.track_region(phi, 0.2 - z, beta=0.5, t=0.2, spacing=0.1,
    ...                             origin=(ax[0],) * 3, progress=False)
    >>> len(frames), frames[-1].area() > frames[0].area()
    (2, True)
    """
    phi = _checked_phi(phi, dtype)
    h = _positive("spacing", spacing)
    t_end = _final_time(t)
    origin = np.asarray(origin, np.float64).reshape(3)
    times = _save_times(saves, t_end)
    phihat, partition = _region_functions(phi, region, h, origin, mesh)
    speed, scale, aux, aux_at, vel = surface_motion(
        beta, velocity, target, weight, h, phi.shape, origin
    )
    tracker = region_tracker(
        phi,
        phihat,
        h,
        speed=speed,
        scale=scale,
        aux=aux,
        velocity=vel,
        band_width=5.0 if band_width is None else band_width,
        reinit_every=reinit_every,
        reinit_iterations=reinit_iterations,
        cfl=cfl,
        max_speed=None if max_speed is None else _positive("max_speed", max_speed) / h,
        aux_at=aux_at,
        device=device,
        dtype=dtype,
        storage=storage,
    )
    # the bar counts simulated time, so it prints rounded times rather than step counts
    time_format = "{l_bar}{bar}| t = {n:.4g}/{total:.4g} [{elapsed}<{remaining}]"
    with progress_bar(
        progress, t_end, "track regions", leave=False, unit="time", bar_format=time_format
    ) as bar:
        return list(
            tracker.iterate(
                times,
                origin=origin,
                keep_volumes=keep_volumes,
                palette=palette,
                partition=partition,
                bar=bar,
            )
        )
