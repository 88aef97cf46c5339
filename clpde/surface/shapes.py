"""Sample surfaces and the data thesis chapter 4's figures put on them, built from formulas
(nothing is downloaded): `surface_shape` (a sphere, torus or double torus), `checker`,
`colour_pattern` and `surface_noise`. `clpde surface FLOW SHAPE` and the examples run on
them. (They lived in clpde.data, which is on the ground floor and imports no capability.)
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from ..runtime import DeviceLike
from .implicit import ImplicitSurface

SURFACE_SHAPES = ("sphere", "torus", "double-torus")


def surface_shape(name: str, resolution: int = 96, device: DeviceLike = None) -> ImplicitSurface:
    """A generated shape as an ImplicitSurface: a unit sphere, a torus of radii 1 and 0.4,
    or a double torus.

    Parameters
    ----------
    name : str
        One of SURFACE_SHAPES: "sphere", "torus" or "double-torus".
    resolution : int
        About how many grid cells across the shape.
    device : str, int, Runtime or None
        The OpenCL device, as for :func:`clpde.use_device`.

    Returns
    -------
    ImplicitSurface

    Examples
    --------
    >>> from clpde.surface import surface_shape
    >>> surf = surface_shape("sphere", resolution=24)
    >>> surf.spacing
    0.08333333333333333
    """
    if name not in SURFACE_SHAPES:
        raise InputError(f"shape must be one of {', '.join(SURFACE_SHAPES)}, not {name!r}")
    spacing = {"sphere": 2.0, "torus": 2.8, "double-torus": 4.2}[name] / resolution
    if name == "sphere":
        return ImplicitSurface.sphere(1.0, spacing, device=device)
    if name == "torus":
        return ImplicitSurface.torus(1.0, 0.4, spacing=spacing, device=device)
    return ImplicitSurface.double_torus(spacing=spacing, device=device)


def checker(surf: ImplicitSurface, cells: int = 6) -> np.ndarray:
    """A 3D checkerboard of 0 and 1 seen on the surface (the data of thesis Figures 4.3
    and 4.4).

    Parameters
    ----------
    surf : ImplicitSurface
        The surface whose grid the data is on.
    cells : int
        Squares across the grid's largest extent; each is about 1/cells of it.

    Returns
    -------
    ndarray
        Of shape surf.shape, values 0 and 1.

    Examples
    --------
    >>> from clpde.surface import checker, surface_shape
    >>> u = checker(surface_shape("sphere", resolution=24))
    >>> float(u.min()), float(u.max())
    (0.0, 1.0)
    """
    lo = surf.origin
    hi = surf.origin + surf.spacing * (np.array(surf.shape[::-1]) - 1)
    k = np.pi * cells / (hi - lo).max()
    return surf.field(
        lambda x, y, z: 0.5 + 0.5 * np.sign(np.sin(k * x) * np.sin(k * y) * np.sin(k * z))
    )


def colour_pattern(surf: ImplicitSurface) -> np.ndarray:
    """RGB stripes and blobs in [0.1, 0.9] on the surface (the data of thesis Figure 4.6).

    Parameters
    ----------
    surf : ImplicitSurface
        The surface whose grid the data is on.

    Returns
    -------
    ndarray
        Of shape (3,) + surf.shape.

    Examples
    --------
    >>> from clpde.surface import colour_pattern, surface_shape
    >>> surf = surface_shape("sphere", resolution=24)
    >>> rgb = colour_pattern(surf)
    >>> rgb.shape == (3,) + surf.shape, bool(0.1 - 1e-9 <= rgb.min() and rgb.max() <= 0.9 + 1e-9)
    (True, True)
    """
    size = surf.spacing * max(surf.shape)
    k = 2 * np.pi * 3 / size

    def f(x, y, z):
        r = 0.5 + 0.4 * np.sign(np.sin(k * x))
        g = 0.5 + 0.4 * np.cos(k * (y + z))
        b = 0.5 + 0.4 * np.sin(0.7 * k * (x - z))
        return [r, g, b]

    return surf.field(f)


def surface_noise(
    surf: ImplicitSurface, sigma: float, rng: np.random.Generator, channels: int | None = None
) -> np.ndarray:
    """Gaussian noise of standard deviation sigma on the surface, constant along its normals.

    Independent values per grid cell would not do: data on a surface is its values at the
    closest points, interpolated from several cells, which averages cell noise down (to
    about half its variance with tricubic interpolation), so a flow told the noise is sigma
    would remove more than the noise. Here the cell noise is extended from the closest
    points and rescaled so that what a flow sees of it (its own extension of the data)
    has deviation sigma on the cells nearest the surface.

    Parameters
    ----------
    surf : ImplicitSurface
        The surface whose grid the noise is on.
    sigma : float
        The noise's standard deviation on the surface.
    rng : numpy.random.Generator
        The source of the noise.
    channels : int or None
        None for one channel, else that many independent channels.

    Returns
    -------
    ndarray
        Of shape surf.shape, or (channels,) + surf.shape.

    Examples
    --------
    >>> import numpy as np
    >>> from clpde.surface import surface_noise, surface_shape
    >>> surf = surface_shape("sphere", resolution=24)
    >>> noise = surface_noise(surf, 0.1, np.random.default_rng(0))
    >>> noise.shape == surf.shape
    True
    """
    shape = surf.shape if channels is None else (channels,) + surf.shape
    noise = surf.extend(rng.standard_normal(shape))
    near = np.abs(surf.psi) < 0.5 * surf.spacing
    return noise * (sigma / surf.extend(noise)[..., near].std())
