"""NumPy reference of kernels/tracking/adaptive.cl (morph_adaptive): the same discrete formulas
on padded arrays (tests/reference/levelset.py's conventions: two ghost cells)."""

import numpy as np

from .levelset import G, _view, upwind_norm


def adaptive_beta(pf1, pf2, delta, noise2, win=3):
    """w beta_ncc + (1 - w) (F2 - F1) on the interior, w = min(var1, var2) /
    (min(var1, var2) + noise2), the variances over (2 win + 1)^2 windows."""
    f1, f2 = _view(pf1, 0, 0), _view(pf2, 0, 0)
    q1, q2 = (np.pad(p, win, mode="edge") for p in (pf1, pf2))
    ny, nx = f1.shape
    o = G + win
    sums = np.zeros((5,) + f1.shape)
    for dy in range(-win, win + 1):
        for dx in range(-win, win + 1):
            a = q1[o + dy : o + dy + ny, o + dx : o + dx + nx]
            b = q2[o + dy : o + dy + ny, o + dx : o + dx + nx]
            sums += np.array([a, b, a * a, b * b, a * b])
    n = (2 * win + 1) ** 2
    m1, m2 = sums[0] / n, sums[1] / n
    c1 = np.maximum(sums[2] / n - m1**2, 0)
    c2 = np.maximum(sums[3] / n - m2**2, 0)
    v1, v2 = c1 + delta**2, c2 + delta**2
    rho = (sums[4] / n - m1 * m2) / np.sqrt(v1 * v2)
    ncc = np.sqrt(v1 / v2) * (f2 - m2) - rho * (f1 - m1)
    s = np.minimum(c1, c2)
    w = s / (s + noise2)
    return w * ncc + (1 - w) * (f2 - f1)


def morph_adaptive(
    pu,
    pf1,
    pf2,
    band,
    prior,
    region,
    dt,
    eps_f,
    eps_u,
    near,
    lam,
    delta,
    noise2,
    mu,
    kd=1.0,
    win=3,
    front_only=True,
):
    """One step over C channels: pf1, pf2 (C, ny+4, nx+4), region (ny, nx) interior values;
    returns (u_new, f1_new (C, ny, nx), (max |du/dt| where |u| < 1 (front_only) or over the
    band, max(|beta|, |S|), max |grad F1|), mean over band cells of the channels' mean
    |beta|, hit)."""
    u = _view(pu, 0, 0)
    ux = 0.5 * (_view(pu, 0, 1) - _view(pu, 0, -1))
    uy = 0.5 * (_view(pu, 1, 0) - _view(pu, -1, 0))
    proj, gsum, babs = np.zeros_like(u), np.zeros_like(u), np.zeros_like(u)
    f1_new, betas, grads = [], [], []
    for p1, p2 in zip(pf1, pf2, strict=True):
        beta = adaptive_beta(p1, p2, delta, noise2, win)
        grad_f = upwind_norm(p1, beta)
        f1_new.append(_view(p1, 0, 0) + dt * beta * grad_f)
        fx = 0.5 * (_view(p1, 0, 1) - _view(p1, 0, -1))
        fy = 0.5 * (_view(p1, 1, 0) - _view(p1, -1, 0))
        proj += beta * (fx * ux + fy * uy)
        gsum += fx**2 + fy**2
        babs += np.abs(beta)
        betas.append(np.abs(beta))
        grads.append(grad_f)
    g2 = ux**2 + uy**2
    speed = kd * proj / np.sqrt((gsum + eps_f**2) * (g2 + eps_u**2)) + region
    uxx = _view(pu, 0, 1) - 2 * u + _view(pu, 0, -1)
    uyy = _view(pu, 1, 0) - 2 * u + _view(pu, -1, 0)
    uxy = 0.25 * (_view(pu, 1, 1) - _view(pu, 1, -1) - _view(pu, -1, 1) + _view(pu, -1, -1))
    curv = (uxx * uy**2 - 2 * ux * uy * uxy + uyy * ux**2) / (g2 + eps_u**2)
    rate = speed * upwind_norm(pu, speed) + mu * curv + lam * (_view(prior, 0, 0) - u)
    u_new = u + dt * rate
    inside = band > 0
    hit = bool(np.any((band == 2) & (np.abs(u_new) < near)))
    beta_max = max(float(np.max([b[inside] for b in betas])), float(np.abs(speed[inside]).max()))
    front = inside & (np.abs(u) < 1) if front_only else inside
    maxima = (
        float(np.abs(rate[front]).max()) if front.any() else 0.0,
        beta_max,
        float(np.max([g[inside] for g in grads])),
    )
    mean_beta = float((babs / len(pf1))[inside].mean())
    f1_new = np.array(
        [np.where(inside, f, _view(p1, 0, 0)) for f, p1 in zip(f1_new, pf1, strict=True)]
    )
    return np.where(inside, u_new, u), f1_new, maxima, mean_beta, hit
