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
    """Harmonic map flow of unit vectors (D.7 for p = 2, 4.11 for p = 1): the
    implementation of ImplicitSurface.harmonic_map, which documents the parameters."""
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
    """Colour denoising as in Figure 4.6, chroma by a harmonic map and brightness by a
    scalar flow: the implementation of ImplicitSurface.denoise_colour, which documents the
    parameters."""
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
