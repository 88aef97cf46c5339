"""NumPy references of kernels/surface/inpaint.cl (inpainting on implicit surfaces): the same
discrete formulas, on padded volumes through flat indices (reference/surface.py's layout)."""

import numpy as np

from . import surface as ref


def laplace_beltrami(u_pad, psi_pad, cells):
    """Appendix E's intrinsic Laplacian (grid units) at `cells`, (nc, n): the mean of the
    forward-gradient/backward-divergence and the reverse choice."""
    _nc, _pz, py, px = u_pad.shape
    sx, sxy = px, px * py
    u = u_pad.reshape(u_pad.shape[0], -1)[:, cells]
    fwd = ref.heat_step(u_pad, psi_pad, cells, 1.0, [1, sx, sxy]) - u
    bwd = ref.heat_step(u_pad, psi_pad, cells, 1.0, [-1, -sx, -sxy]) - u
    return 0.5 * (fwd + bwd)


def harmonic_step(u_pad, prev_pad, psi_pad, nodes, mom, gain):
    """inpaint_harmonic_step at the hole's nodes: (new x, new prev, change), each (nc, n)."""
    flat = u_pad.reshape(u_pad.shape[0], -1)
    u = flat[:, nodes]
    moved = u - prev_pad.reshape(u_pad.shape[0], -1)[:, nodes]
    x = u + mom * moved + gain * laplace_beltrami(u_pad, psi_pad, nodes)
    return x, u, np.abs(moved)


def chebyshev_coefficients(a, b, steps):
    """(mom, gain) of each step of Chebyshev's semi-iterative method for a spectrum in
    [a, b] (clpde/surface/inpainting.py's recurrence)."""
    theta, delta = (b + a) / 2, (b - a) / 2
    sigma = theta / delta
    rho = 1 / sigma
    out = [(0.0, 1 / theta)]
    for _ in range(steps - 1):
        new = 1 / (2 * sigma - rho)
        out.append((new * rho, 2 * new / delta))
        rho = new
    return out


def harmonic_fill(u_pad, psi_pad, nodes, reach, reach_cp, ext, ext_cp, a, b, steps, order=3):
    """`steps` Chebyshev steps of the harmonic fill: the hole's nodes stepped, its reach cells
    re-extended from the node values (closest points reach_cp, padded index units), then its
    extension band cells (ext_cp). u_pad holds the known data and the start in the hole.
    Returns the padded volume after the fill."""
    nc = u_pad.shape[0]
    cur = u_pad.astype(np.float64).copy()
    x = cur.copy()
    prev = cur.copy()
    flat = lambda a_: a_.reshape(nc, -1)  # noqa: E731
    for mom, gain in chebyshev_coefficients(a, b, steps):
        new_x, new_prev, _ = harmonic_step(cur, prev, psi_pad, nodes, mom, gain)
        flat(x)[:, nodes] = new_x
        flat(prev)[:, nodes] = new_prev
        flat(cur)[:, reach] = ref.extend_cp(x, reach, reach_cp, order)
    flat(cur)[:, ext] = ref.extend_cp(x, ext, ext_cp, order)
    return cur
