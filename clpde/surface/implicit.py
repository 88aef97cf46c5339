"""ImplicitSurface: the zero level set of a signed distance function on a 3D grid.

The surface keeps psi on the device together with two band lists:
- the *step band* |psi| < inner * h, where the flows are updated; inner covers every node
  the closest-point interpolation reads (2 sqrt(3) cells for tricubic, sqrt(3) trilinear);
- the *extension band* |psi| < outer * h (outer >= inner + sqrt(2)), re-extended from the
  step band's values after every step, so every neighbour a step reads holds data that is
  constant along the normals.
The steps themselves run on two narrower lists cut to what they need (same results):
- `node_band`: the interpolation nodes of the extension band's closest points, the only
  cells whose stepped values are ever read;
- `reach_band`: those nodes and their 18 neighbours, the cells a step reads, re-extended
  after every step. The whole extension band is re-extended once, when a flow returns.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, DTypeLike

from ..errors import InputError
from ..fields import check_fits
from ..grid3d import Grid3D
from ..imagedata import positive as _positive
from ..runtime import DeviceLike, get_runtime
from . import band as band_setup
from . import sampling as _sampling
from .band import NODE_REACH, Band, interp_code, values_as_array
from .flow_methods import FlowMethods
from .level_set import extend_by_pde, reinitialized_psi, slope_at_surface
from .mesh_sdf import grid_for_mesh, load_mesh, mesh_to_sdf, rim_cells
from .shape_methods import ShapeMethods
from .storage import FLOW_STATES, make_flow

STORAGES = tuple(FLOW_STATES)  # "lists", "bricks"


class ImplicitSurface(FlowMethods, ShapeMethods):
    """A closed surface given as the zero level set of a signed distance function psi.

    Points of cell (k, j, i) are origin + h * (i, j, k). The flows on the surface are its
    methods, their only public form (flow_methods.py, shape_methods.py): `heat`, `tv`,
    `denoise_tv`, `diffuse_along`, `harmonic_map`, `denoise_colour`, `reaction_diffusion`,
    `stability_limit`, `principal_directions`, and `to_mesh` and `render` for pictures. They
    run on a narrow band around psi = 0. `from_mesh`, `from_volume`, `from_function`,
    `sphere`, `torus` and `double_torus` build a surface from other descriptions.

    Parameters
    ----------
    psi : array_like
        (nz, ny, nx) signed distance, negative inside, in world units.
    spacing : float
        The grid spacing h.
    origin : array_like, optional
        World (x, y, z) of psi[0, 0, 0].
    band_width : float, optional
        The outer band's half-width in cells (default: the narrowest the interpolation
        allows).
    interpolation : {'tricubic', 'trilinear'}, optional
        The closest-point interpolation of the re-extension.
    dtype : {float32, float64}, optional
        The device's arithmetic.
    device : str or int or Runtime, optional
        The OpenCL device, as for `clpde.use_device`.
    storage : {'lists', 'bricks'}, optional
        The flows' band storage (see `storage`): the same results.

    Raises
    ------
    InputError
        For a psi without a zero level set, non-finite values, a band too narrow for the
        interpolation or reaching the volume's border.

    Examples
    --------
    >>> s = ImplicitSurface.sphere(1.0, spacing=0.1)
    >>> s.shape, s.storage
    ((37, 37, 37), 'lists')
    """

    _check_border = True  # whether a new psi's band must be clear of the border (from_volume)

    def __init__(
        self,
        psi: ArrayLike,
        spacing: float,
        origin: ArrayLike = (0.0, 0.0, 0.0),
        *,
        band_width: float | None = None,
        interpolation: str = "tricubic",
        dtype: DTypeLike = np.float32,
        device: DeviceLike = None,
        storage: str = "lists",
    ):
        psi = np.asarray(psi)
        if psi.ndim != 3:
            raise InputError(f"psi must be a 3D (nz, ny, nx) volume, got shape {psi.shape}")
        if min(psi.shape) < 4:
            raise InputError(f"psi needs at least 4 cells along each axis, got {psi.shape}")
        if not np.issubdtype(psi.dtype, np.number) or np.iscomplexobj(psi):
            raise InputError(f"psi must hold real numbers, not {psi.dtype}")
        if not np.all(np.isfinite(psi)):
            raise InputError(
                "psi contains NaN or infinite values; fill them before building a surface"
            )
        if not (psi.min() < 0 < psi.max()):
            raise InputError(
                "psi has no zero level set (it never changes sign): no surface to work on"
            )
        self.spacing = _positive("spacing", spacing)
        origin = np.asarray(origin, dtype=np.float64).reshape(-1)
        if origin.shape != (3,) or not np.all(np.isfinite(origin)):
            raise InputError(f"origin must be three finite numbers (x, y, z), got {origin!r}")
        self.origin = origin
        self.interp = interp_code(interpolation)
        self.inner = NODE_REACH[self.interp] + 0.04
        min_outer = self.inner + np.sqrt(2.0) + 0.04
        self.outer = min_outer if band_width is None else _positive("band_width", band_width)
        if self.outer < min_outer:
            raise InputError(
                f"band_width={self.outer:g} cells is too narrow for {interpolation} re-extension; "
                f"use band_width >= {min_outer:.2f}"
            )
        self.runtime = get_runtime(device)
        # psi, psi in cells and the band masks at the least; the bands' lists come on top
        check_fits(self.runtime, (1,) + psi.shape, "the surface", 3, ghost=3, dtype=dtype)
        self.storage = storage
        self.grid = Grid3D(
            self.runtime, psi.shape[2], psi.shape[1], psi.shape[0], ghost=3, dtype=np.dtype(dtype)
        )
        self._set_psi(psi.astype(np.float64, copy=True))

    @property
    def storage(self) -> str:
        """Where the flows keep their data on the device: "lists" (the default), dense volumes
        stepped over band lists, or "bricks", only the band's 8^3 bricks (bricks.py). Every
        flow runs in both, through the same per-cell code (kernels/surface/flux.h), with the
        same results; which is faster and how much memory each takes depends on the grid's
        size (docs/surface_storage.md has the measurements)."""
        return self._storage

    @storage.setter
    def storage(self, value: str) -> None:
        FLOW_STATES.choose(value)
        self._storage = value

    def _set_psi(self, psi: np.ndarray) -> None:
        """(Re)build the device copy of psi, the two bands and the closest points."""
        self.psi = psi
        # Ghost cells continue psi linearly so stencils next to the border stay meaningful.
        self.psi_dev = self.grid.upload(self.psi[None], mode="linear")
        # Band tests and closest points run in grid units.
        with self.runtime.lock:  # pyopencl's arithmetic kernels are shared by every thread
            psi_cells = self.psi_dev / self.grid.scalar(self.spacing)
        self.step_band = self.grid.band(psi_cells, self.inner)
        self.ext_band = self.grid.band(psi_cells, self.outer)
        if self._check_border:
            band_setup.check_band_clear_of_border(self)
        self.cp = band_setup.closest_points(self, self.ext_band)
        self.cp_base, self.cp_frac = band_setup.cp_stencils(self, self.ext_band, self.cp)
        band_setup.narrow_bands(self)
        self.band = Band(self)  # data on this psi's band (band.py)

    # ---- construction from shapes ----------------------------------------------------------
    @classmethod
    def from_volume(
        cls,
        psi: ArrayLike,
        spacing: float,
        origin: ArrayLike = (0.0, 0.0, 0.0),
        *,
        reinitialize: bool = False,
        **options: Any,
    ) -> ImplicitSurface:
        """A surface from a signed distance volume (nz, ny, nx) with the given spacing.

        reinitialize=True first turns any level-set function (negative inside) into a
        signed distance, on the device."""
        if reinitialize:
            psi = np.asarray(psi, dtype=np.float64)
            # rescale to unit slope at the surface first (the zero level set is kept), so
            # the bands are about right before the exact reinitialisation
            scale = slope_at_surface(psi, spacing) if psi.ndim == 3 else 1.0
            # a level-set function's band may reach the border until it is reinitialised:
            # the border is checked after that
            surf = cls.__new__(cls)
            surf._check_border = False
            surf.__init__(psi / scale, spacing, origin, **options)
            surf.reinitialize()
            band_setup.check_band_clear_of_border(surf)
            return surf
        return cls(psi, spacing, origin, **options)

    @classmethod
    def from_mesh(
        cls,
        mesh: object,
        spacing: float | None = None,
        resolution: int = 128,
        *,
        band_width: float | None = None,
        **options: Any,
    ) -> ImplicitSurface:
        """A surface from a triangle mesh (trimesh.Trimesh or any file trimesh loads).

        spacing defaults to the bounding box's longest side / resolution. The distance is exact
        in the band. The sign comes from a flood fill checked by the generalized winding number
        (see mesh_sdf): flipped faces, a mesh turned inside out and holes of any size are
        handled, a hole being closed along the sheet where the winding number crosses 1/2; the
        cells whose closest mesh point lies on a hole's rim are reinitialised, so psi is a
        distance across the sheet too. The mesh passed in is not modified; one that is not
        watertight gets a warning."""
        mesh = load_mesh(mesh)
        outer = band_width
        if outer is None:
            interp = interp_code(options.get("interpolation", "tricubic"))
            outer = NODE_REACH[interp] + np.sqrt(2.0) + 0.08
        padding = int(np.ceil(outer)) + 4
        origin, h, shape = grid_for_mesh(mesh, spacing, resolution, padding)
        stats = {}
        psi, face, cpoint = mesh_to_sdf(
            mesh, origin, h, shape, outer + 3.0, device=options.get("device"), stats=stats
        )
        surf = cls(psi, h, origin, band_width=band_width, **options)
        rim = rim_cells(mesh, face, cpoint, h) if stats.get("leaked") else ()
        if len(rim):
            # a closed hole: psi jumps across the sheet that closes it (|psi| is the distance
            # to the rim there), so normals, closest points and the signed-distance flows
            # (4.8) would be wrong near it; the cells whose closest point is on the rim take
            # a reinitialised distance, the others keep their exact one
            cap = np.abs(surf.psi).max()  # what cells past the band hold
            patched = surf.psi.copy()
            patched.reshape(-1)[rim] = np.clip(reinitialized_psi(surf).reshape(-1)[rim], -cap, cap)
            surf._set_psi(patched)
        surf.mesh = mesh
        surf._mesh_face = face
        surf._mesh_cp = cpoint
        return surf

    def field_from_mesh(self, values: ArrayLike) -> np.ndarray:
        """Data given at the vertices of the mesh this surface was built from (shape
        (vertices,) or (vertices, channels), e.g. colours), carried to the band: each cell
        takes the barycentric interpolation on its nearest triangle at its closest point.
        Returns (nz, ny, nx) or (channels, nz, ny, nx); zeros off the band."""
        from trimesh.triangles import points_to_barycentric

        mesh = getattr(self, "mesh", None)
        if mesh is None:
            raise InputError("this surface was not built from a mesh; use surf.field(f) instead")
        values = np.asarray(values, dtype=np.float64)
        if values.shape[0] != len(mesh.vertices):
            raise InputError(
                f"values must have one row per mesh vertex ({len(mesh.vertices)}), got "
                f"{values.shape}"
            )
        if not np.all(np.isfinite(values)):
            raise InputError("values contain NaN or infinite entries")
        flat_face = self._mesh_face.reshape(-1)
        cells = np.flatnonzero(flat_face >= 0)
        faces = flat_face[cells]
        # _mesh_cp holds the closest points of exactly these cells, in this order
        bary = points_to_barycentric(np.asarray(mesh.triangles)[faces], self._mesh_cp)
        # closest points lie on their triangles: the weights are convex but for rounding, and
        # clipping keeps e.g. colours within their range
        bary = np.clip(bary, 0, None)
        bary /= bary.sum(axis=1, keepdims=True)
        corner = np.asarray(mesh.faces)[faces]
        vals = values.reshape(len(values), -1)
        per_cell = np.einsum("ck,ckm->cm", bary, vals[corner])
        out = np.zeros((vals.shape[1], flat_face.size))
        out[:, cells] = per_cell.T
        out = out.reshape((vals.shape[1],) + self.shape)
        return out[0] if values.ndim == 1 else out

    @classmethod
    def from_function(
        cls, sdf: Callable, bounds: tuple[ArrayLike, ArrayLike], spacing: float, **options: Any
    ) -> ImplicitSurface:
        """Sample a signed distance function sdf(x, y, z) on a box bounds = (lo, hi),
        padded by the band width plus interpolation room on every side."""
        h = _positive("spacing", spacing)
        lo, hi = (np.asarray(b, dtype=np.float64) for b in bounds)
        margin = (options.get("band_width") or options.get("band") or 5.0) + 3.0
        lo = lo - margin * h
        hi = hi + margin * h
        n = np.ceil((hi - lo) / h).astype(int) + 1
        x = lo[0] + h * np.arange(n[0])
        y = lo[1] + h * np.arange(n[1])
        z = lo[2] + h * np.arange(n[2])
        psi = sdf(x[None, None, :], y[None, :, None], z[:, None, None])
        psi = np.broadcast_to(psi, (n[2], n[1], n[0]))
        return cls(psi, h, lo, **options)

    @classmethod
    def sphere(
        cls,
        radius: float = 1.0,
        spacing: float = 0.05,
        center: ArrayLike = (0.0, 0.0, 0.0),
        **options: Any,
    ) -> ImplicitSurface:
        """Sphere of the given radius around `center` (world x, y, z)."""
        r = _positive("radius", radius)
        c = np.asarray(center, dtype=np.float64)

        def sdf(x, y, z):
            return np.sqrt((x - c[0]) ** 2 + (y - c[1]) ** 2 + (z - c[2]) ** 2) - r

        return cls.from_function(sdf, (c - r, c + r), spacing, **options)

    @classmethod
    def torus(
        cls, major: float = 1.0, minor: float = 0.4, spacing: float = 0.05, **options: Any
    ) -> ImplicitSurface:
        """Torus around the z axis: tube radius `minor` at distance `major` from the axis."""
        big, small = _positive("major", major), _positive("minor", minor)
        if small >= big:
            raise InputError(f"minor radius {small} must be smaller than the major radius {big}")
        ext = np.array([big + small, big + small, small])
        return cls.from_function(_torus_sdf(big, small, 0.0), (-ext, ext), spacing, **options)

    @classmethod
    def double_torus(
        cls, major: float = 0.8, minor: float = 0.3, spacing: float = 0.05, **options: Any
    ) -> ImplicitSurface:
        """Genus-2 surface: the union of two overlapping tori side by side along x.

        min() of the two distances is exact outside and near the surface away from the seam
        where the tori merge; reinitialise for an exact distance there."""
        big, small = _positive("major", major), _positive("minor", minor)
        if small >= big:
            raise InputError(f"minor radius {small} must be smaller than the major radius {big}")
        shift = big + 0.5 * small
        left, right = _torus_sdf(big, small, -shift), _torus_sdf(big, small, shift)

        def sdf(x, y, z):
            return np.minimum(left(x, y, z), right(x, y, z))

        ext = np.array([shift + big + small, big + small, small])
        return cls.from_function(sdf, (-ext, ext), spacing, **options)

    # ---- geometry ----------------------------------------------------------------------------
    @property
    def shape(self) -> tuple[int, int, int]:
        """The grid's (nz, ny, nx): the shape of psi and of dense scalar data."""
        return self.psi.shape

    def coordinates(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """World coordinates x, y, z of the grid cells, broadcastable to `shape`."""
        nz, ny, nx = self.shape
        h, o = self.spacing, self.origin
        x = o[0] + h * np.arange(nx)
        y = o[1] + h * np.arange(ny)
        z = o[2] + h * np.arange(nz)
        return x[None, None, :], y[None, :, None], z[:, None, None]

    def closest_points_host(self):
        """World closest points x - psi grad psi / |grad psi| of every cell (numpy)."""
        g = np.gradient(self.psi, self.spacing)
        norm = np.sqrt(g[0] ** 2 + g[1] ** 2 + g[2] ** 2)
        norm[norm == 0] = 1.0
        x, y, z = self.coordinates()
        d = self.psi / norm
        return x - d * g[2], y - d * g[1], z - d * g[0]

    def reinitialize(
        self, iterations: int | None = None, progress: bool | None = None
    ) -> ImplicitSurface:
        """Turn psi into a signed distance function on the device (Sussman's PDE with
        Russo-Smereka's subcell fix), keeping its zero level set; rebuilds the bands."""
        self._set_psi(reinitialized_psi(self, iterations, progress))
        return self

    def extend(
        self, u: ArrayLike, method: str = "closest-point", iterations: int | None = None
    ) -> np.ndarray:
        """Extend data off the surface, constant along the normals: by closest-point
        interpolation (one pass), or by the upwind PDE of section 4.2,
        u_t + sign(psi) grad u . grad psi / |grad psi| = 0, run to steady state in the band."""
        if method not in ("closest-point", "pde"):
            raise InputError(f"method must be 'closest-point' or 'pde', not {method!r}")
        if method == "closest-point":
            return make_flow(self, u).result()
        return extend_by_pde(self, u, iterations)

    # ---- data on the surface -----------------------------------------------------------------
    def field(self, f: Callable, dtype: DTypeLike = np.float64) -> np.ndarray:
        """Data f(x, y, z) on the surface, extended constant along the normals.

        f is called once with broadcastable coordinate arrays of the cells' closest points;
        it returns an array (scalar data: result shape `shape`) or a sequence of arrays
        (vector data: result shape (channels,) + `shape`).
        """
        x, y, z = self.closest_points_host()
        return values_as_array(f(x, y, z), self.shape, dtype)

    # ---- the band form: data at the extension band's cells only ------------------------------
    def band_indices(self) -> np.ndarray:
        """Flat (C-order) indices into `shape` of the extension band's cells, increasing.

        They fix the *band form* of data on this surface: values at these cells only, shape
        (n,) for scalar data or (channels, n). The flows (heat, tv, denoise_tv), `extend` and
        `sample` take the band form in place of a dense volume and return it in kind, so a
        big grid (512^3) never needs a dense float64 copy of the data; `band_values` and
        `from_band` convert. Every value a flow reads lies on the band, so a flow's band-form
        result is its dense result at these cells, bitwise.

        >>> s = ImplicitSurface.sphere(1.0, spacing=0.1)
        >>> u = s.band_field(lambda x, y, z: z)
        >>> u.shape == s.band_indices().shape
        True
        >>> bool(np.allclose(s.heat(u, 0.01), s.band_values(s.heat(s.from_band(u), 0.01))))
        True
        """
        return self.band.cells()[0].copy()

    def band_coordinates(self) -> np.ndarray:
        """World (x, y, z) of the extension band's cells, shape (n, 3), in band-form order."""
        return self.band.coordinates()

    def band_closest_points(self) -> np.ndarray:
        """World closest points x - psi grad psi / |grad psi| of the extension band's cells,
        shape (n, 3) (central differences, as `closest_points_host`, at the band only)."""
        return self.band.closest_points()

    def band_field(self, f: Callable, dtype: DTypeLike = np.float64) -> np.ndarray:
        """`field` in band form: f(x, y, z) at the band cells' closest points (1D arrays),
        shape (n,) for an array result or (channels, n) for a sequence of them."""
        cp = self.band_closest_points()
        return values_as_array(f(cp[:, 0], cp[:, 1], cp[:, 2]), (cp.shape[0],), dtype)

    def band_values(self, u: ArrayLike) -> np.ndarray:
        """Dense data (`shape`, or (channels,) + `shape`) in band form: its values at the
        band's cells, dtype kept."""
        return self.band.values(np.asarray(u))

    def from_band(self, values: ArrayLike, fill: float = 0.0) -> np.ndarray:
        """Band-form values as a dense volume (`shape`, or (channels,) + `shape`), `fill` off
        the band, dtype kept (floats; others become float64)."""
        return self.band.dense(np.asarray(values), fill)

    def world_to_index(self, points: ArrayLike) -> np.ndarray:
        """(n, 3) world points to padded index coordinates (3, n)."""
        return _sampling.world_to_index(self, points)

    def sample(
        self, u: ArrayLike, points: ArrayLike, interpolation: str = "tricubic"
    ) -> np.ndarray:
        """Values of u at world points (n, 3): shape (n,) for scalar u, (n, channels) else.
        u may be dense or in band form (band_indices).

        Points must lie within the interpolation reach of the surface (on it, typically)."""
        return _sampling.sample(self, u, points, interpolation)


def _torus_sdf(big: float, small: float, shift: float):
    def sdf(x, y, z):
        ring = np.sqrt((x - shift) ** 2 + y**2) - big
        return np.sqrt(ring**2 + z**2) - small

    return sdf
