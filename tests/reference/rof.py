"""NumPy references of the ROF kernels (kernels/planar/rof.cl), the same discrete formulas.

Padded layout as in planar.py: f is (nc, ny + 2, nx + 2) with mirrored ghosts; the dual field
p is (nc, ny + 2, nx + 2, 2) with (px, py) interleaved, ghosts as rof.cl keeps them.

Besides the kernel-by-kernel references, `fgp` is the textbook algorithm on unpadded arrays
(forward-difference gradient that is zero across the border, div its negative adjoint), which
the device iterates must reproduce: that checks the reflected-ghost trick of rof.cl.

The gradient-descent kernels (rof_step, rof_lambda_rows/finish in planar.cl) have their
references in planar.py, re-exported here.
"""

import numpy as np

from .planar import pad_neumann, rof_lambda, rof_step  # noqa: F401  (re-exported)


def _q(p, p_old, beta):
    return p + beta * (p - p_old)


def dual_step(p, p_old, f, lam, beta):
    """rof_dual_step: the new padded dual field (untouched ghosts zero, as the kernel's)."""
    q = _q(p, p_old, beta)
    qx, qy = q[..., 0], q[..., 1]
    lam = np.asarray(lam, float)[:, None, None]
    # div q on the padded grid wherever its backward neighbours exist (rows/cols >= 1)
    div = np.zeros_like(qx)
    div[:, 1:, 1:] = qx[:, 1:, 1:] - qx[:, 1:, :-1] + qy[:, 1:, 1:] - qy[:, :-1, 1:]
    w = lam * f + div
    c = (slice(None), slice(1, -1), slice(1, -1))
    ax = qx[c] + 0.125 * (w[:, 1:-1, 2:] - w[c])
    ay = qy[c] + 0.125 * (w[:, 2:, 1:-1] - w[c])
    norm2 = ax * ax + ay * ay
    shrink = np.where(norm2 > 1, 1 / np.sqrt(np.maximum(norm2, 1e-300)), 1.0)
    new = np.zeros_like(p)
    new[:, 1:-1, 1:-1, 0] = ax * shrink
    new[:, 1:-1, 1:-1, 1] = ay * shrink
    nx, ny = ax.shape[2], ax.shape[1]
    # reflected ghosts: right column and bottom row
    if nx >= 2:
        new[:, 1:-1, nx + 1, 0] = -new[:, 1:-1, nx - 1, 0]
    new[:, 1:-1, nx + 1, 1] = new[:, 1:-1, nx, 1]
    new[:, ny + 1, 1:-1, 0] = new[:, ny, 1:-1, 0]
    if ny >= 2:
        new[:, ny + 1, 1:-1, 1] = -new[:, ny - 1, 1:-1, 1]
    return new


def dual_step_vec(p, p_old, f, lam, beta):
    """rof_dual_step_vec: dual_step's unprojected step, projected per cell onto the unit
    ball of all channels' (px, py) together; lam is the shared lambda."""
    q = _q(p, p_old, beta)
    qx, qy = q[..., 0], q[..., 1]
    div = np.zeros_like(qx)
    div[:, 1:, 1:] = qx[:, 1:, 1:] - qx[:, 1:, :-1] + qy[:, 1:, 1:] - qy[:, :-1, 1:]
    w = lam * f + div
    c = (slice(None), slice(1, -1), slice(1, -1))
    ax = qx[c] + 0.125 * (w[:, 1:-1, 2:] - w[c])
    ay = qy[c] + 0.125 * (w[:, 2:, 1:-1] - w[c])
    norm2 = (ax * ax + ay * ay).sum(axis=0)
    shrink = 1 / np.sqrt(np.maximum(norm2, 1.0))
    new = np.zeros_like(p)
    new[:, 1:-1, 1:-1, 0] = ax * shrink
    new[:, 1:-1, 1:-1, 1] = ay * shrink
    ny, nx = ax.shape[1], ax.shape[2]
    if nx >= 2:
        new[:, 1:-1, nx + 1, 0] = -new[:, 1:-1, nx - 1, 0]
    new[:, 1:-1, nx + 1, 1] = new[:, 1:-1, nx, 1]
    new[:, ny + 1, 1:-1, 0] = new[:, ny, 1:-1, 0]
    if ny >= 2:
        new[:, ny + 1, 1:-1, 1] = -new[:, ny - 1, 1:-1, 1]
    return new


def dual_lambda_vec(sums_dd, lam, n, sigma2, lam_min):
    """rof_dual_lambda_vec: the shared lambda from the channels' summed (div p)^2, sigma2
    the channels' mean noise variance."""
    return max(lam_min, float(np.sum(sums_dd)) / (lam * n * len(sums_dd) * sigma2))


def dual_rows(p, f, lam, u_before):
    """rof_dual_rows: (u interior (nc, ny, nx), sums (nc, 4)): sum (div p)^2,
    sum (u - u_before)^2, sum u^2 and max |u - u_before|, with u = f + div(p) / lambda."""
    px, py = p[..., 0], p[..., 1]
    div = px[:, 1:-1, 1:-1] - px[:, 1:-1, :-2] + py[:, 1:-1, 1:-1] - py[:, :-2, 1:-1]
    lam = np.asarray(lam, float)[:, None, None]
    u = f[:, 1:-1, 1:-1] + div / lam
    sums = np.stack(
        [
            (div**2).sum(axis=(1, 2)),
            ((u - u_before) ** 2).sum(axis=(1, 2)),
            (u**2).sum(axis=(1, 2)),
            np.abs(u - u_before).max(axis=(1, 2)),
        ],
        axis=1,
    )
    return u, sums


def dual_lambda(sum_dd, lam, n, sigma2, lam_min):
    """rof_dual_lambda: lambda_new = sum (div p)^2 / (lambda N sigma^2), at least lam_min;
    channels with sigma2 = inf (inv_n_sigma2 = 0) keep their lambda."""
    sigma2 = np.asarray(sigma2, float)
    new = np.maximum(lam_min, np.asarray(sum_dd) / (np.asarray(lam) * n * sigma2))
    return np.where(np.isinf(sigma2), lam, new)


# ---- the textbook algorithm, for comparison with whole device runs ---------------------
def grad(u):
    gx, gy = np.zeros_like(u), np.zeros_like(u)
    gx[..., :, :-1] = u[..., :, 1:] - u[..., :, :-1]
    gy[..., :-1, :] = u[..., 1:, :] - u[..., :-1, :]
    return gx, gy


def div(px, py):
    """Negative adjoint of grad: sum(div(p) * u) = -sum(p . grad u)."""
    d = np.zeros_like(px)
    d[..., :, :-1] += px[..., :, :-1]
    d[..., :, 1:] -= px[..., :, :-1]
    d[..., :-1, :] += py[..., :-1, :]
    d[..., 1:, :] -= py[..., :-1, :]
    return d


def fgp(f, lam, iterations):
    """Fast projected gradient on the dual of min TV(u) + lam/2 |u - f|^2 (2-D f)."""
    px, py = np.zeros_like(f), np.zeros_like(f)
    px_old, py_old = px.copy(), py.copy()
    t, beta = 1.0, 0.0
    for _ in range(iterations):
        qx, qy = px + beta * (px - px_old), py + beta * (py - py_old)
        gx, gy = grad(lam * f + div(qx, qy))
        ax, ay = qx + gx / 8, qy + gy / 8
        shrink = 1 / np.maximum(1, np.sqrt(ax * ax + ay * ay))
        px_old, py_old, px, py = px, py, ax * shrink, ay * shrink
        t_next = 0.5 * (1 + np.sqrt(1 + 4 * t * t))
        beta, t = (t - 1) / t_next, t_next
    return f + div(px, py) / lam


def rof_energy(u, f, lam):
    """Isotropic TV(u) + lam/2 |u - f|^2 with the same discrete gradient."""
    gx, gy = grad(u)
    return np.sqrt(gx * gx + gy * gy).sum() + 0.5 * lam * ((u - f) ** 2).sum()


def fgp_vec(f, lam, iterations):
    """fgp for colour-coupled TV: f is (nc, ny, nx), the projection is onto the unit ball
    of all channels' dual vectors at each pixel."""
    px, py = np.zeros_like(f), np.zeros_like(f)
    px_old, py_old = px.copy(), py.copy()
    t, beta = 1.0, 0.0
    for _ in range(iterations):
        qx, qy = px + beta * (px - px_old), py + beta * (py - py_old)
        gx, gy = grad(lam * f + div(qx, qy))
        ax, ay = qx + gx / 8, qy + gy / 8
        shrink = 1 / np.maximum(1, np.sqrt((ax * ax + ay * ay).sum(axis=0)))
        px_old, py_old, px, py = px, py, ax * shrink, ay * shrink
        t_next = 0.5 * (1 + np.sqrt(1 + 4 * t * t))
        beta, t = (t - 1) / t_next, t_next
    return f + div(px, py) / lam
