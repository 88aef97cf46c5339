"""Harmonic maps of unit vectors on a surface (4.11, D.7), and the colour denoising built on
them (Figure 4.6): chroma by a harmonic map, brightness by a scalar flow."""

from __future__ import annotations

import warnings
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from ..errors import InputError
from .flows import heat, step_flow, tv

if TYPE_CHECKING:
    from .implicit import ImplicitSurface


def harmonic_map(
    surf: ImplicitSurface,
    u: ArrayLike,
    t: float,
    p: int = 2,
    dt: float | None = None,
    *,
    eps: float = 1.0,
    alternate: bool = True,
    progress: bool | None = None,
    line_field: bool = False,
) -> np.ndarray:
    """Harmonic map flow of unit vectors on the surface: (D.7) for p = 2, (4.11) for p = 1.

    The vectors are renormalised after every step, so they stay unit vectors.

    Parameters
    ----------
    surf : ImplicitSurface
        The surface.
    u : array_like
        Unit vectors on the surface: (channels, nz, ny, nx), or their band form (channels, n)
        (`surf.band_indices()`); returned in kind. Vectors off unit length are normalised,
        with a warning.
    t : float
        The evolution time (world units).
    p : {1, 2}, optional
        The exponent: 2 smooths as the heat flow does, 1 (the TV analogue) keeps edges.
    dt : float, optional
        The time step; 0.8 of `stability_limit` ('harmonic2' or 'harmonic1') by default.
    eps : float, optional
        Regularisation of the gradient's norm for p = 1, as for `tv`.
    alternate : bool, optional
        Cycle the one-sided differences, as for `heat`.
    progress : bool, optional
        Draw a progress bar; by default only for long runs on a terminal.
    line_field : bool, optional
        Treat u as a field of lines, u and -u alike (principal directions, Figure 4.5):
        before a step or an interpolation weighs neighbouring vectors, each is turned to the
        side of the vector it is compared with, so arbitrary sign flips between neighbours
        are neither smoothed into zero vectors nor counted as edges. This is the harmonic
        map into the projective plane, worked in local sign-aligned charts (the doubled-angle
        alternative needs a tangent frame, which has no smooth global choice on a sphere).
        The result's signs are arbitrary, consistent only locally.

    Returns
    -------
    ndarray
        The unit vectors after time t, in u's form.

    Raises
    ------
    InputError
        For p other than 1 or 2, data that is not vector data on the surface's grid or band,
        zero vectors in the band, or an unstable dt.

    Examples
    --------
    >>> import numpy as np
    >>> from clpde.surface import ImplicitSurface, harmonic_map
    >>> s = ImplicitSurface.sphere(1.0, spacing=0.2)
    >>> v = s.field(lambda x, y, z: (np.ones_like(x), 0.1 * y, 0.1 * z))
    >>> v /= np.sqrt((v**2).sum(axis=0))
    >>> w = harmonic_map(s, v, 0.01)
    >>> w.shape == v.shape
    True
    >>> band = np.abs(s.psi) < 0.1
    >>> bool(np.allclose((w**2).sum(axis=0)[band], 1.0, atol=1e-5))   # still unit vectors
    True
    """
    if p not in (1, 2):
        raise InputError(f"p must be 1 or 2, not {p!r}")
    data = np.asarray(u, dtype=np.float64)
    band_form = data.ndim == 2 and surf.band.form_channels(data) is not None
    if data.ndim != 4 and not band_form:
        raise InputError(
            "harmonic maps need vector data (channels, nz, ny, nx), or its band "
            f"form (channels, {surf.ext_band.n}), got shape {data.shape}"
        )
    norm = np.sqrt((data**2).sum(axis=0))
    norm = norm if band_form else norm[np.abs(surf.psi) < surf.outer * surf.spacing]
    if np.any(norm == 0):
        raise InputError("u has zero vectors in the band; harmonic maps need unit vectors")
    if np.abs(norm - 1).max() > 1e-3:
        warnings.warn("u is not made of unit vectors; normalising it", stacklevel=2)
    return step_flow(
        surf,
        u,
        t,
        dt,
        f"harmonic{p}",
        p=p,
        eps=eps,
        harmonic=True,
        alternate=alternate,
        progress=progress,
        line_field=line_field,
    )[0]


def denoise_colour(
    surf: ImplicitSurface,
    rgb: ArrayLike,
    t: float,
    dt: float | None = None,
    *,
    brightness: str = "tv",
    p: int = 1,
    eps: float = 1.0,
    alternate: bool = True,
    progress: bool | None = None,
) -> np.ndarray:
    """Colour data on the surface denoised as in Figure 4.6: chroma and brightness apart.

    The chroma (the RGB vector over its length, a unit vector) follows the harmonic map flow
    of exponent p, the brightness (the length) a scalar flow, both for time t. Cells with no
    colour (black) take the grey chroma, so they carry no direction.

    Parameters
    ----------
    surf : ImplicitSurface
        The surface.
    rgb : array_like
        (3, nz, ny, nx) colours, non-negative (e.g. in [0, 1]).
    t : float
        The evolution time of both flows (world units).
    dt : float, optional
        The time step; 0.8 of each flow's `stability_limit` by default.
    brightness : {'tv', 'heat', None}, optional
        The brightness's flow: 'tv' (4.10, the default: it keeps edges of brightness that
        heat blurs), 'heat' (4.8), or None to keep it.
    p : {1, 2}, optional
        The chroma's harmonic map exponent (1: (4.11), which keeps colour edges).
    eps : float, optional
        Regularisation of the gradient's norm of the p = 1 and TV flows.
    alternate : bool, optional
        Cycle the one-sided differences, as for `heat`.
    progress : bool, optional
        Draw a progress bar; by default only for long runs on a terminal.

    Returns
    -------
    ndarray
        The denoised (3, nz, ny, nx) colours, in rgb's float dtype (float64 for integers).

    Raises
    ------
    InputError
        For data of another shape, non-finite or negative values on the band, an unknown
        brightness flow or an unstable dt.

    Examples
    --------
    >>> import numpy as np
    >>> from clpde.surface import ImplicitSurface, denoise_colour
    >>> s = ImplicitSurface.sphere(1.0, spacing=0.2)
    >>> rgb = s.field(lambda x, y, z: (0.5 + 0.4 * x, 0.5 + 0.0 * y, 0.5 - 0.4 * z))
    >>> out = denoise_colour(s, rgb, 0.01)
    >>> out.shape == rgb.shape, out.dtype
    (True, dtype('float64'))
    """
    data = np.asarray(rgb)
    if data.shape != (3,) + surf.shape:
        raise InputError(
            f"rgb must have shape {(3,) + surf.shape} (channels first), got {data.shape}"
        )
    if brightness not in ("heat", "tv", None):
        raise InputError(f"brightness must be 'heat', 'tv' or None, not {brightness!r}")
    values = data.astype(np.float64)
    band = np.abs(surf.psi) < surf.outer * surf.spacing
    if not np.all(np.isfinite(values[:, band])):
        raise InputError("rgb has NaN or infinite values on the surface's band")
    if np.any(values[:, band] < 0):
        raise InputError(
            "rgb has negative values on the band; give colours as non-negative "
            "intensities (e.g. RGB in [0, 1])"
        )
    length = np.sqrt((values**2).sum(axis=0))
    lit = length > 1e-6 * max(float(length[band].max()), 1e-300)
    chroma = np.where(lit, values / np.where(lit, length, 1), 1 / np.sqrt(3.0))
    chroma = harmonic_map(surf, chroma, t, p, dt, eps=eps, alternate=alternate, progress=progress)
    if brightness == "heat":
        length = heat(surf, length, t, dt, alternate=alternate, progress=progress)
    elif brightness == "tv":
        length = tv(surf, length, t, dt, eps=eps, alternate=alternate, progress=progress)
    out = chroma * length
    return out.astype(data.dtype if np.issubdtype(data.dtype, np.floating) else np.float64)
