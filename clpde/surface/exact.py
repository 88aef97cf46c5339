"""Exact heat-flow solutions on the unit sphere, for checking surface flows.

On the unit sphere the spherical harmonics of degree l decay under the intrinsic heat flow
as exp(-l(l+1)t): u = xy (degree 2) decays as exp(-6t), and u = exp(3z), expanded in
Legendre polynomials of z, decays term by term.
"""

import numpy as np
from numpy.polynomial import legendre


def sphere_points(n: int = 1500) -> np.ndarray:
    """n quasi-uniform points on the unit sphere (a Fibonacci lattice), shape (n, 3)."""
    i = np.arange(n) + 0.5
    polar = np.arccos(1 - 2 * i / n)
    azimuth = np.pi * (1 + 5**0.5) * i
    return np.stack(
        [np.cos(azimuth) * np.sin(polar), np.sin(azimuth) * np.sin(polar), np.cos(polar)], 1
    )


def xy_exact(points: np.ndarray, t: float) -> np.ndarray:
    """Heat flow of u = xy on the unit sphere at time t, at (n, 3) points on it."""
    return np.exp(-6 * t) * points[:, 0] * points[:, 1]


def exp3z_exact(z: np.ndarray, t: float, degree: int = 40) -> np.ndarray:
    """Heat flow of u = exp(3z) on the unit sphere: sum a_l P_l(z) exp(-l(l+1)t)."""
    nodes, weights = legendre.leggauss(80)
    coef = np.array(
        [
            (2 * ell + 1)
            / 2
            * np.sum(weights * np.exp(3 * nodes) * legendre.legval(nodes, np.eye(degree)[ell]))
            for ell in range(degree)
        ]
    )
    decay = np.exp(-np.arange(degree) * (np.arange(degree) + 1) * t)
    return legendre.legval(z, coef * decay)
