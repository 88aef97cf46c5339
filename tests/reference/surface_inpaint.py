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


def _central(f, cells, sx, sxy, half):
    s = 0.5 if half else 1.0
    return [s * (f[cells + e] - f[cells - e]) for e in (1, sx, sxy)]


def _tangential(v, n):
    s = v[0] * n[0] + v[1] * n[1] + v[2] * n[2]
    return [v[a] - s * n[a] for a in range(3)]


def _unit_normal(p, cells, sx, sxy):
    n = ref._normal(p, cells, sx, sxy)
    inv = 1 / np.sqrt(n[0] ** 2 + n[1] ** 2 + n[2] ** 2 + 1e-30)
    return [c * inv for c in n]


def transport_step(u_pad, lap_pad, psi_pad, nodes, dt, grad_eps2, min_slope2, bounds):
    """inpaint_transport_step at `nodes`: (new values, |change|), each (nc, n); no step where
    psi's central-difference gradient (times h) has a square below min_slope2; bounds (nc, 2)
    the range each channel is clamped to."""
    nc, _pz, py, px = u_pad.shape
    sx, sxy = px, px * py
    p = psi_pad.ravel().astype(np.float64)
    n = _unit_normal(p, nodes, sx, sxy)
    slope2 = sum(c**2 for c in ref._normal(p, nodes, sx, sxy))
    out, change = np.empty((nc, nodes.size)), np.empty((nc, nodes.size))
    for c in range(nc):
        f = u_pad[c].ravel().astype(np.float64)
        lap = lap_pad[c].ravel().astype(np.float64)
        g = _tangential(_central(f, nodes, sx, sxy, True), n)
        dl = _tangential(_central(lap, nodes, sx, sxy, False), n)
        t = np.cross(np.stack(n, 1), np.stack(g, 1))
        beta = (np.stack(dl, 1) * t).sum(1) / np.sqrt(g[0] ** 2 + g[1] ** 2 + g[2] ** 2 + grad_eps2)
        up = down = 0.0
        for e in (1, sx, sxy):
            back, fwd = f[nodes] - f[nodes - e], f[nodes + e] - f[nodes]
            up = up + np.minimum(back, 0) ** 2 + np.maximum(fwd, 0) ** 2
            down = down + np.maximum(back, 0) ** 2 + np.minimum(fwd, 0) ** 2
        step = dt * np.where(slope2 > min_slope2, beta * np.sqrt(np.where(beta > 0, up, down)), 0)
        out[c] = np.clip(f[nodes] + step, *bounds[c])
        change[c] = np.abs(out[c] - f[nodes])
    return out, change


def diffusion_step(u_pad, psi_pad, nodes, dt, e2):
    """inpaint_diffusion_step at `nodes`: u + dt |P grad u| div(P grad u / |P grad u|_e),
    the channels' joint gradient, the divergence the mean of the two one-sided choices."""
    nc, _pz, py, px = u_pad.shape
    sx, sxy = px, px * py
    u = u_pad.reshape(nc, -1).astype(np.float64)[:, nodes]
    fwd = ref.flow_step(u_pad, psi_pad, nodes, 1.0, 0.0, 0.0, e2, [1, sx, sxy], flow_p=1)
    bwd = ref.flow_step(u_pad, psi_pad, nodes, 1.0, 0.0, 0.0, e2, [-1, -sx, -sxy], flow_p=1)
    p = psi_pad.ravel().astype(np.float64)
    n = _unit_normal(p, nodes, sx, sxy)
    g2 = 0.0
    for c in range(nc):
        g = _tangential(_central(u_pad[c].ravel().astype(np.float64), nodes, sx, sxy, True), n)
        g2 = g2 + g[0] ** 2 + g[1] ** 2 + g[2] ** 2
    return u + dt * np.sqrt(g2) * 0.5 * ((fwd - u) + (bwd - u))
