"""The surface's shape as ImplicitSurface's methods: its principal curvature directions, its
triangle mesh and pictures of data on it.

`ShapeMethods` is a base of ImplicitSurface, as `FlowMethods` (flow_methods.py) is: the
documented public form, calling the implementations in curvature.py and render.py.
"""

from __future__ import annotations

import os
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from . import curvature as _curvature
from . import render as _render

if TYPE_CHECKING:  # annotations only: trimesh is imported where a mesh is made
    import trimesh


class ShapeMethods:
    """The curvature directions, mesh and pictures of ImplicitSurface (its base class)."""

    def principal_directions(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Principal curvature directions and curvatures of the surface, extended along
        normals.

        Directions are defined up to sign, which the flows along them ignore (the flux
        (d.Pv)d is even in d); sample them at nodes rather than interpolating across sign
        flips.

        Returns
        -------
        major, minor : ndarray
            (3, nz, ny, nx) unit tangent fields (major = the larger curvature), computed at
            every cell of the extension band (constant along normals for a distance
            function); zeros off the band.
        curvatures : ndarray
            (2, nz, ny, nx): the larger and the smaller principal curvature.

        Examples
        --------
        >>> import numpy as np
        >>> from clpde.surface import ImplicitSurface
        >>> s = ImplicitSurface.sphere(1.0, spacing=0.1)
        >>> major, minor, curvatures = s.principal_directions()
        >>> on = np.abs(s.psi) < 0.05
        >>> bool(np.allclose(curvatures[:, on], 1.0, atol=0.1))   # a unit sphere: k1 = k2 = 1
        True
        """
        return _curvature.principal_directions(self)

    def to_mesh(
        self,
        u: ArrayLike | None = None,
        *,
        vmin: float | None = None,
        vmax: float | None = None,
        interpolation: str = "tricubic",
    ) -> trimesh.Trimesh:
        """The surface as a triangle mesh (marching cubes of psi = 0), coloured by u.

        Parameters
        ----------
        u : array_like, optional
            Data on the surface (dense or band form, scalar or 3-channel), sampled at the
            vertices: scalars are coloured through the colour ramp (`clpde.surface.colormap`)
            and kept in ``mesh.vertex_attributes['u']``; 3-channel data is RGB (clipped to
            [0, 1]), kept as 'u0', 'u1', 'u2'. None leaves the mesh uncoloured.
        vmin, vmax : float, optional
            The scalar values mapped to the ramp's ends (default: the sampled values' range).
        interpolation : {'tricubic', 'trilinear'}, optional
            How u is sampled at the vertices (`sample`).

        Returns
        -------
        trimesh.Trimesh
            The mesh, faces pointing out, in world coordinates (`clpde.surface.export_mesh`
            writes it, `clpde.surface.render_mesh` draws it).

        Raises
        ------
        InputError
            For data of another shape or with other than 1 or 3 channels.

        Examples
        --------
        >>> from clpde.surface import ImplicitSurface
        >>> s = ImplicitSurface.sphere(1.0, spacing=0.1)
        >>> mesh = s.to_mesh(s.field(lambda x, y, z: z))
        >>> mesh.is_watertight, mesh.vertex_attributes["u"].shape == (len(mesh.vertices),)
        (True, True)
        """
        return _render.to_mesh(self, u, vmin=vmin, vmax=vmax, interpolation=interpolation)

    def render(
        self,
        u: ArrayLike | None = None,
        path: str | os.PathLike | None = None,
        *,
        views: tuple[tuple[float, float], ...] = ((30.0, 20.0),),
        size: int = 512,
        vmin: float | None = None,
        vmax: float | None = None,
        colour_bar: bool = True,
    ) -> np.ndarray:
        """Picture(s) of data on the surface, side by side, written as PNG if a path is given.

        Parameters
        ----------
        u : array_like, optional
            Data on the surface, as for `to_mesh`.
        path : str or os.PathLike, optional
            A .png file to write the picture to, atomically.
        views : sequence of (float, float), optional
            (azimuth, elevation) pairs in degrees, one picture each, placed side by side.
        size : int, optional
            Each view's width and height in pixels.
        vmin, vmax : float, optional
            The scalar values mapped to the colour ramp's ends (default: the data's range).
        colour_bar : bool, optional
            Draw a colour bar with the value range below the views, for scalar data.

        Returns
        -------
        ndarray
            The (size [+ bar], size * len(views), 3) uint8 picture.

        Raises
        ------
        InputError
            For no views, a path not ending in .png, or data that `to_mesh` refuses.

        Examples
        --------
        >>> from clpde.surface import ImplicitSurface
        >>> s = ImplicitSurface.sphere(1.0, spacing=0.1)
        >>> picture = s.render(s.field(lambda x, y, z: z), views=[(30, 20), (210, 20)], size=64)
        >>> picture.shape[1:], picture.dtype
        ((128, 3), dtype('uint8'))
        """
        return _render.render(
            self,
            u,
            path,
            views=views,
            size=size,
            vmin=vmin,
            vmax=vmax,
            colour_bar=colour_bar,
        )
