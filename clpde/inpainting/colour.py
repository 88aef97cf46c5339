"""The luminance-chroma colour model of thesis Figure 3.7: (rho, sin phi, sin psi).

rho is the length of the (R, G, B) vector, psi its elevation towards the G axis and phi the
angle of its (R, B) projection:

    rho = sqrt(R^2 + G^2 + B^2),   sin psi = G / rho,   sin phi = R / sqrt(R^2 + B^2).

The inverse printed in the thesis (R = rho sqrt(1 - rho^2) sin phi) is garbled. From the
definitions, sqrt(R^2 + B^2) = sqrt(rho^2 - G^2) = rho cos psi, so

    G = rho sin psi,   R = rho cos psi sin phi,   B = rho cos psi cos phi,

with cos = sqrt(1 - sin^2), since R, G, B >= 0 puts both angles in [0, pi/2].
Black (rho = 0) and pure green (R = B = 0) have undefined angles; they get sin = 0 there,
which the inverse maps back to the same colour.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike


def rgb_to_rho_phi_psi(rgb: ArrayLike) -> np.ndarray:
    """(3, ...) non-negative R, G, B -> (3, ...) rho, sin phi, sin psi.

    Examples
    --------
    >>> import numpy as np
    >>> from clpde.inpainting.colour import rgb_to_rho_phi_psi
    >>> rho, sin_phi, sin_psi = rgb_to_rho_phi_psi(np.array([3.0, 0.0, 4.0]))
    >>> float(rho), float(sin_phi), float(sin_psi)
    (5.0, 0.6, 0.0)
    """
    r, g, b = (np.asarray(c, np.float64) for c in rgb)
    rho = np.sqrt(r * r + g * g + b * b)
    rb = np.sqrt(r * r + b * b)
    with np.errstate(invalid="ignore", divide="ignore"):
        sin_psi = np.where(rho > 0, g / np.where(rho > 0, rho, 1), 0.0)
        sin_phi = np.where(rb > 0, r / np.where(rb > 0, rb, 1), 0.0)
    return np.stack([rho, sin_phi, sin_psi])


def rho_phi_psi_to_rgb(model: ArrayLike) -> np.ndarray:
    """Inverse of rgb_to_rho_phi_psi. Values a flow pushed out of range are clipped first
    (rho >= 0, sines in [0, 1]) so the result is a valid colour.

    Examples
    --------
    >>> import numpy as np
    >>> from clpde.inpainting.colour import rgb_to_rho_phi_psi, rho_phi_psi_to_rgb
    >>> rgb = np.random.default_rng(0).random((3, 4, 5))
    >>> bool(np.allclose(rho_phi_psi_to_rgb(rgb_to_rho_phi_psi(rgb)), rgb))
    True
    """
    rho = np.maximum(np.asarray(model[0], np.float64), 0.0)
    sin_phi = np.clip(np.asarray(model[1], np.float64), 0.0, 1.0)
    sin_psi = np.clip(np.asarray(model[2], np.float64), 0.0, 1.0)
    cos_psi = np.sqrt(1.0 - sin_psi**2)
    cos_phi = np.sqrt(1.0 - sin_phi**2)
    return np.stack([rho * cos_psi * sin_phi, rho * sin_psi, rho * cos_psi * cos_phi])
