"""Numpy twin of kernels/inpainting/spectral.cl and of the plan in
clpde/inpainting/spectral_plan.py: the same frequency-selective fill, written plainly (loops
over blocks, numpy's FFT for the transforms, a Python loop for the greedy picks), in
float64."""

import numpy as np


def fit_block(
    values,
    weight,
    *,
    iterations,
    gamma,
    alpha,
    stop,
    detrend=True,
    cutoff=1.5,
    floor=0.0,
    stall=0.0,
    record=None,
):
    """The model of one window: values and weight (L, L) -> the model's (L, L) values.
    record(gain, energy, model), if given, sees the plane (gain None) and each pick's gain,
    the residual before it and the model after it (benchmarks/inpaint_spectral_stall.py)."""
    L = values.shape[0]
    centre = (L - 1) / 2
    u, v = np.mgrid[0:L, 0:L]
    u, v = (u - centre) / L, (v - centre) / L
    plane = np.zeros((L, L))
    total = weight.sum()
    if detrend and total > 0:
        basis = np.stack([np.ones_like(u), u, v]).reshape(3, -1)
        wb = basis * weight.ravel()
        a = wb @ basis.T + np.diag([0, 1e-3 * total, 1e-3 * total])
        coef = np.linalg.solve(a, wb @ values.ravel())
        plane = (coef @ basis).reshape(L, L)
    energy = float((weight * (values - plane) ** 2).sum())  # the weighted squared error
    R = np.fft.fft2(weight * (values - plane))  # sum w f exp(-2 pi i k.x / L), [ky, kx]
    W = np.fft.fft2(weight)
    W0 = W[0, 0].real
    model = plane.copy()
    if record is not None:
        record(None, energy, model)
    if W0 <= 0:
        return model
    H = L // 2 + 1
    ky, kx = np.meshgrid(np.arange(L), np.arange(H), indexing="ij")
    fy = np.where(ky <= L // 2, ky, ky - L)
    nu = np.minimum(np.sqrt(fy**2 + kx**2) / (0.5 * L * np.sqrt(2)), 1.0)
    prior = (1 - nu) ** alpha
    candidate = fy**2 + kx**2 <= (cutoff * 0.5 * L) ** 2
    self_conj = ((2 * ky) % L == 0) & ((2 * kx) % L == 0)
    V = W[(2 * ky) % L, (2 * kx) % L]
    den = np.maximum(W0**2 - np.abs(V) ** 2, 1e-3 * W0**2)
    m, n = np.mgrid[0:L, 0:L]
    first = None
    for _ in range(iterations):
        r = R[:, :H]
        c_pair = (r * W0 - V * np.conj(r)) / den
        gain = np.where(self_conj, r.real**2 / W0, 2 * (np.conj(c_pair) * r).real)
        # the first of equal scores in the kernel's order, column by column (kx, then ky)
        j = int(np.argmax(np.where(candidate, gain * prior, -np.inf).T.ravel()))
        b, a = divmod(j, L)
        g = gain[a, b]
        if first is None:
            first = g
        if (
            not g > 0
            or g < stop * first
            or (floor > 0 and energy <= floor**2 * W0)
            or g < stall * energy
        ):
            break
        before = energy
        energy -= gamma * (2 - gamma) * g  # a step gamma along the pair's best coefficient
        phase = np.exp(2j * np.pi * (a * m + b * n) / L)
        if self_conj[a, b]:
            c = gamma * r[a, b].real / W0
            model += c * phase.real
            R -= c * np.roll(W, (a, b), (0, 1))
        else:
            c = gamma * c_pair[a, b]
            model += 2 * (c * phase).real
            R -= c * np.roll(W, (a, b), (0, 1)) + np.conj(c) * np.roll(W, (-a, -b), (0, 1))
        if record is not None:
            record(g, before, model)
    return model


def plan(omega, *, block, min_block, border, split, delta, shift=(0, 0)):
    """(crop, blocks [(row, col, B)], waves [[block index, ...]], wave_of): as the host's
    plan, written with loops."""
    ny, nx = omega.shape
    rows, cols = np.flatnonzero(omega.any(1)), np.flatnonzero(omega.any(0))
    gy0, gx0 = rows[0] - shift[0], cols[0] - shift[1]
    gy = -(-(rows[-1] + 1 - gy0) // block)
    gx = -(-(cols[-1] + 1 - gx0) // block)
    cy0, cx0 = max(0, gy0 - border), max(0, gx0 - border)
    cy1, cx1 = min(ny, gy0 + gy * block + border), min(nx, gx0 + gx * block + border)
    hole = omega[cy0:cy1, cx0:cx1]
    oy, ox = gy0 - cy0, gx0 - cx0
    h, w = hole.shape

    def window_sum(weight, y, x, s):
        ya, yb = max(0, y - border), min(h, y + s + border)
        xa, xb = max(0, x - border), min(w, x + s + border)
        return weight[ya:yb, xa:xb].sum() if ya < yb and xa < xb else 0.0

    known = (~hole).astype(float)
    blocks = []
    todo = [(oy + i * block, ox + j * block, block) for i in range(gy) for j in range(gx)]
    while todo:
        nxt = []
        for y, x, s in todo:
            if not hole[max(y, 0) : max(y + s, 0), max(x, 0) : max(x + s, 0)].any():
                continue
            if window_sum(known, y, x, s) / (s + 2 * border) ** 2 < split and s > min_block:
                s2 = s // 2
                nxt += [(y, x, s2), (y, x + s2, s2), (y + s2, x, s2), (y + s2, x + s2, s2)]
            else:
                blocks.append((y, x, s))
        todo = nxt
    filled = np.zeros(hole.shape)
    wave_of = np.where(hole, -2, -1)
    pending = set(range(len(blocks)))
    waves = []

    def conflict(i, j):
        (ya, xa, sa), (yb, xb, sb) = blocks[i], blocks[j]
        return (
            ya - border < yb + sb
            and yb < ya + sa + border
            and xa - border < xb + sb
            and xb < xa + sa + border
        )

    while pending:
        # counts kept apart, so that equal scores stay equal in floating point
        score = {
            i: (window_sum(known, *blocks[i]) + delta * window_sum(filled, *blocks[i]))
            / (blocks[i][2] + 2 * border) ** 2
            for i in pending
        }
        best = max(score.values())
        key = {i: (score[i], -i) for i in pending}
        chosen = [
            i
            for i in sorted(pending)
            if (score[i] > 0 or best <= 0)
            and all(key[i] > key[j] for j in pending if j != i and conflict(i, j))
        ]
        # the host orders a wave's blocks by rank; the result does not depend on it
        wave = len(waves)
        for i in chosen:
            y, x, s = blocks[i]
            inner = (slice(max(y, 0), max(y + s, 0)), slice(max(x, 0), max(x + s, 0)))
            fresh = wave_of[inner] == -2
            wave_of[inner][fresh] = wave
            filled[inner][fresh] = 1
        waves.append(chosen)
        pending -= set(chosen)
    return (cy0, cy1, cx0, cx1), blocks, waves, wave_of


def fill(
    data,
    omega,
    *,
    block=8,
    min_block=4,
    border=12,
    split=0.3,
    rho=0.6,
    delta=1.0,
    gamma=0.7,
    alpha=2.0,
    iterations=100,
    stop=0.0,
    floor=0.0,
    stall=0.005,
    colour="pca",
    detrend=True,
    shifts=2,
    cutoff=1.5,
    per_pixel=0.0,
    minor=0.3,
):
    """The whole fill of (channels, rows, cols) float data, float64: every block grid's fill
    on its own, then their average."""
    out = np.array(data, np.float64)
    h2 = block // 2
    offsets = {1: [(0, 0)], 2: [(0, 0), (h2, h2)], 4: [(0, 0), (0, h2), (h2, 0), (h2, h2)]}
    plans = [
        plan(
            omega,
            block=block,
            min_block=min_block,
            border=border,
            split=split,
            delta=delta,
            shift=sh,
        )
        for sh in offsets[shifts]
    ]
    y0 = min(p[0][0] for p in plans)
    y1 = max(p[0][1] for p in plans)
    x0 = min(p[0][2] for p in plans)
    x1 = max(p[0][3] for p in plans)
    part = out[:, y0:y1, x0:x1]
    hole = omega[y0:y1, x0:x1]
    nc = part.shape[0]
    if colour == "pca" and nc > 1:
        values = part[:, ~hole]
        mean = values.mean(1)
        _, vecs = np.linalg.eigh(np.atleast_2d(np.cov(values)))
        axes = vecs[:, ::-1].T
    else:
        mean, axes = np.zeros(nc), np.eye(nc)
    start = np.einsum("ij,jyx->iyx", axes, part - mean[:, None, None])
    start[:, hole] = 0
    h, w = hole.shape
    fills = []
    for (cy0, cy1, cx0, cx1), blocks, waves, wave_of_crop in plans:
        work = start.copy()
        wave_of = np.full(hole.shape, -1)
        wave_of[cy0 - y0 : cy1 - y0, cx0 - x0 : cx1 - x0] = wave_of_crop
        for wave, members in enumerate(waves):
            for i in members:
                y, x, s = blocks[i]
                picks = iterations
                if per_pixel > 0:
                    holes = (
                        wave_of_crop[max(y, 0) : max(y + s, 0), max(x, 0) : max(x + s, 0)] >= 0
                    ).sum()
                    picks = int(min(iterations, max(4, np.ceil(per_pixel * holes))))
                y, x = y + cy0 - y0, x + cx0 - x0
                L = s + 2 * border
                centre = (L - 1) / 2
                m, n = np.mgrid[0:L, 0:L]
                decay = rho ** np.hypot(m - centre, n - centre)
                yy, xx = y - border + m, x - border + n
                inside = (yy >= 0) & (yy < h) & (xx >= 0) & (xx < w)
                yc, xc = np.clip(yy, 0, h - 1), np.clip(xx, 0, w - 1)
                state = wave_of[yc, xc]
                s_w = np.where(
                    state == -1, 1.0, np.where((state >= 0) & (state < wave), delta, 0.0)
                )
                weight = np.where(inside, s_w * decay, 0.0)
                target = (
                    inside
                    & (state == wave)
                    & (m >= border)
                    & (m < border + s)
                    & (n >= border)
                    & (n < border + s)
                )
                for c in range(nc):
                    values = np.where(weight > 0, work[c, yc, xc], 0.0)
                    model = fit_block(
                        values,
                        weight,
                        # the channels after the first take `minor` of the picks
                        iterations=picks if c == 0 else max(1, int(np.rint(minor * picks))),
                        gamma=gamma,
                        alpha=alpha,
                        stop=stop,
                        floor=floor,
                        stall=stall,
                        detrend=detrend,
                        cutoff=cutoff,
                    )
                    work[c, yc[target], xc[target]] = model[target]
        fills.append(work)
    filled = np.einsum("ji,jyx->iyx", axes, np.mean(fills, 0)) + mean[:, None, None]
    part[:, hole] = filled[:, hole]
    return out
