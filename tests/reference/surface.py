"""NumPy references of the surface kernels (kernels/surface_*.cl): the same discrete formulas.

Volumes are padded (nc, PZ, PY, PX) arrays handled through flat indices, as the kernels do:
`sx` = PX is the row stride and `sxy` = PX * PY the slab stride.
"""

import numpy as np


def band_indices(psi_pad, width, ghost):
    """Sorted flat indices of interior cells with |psi| < width."""
    mask = np.zeros(psi_pad.shape, bool)
    g = ghost
    inner = np.abs(psi_pad[g:-g, g:-g, g:-g]) < width
    mask[g:-g, g:-g, g:-g] = inner
    return np.flatnonzero(mask)


def closest_points(psi_pad, band, inv_h):
    """Padded index coordinates (3, n) of x - psi grad psi / |grad psi| (central differences)."""
    _pz, py, px = psi_pad.shape
    sx, sxy = px, px * py
    f = psi_pad.ravel().astype(np.float64)
    gx = f[band + 1] - f[band - 1]
    gy = f[band + sx] - f[band - sx]
    gz = f[band + sxy] - f[band - sxy]
    d = f[band] * inv_h / np.sqrt(gx**2 + gy**2 + gz**2 + 1e-30)
    z, rem = np.divmod(band, sxy)
    y, x = np.divmod(rem, sx)
    return np.stack([x - d * gx, y - d * gy, z - d * gz])


def _axis_weights(p, n, order):
    f = np.floor(p)
    t = p - f
    if order == 3:
        w = np.stack(
            [
                -t * (t - 1) * (t - 2) / 6,
                (t + 1) * (t - 1) * (t - 2) / 2,
                -(t + 1) * t * (t - 2) / 2,
                (t + 1) * t * (t - 1) / 6,
            ]
        )
        first = np.clip(f.astype(int) - 1, 0, n - 4)
    else:
        w = np.stack([1 - t, t])
        first = np.clip(f.astype(int), 0, n - 2)
    return first, w


def interpolate(u_pad, points, order=3):
    """Values (nc, n) of the padded volumes u_pad (nc, PZ, PY, PX) at index points (3, n)."""
    nc, pz, py, px = u_pad.shape
    x0, wx = _axis_weights(points[0], px, order)
    y0, wy = _axis_weights(points[1], py, order)
    z0, wz = _axis_weights(points[2], pz, order)
    out = np.zeros((nc, points.shape[1]))
    nodes = wx.shape[0]
    for a in range(nodes):
        for b in range(nodes):
            for e in range(nodes):
                w = wz[a] * wy[b] * wx[e]
                out += w * u_pad[:, z0 + a, y0 + b, x0 + e]
    return out


def cp_stencils(points, padded_shape, order=3):
    """Flat padded index of each point's first interpolation node, and the point's offsets
    (3, n) from floor(point): what kernels/surface/band.cl's cp_stencils stores per band cell."""
    pz, py, px = padded_shape
    x0, _ = _axis_weights(points[0], px, order)
    y0, _ = _axis_weights(points[1], py, order)
    z0, _ = _axis_weights(points[2], pz, order)
    return z0 * px * py + y0 * px + x0, points - np.floor(points)


def node_cells(base, padded_shape, order=3):
    """Sorted flat indices of every interpolation node of the stencils starting at `base`."""
    _pz, py, px = padded_shape
    k = 4 if order == 3 else 2
    a, b, e = np.meshgrid(np.arange(k), np.arange(k), np.arange(k), indexing="ij")
    offsets = (a * px * py + b * px + e).ravel()
    return np.unique(base[:, None] + offsets[None, :])


def stencil_cells(cells, padded_shape):
    """Sorted flat indices of the cells and their 6 face and 12 edge neighbours."""
    _pz, py, px = padded_shape
    offsets = [
        dz * px * py + dy * px + dx
        for dz in (-1, 0, 1)
        for dy in (-1, 0, 1)
        for dx in (-1, 0, 1)
        if abs(dx) + abs(dy) + abs(dz) <= 2
    ]
    return np.unique(cells[:, None] + np.array(offsets)[None, :])


def interpolate_lines(u_pad, points, order=3):
    """interpolate() for line fields: each node's vector is first turned to the side of the
    vector at the node floor(point)."""
    nc, pz, py, px = u_pad.shape
    x0, wx = _axis_weights(points[0], px, order)
    y0, wy = _axis_weights(points[1], py, order)
    z0, wz = _axis_weights(points[2], pz, order)
    k = wx.shape[0]
    m = k // 2 - 1
    ref = u_pad[:, z0 + m, y0 + m, x0 + m]
    out = np.zeros((nc, points.shape[1]))
    for a in range(k):
        for b in range(k):
            for e in range(k):
                node = u_pad[:, z0 + a, y0 + b, x0 + e]
                sign = np.where((node * ref).sum(axis=0) < 0, -1.0, 1.0)
                out += wz[a] * wy[b] * wx[e] * sign * node
    return out


def extend_cp(u_pad, band, cp, order=3, normalize=False, line_field=False):
    """The band's new values (nc, n): u interpolated at the closest points."""
    v = interpolate_lines(u_pad, cp, order) if line_field else interpolate(u_pad, cp, order)
    if normalize:
        norm = np.sqrt((v**2).sum(axis=0))
        v = np.where(norm > 0, v / np.where(norm > 0, norm, 1), 0)
    return v


def _normal(f, j, sx, sxy):
    return (
        0.5 * (f[j + 1] - f[j - 1]),
        0.5 * (f[j + sx] - f[j - sx]),
        0.5 * (f[j + sxy] - f[j - sxy]),
    )


def heat_flux(f, p, j, offsets, sx, sxy, weighted):
    """|N| P_N v (or P_N v) at cells j, v the signed one-sided gradient."""
    v = [np.sign(e) * (f[j + e] - f[j]) for e in offsets]
    n = _normal(p, j, sx, sxy)
    nn = n[0] ** 2 + n[1] ** 2 + n[2] ** 2 + 1e-30
    s = (n[0] * v[0] + n[1] * v[1] + n[2] * v[2]) / nn
    length = np.sqrt(nn) if weighted else 1.0
    return [length * (v[a] - s * n[a]) for a in range(3)]


def heat_step(u_pad, psi_pad, band, r, offsets, weighted=False):
    """New band values (nc, n) of one appendix-E step v = u + r div(|N| P_N grad u) / |N|."""
    nc, _pz, py, px = u_pad.shape
    sx, sxy = px, px * py
    p = psi_pad.ravel().astype(np.float64)
    out = np.empty((nc, band.size))
    for c in range(nc):
        f = u_pad[c].ravel().astype(np.float64)
        wc = heat_flux(f, p, band, offsets, sx, sxy, weighted)
        div = 0.0
        for a, e in enumerate(offsets):
            wn = heat_flux(f, p, band - e, offsets, sx, sxy, weighted)
            div = div + np.sign(e) * (wc[a] - wn[a])
        if weighted:
            n = _normal(p, band, sx, sxy)
            div = div / np.sqrt(n[0] ** 2 + n[1] ** 2 + n[2] ** 2 + 1e-30)
        out[c] = f[band] + r * div
    return out


def _line_sign(u_flat, plane, ref, cells):
    """+1 or -1 per cell: turns the vector at `cells` to the side of the one at `ref`."""
    nc = u_flat.size // plane
    dot = sum(u_flat[c * plane + ref] * u_flat[c * plane + cells] for c in range(nc))
    return np.where(dot < 0, -1.0, 1.0)


def flow_flux(
    u_flat, p, j, offsets, sx, sxy, plane, e2, flow_p, weighted, direction=None, ref=None
):
    """flow_step's fluxes at cells j: list over channels of 3 components, and |P v|^2.
    With ref (line fields), every vector read is turned to the side of the one at ref."""
    n = _normal(p, j, sx, sxy)
    nn = n[0] ** 2 + n[1] ** 2 + n[2] ** 2 + 1e-30
    length = np.sqrt(nn) if weighted else 1.0
    nc = u_flat.size // plane
    sign = (
        (lambda cells: 1.0)
        if ref is None
        else (lambda cells: _line_sign(u_flat, plane, ref, cells))
    )
    pv, g2 = [], 0.0
    for c in range(nc):
        f = u_flat[c * plane : (c + 1) * plane]
        fj = sign(j) * f[j]
        v = [np.sign(e) * (sign(j + e) * f[j + e] - fj) for e in offsets]
        s = (n[0] * v[0] + n[1] * v[1] + n[2] * v[2]) / nn
        w = [v[a] - s * n[a] for a in range(3)]
        g2 = g2 + w[0] ** 2 + w[1] ** 2 + w[2] ** 2
        pv.append(w)
    if direction is not None:
        d = [direction[a * plane + j] for a in range(3)]
        out = []
        for w in pv:
            a = length * (d[0] * w[0] + d[1] * w[1] + d[2] * w[2])
            out.append([a * d[0], a * d[1], a * d[2]])
        return out, g2
    gain = length / np.sqrt(g2 + e2) if flow_p == 1 else length
    return [[gain * x for x in w] for w in pv], g2


def flow_step(
    u_pad,
    psi_pad,
    band,
    r,
    dt,
    lam,
    e2,
    offsets,
    flow_p=2,
    harmonic=False,
    u0_pad=None,
    direction=None,
    weighted=False,
    line_field=False,
):
    """New band values (nc, n) of flow_step (TV, harmonic maps, flux along d, fidelity)."""
    nc, pz, py, px = u_pad.shape
    sx, sxy, plane = px, px * py, px * py * pz
    u = u_pad.ravel().astype(np.float64)
    p = psi_pad.ravel().astype(np.float64)
    d = None if direction is None else direction.ravel().astype(np.float64)
    ref = band if line_field else None
    wc, g2 = flow_flux(u, p, band, offsets, sx, sxy, plane, e2, flow_p, weighted, d, ref)
    nb = [
        flow_flux(u, p, band - e, offsets, sx, sxy, plane, e2, flow_p, weighted, d, ref)[0]
        for e in offsets
    ]
    inv_len = 1.0
    if weighted:
        n = _normal(p, band, sx, sxy)
        inv_len = 1 / np.sqrt(n[0] ** 2 + n[1] ** 2 + n[2] ** 2 + 1e-30)
    out = np.empty((nc, band.size))
    for c in range(nc):
        uc = u[c * plane + band]
        div = sum(np.sign(e) * (wc[c][a] - nb[a][c][a]) for a, e in enumerate(offsets))
        rate = div * inv_len
        if harmonic:
            rate = rate + uc * (g2 if flow_p == 2 else np.sqrt(g2))
        val = uc + r * rate
        if u0_pad is not None:
            val = val - dt * lam * (uc - u0_pad.ravel()[c * plane + band])
        out[c] = val
    return out


def tv_lambda_terms(u_pad, u0_pad, psi_pad, band, inv_h, eps_cells, e2, offsets):
    """(num, area, resid) per band cell, as the tv_lambda_terms kernel."""
    _nc, _pz, py, px = u_pad.shape
    sx, sxy = px, px * py
    u, u0 = u_pad.ravel().astype(np.float64), u0_pad.ravel().astype(np.float64)
    p = psi_pad.ravel().astype(np.float64)
    d = p[band] * inv_h
    delta = np.where(
        np.abs(d) < eps_cells, (1 + np.cos(np.pi * d / eps_cells)) / (2 * eps_cells), 0
    )
    n = _normal(p, band, sx, sxy)
    nn = n[0] ** 2 + n[1] ** 2 + n[2] ** 2 + 1e-30
    v = [np.sign(e) * (u[band + e] - u[band]) for e in offsets]
    v0 = [np.sign(e) * (u0[band + e] - u0[band]) for e in offsets]
    s = (n[0] * v[0] + n[1] * v[1] + n[2] * v[2]) / nn
    pv = [v[a] - s * n[a] for a in range(3)]
    norm = np.sqrt(pv[0] ** 2 + pv[1] ** 2 + pv[2] ** 2 + e2)
    num = delta * sum((v[a] - v0[a]) * pv[a] for a in range(3)) / norm
    return num, delta, delta * (u[band] - u0[band]) ** 2


def extend_pde_step(u_pad, psi_pad, band, r, h):
    """Band values (nc, n) after one upwind step of u_t + sign(psi) N . grad u = 0."""
    nc, _pz, py, px = u_pad.shape
    sx, sxy = px, px * py
    p = psi_pad.ravel().astype(np.float64)
    n = _normal(p, band, sx, sxy)
    inv = 1 / np.sqrt(n[0] ** 2 + n[1] ** 2 + n[2] ** 2 + 1e-30)
    sgn = p[band] / np.sqrt(p[band] ** 2 + h * h)
    a = [sgn * n[k] * inv for k in range(3)]
    out = np.empty((nc, band.size))
    for c in range(nc):
        f = u_pad[c].ravel().astype(np.float64)
        total = 0.0
        for k, s in enumerate((1, sx, sxy)):
            back = f[band] - f[band - s]
            fwd = f[band + s] - f[band]
            total = total + a[k] * np.where(a[k] > 0, back, fwd)
        out[c] = f[band] - r * total
    return out


def reinit_step(phi_pad, phi0_pad, band, r, h):
    """Band values after one Sussman/Godunov step with Russo-Smereka's subcell fix."""
    _pz, py, px = phi_pad.shape[-3:]
    sx, sxy = px, px * py
    f = phi_pad.ravel().astype(np.float64)
    f0 = phi0_pad.ravel().astype(np.float64)
    p0 = f0[band]
    s = np.sign(p0)
    near = np.zeros(band.size, bool)
    for st in (1, -1, sx, -sx, sxy, -sxy):
        near |= p0 * f0[band + st] <= 0
    c = f[band]
    slope2 = 0.0
    gsum = 0.0
    for st in (1, sx, sxy):
        sl = np.maximum.reduce(
            [
                np.abs(f0[band + st] - f0[band - st]) * 0.5,
                np.abs(f0[band + st] - p0),
                np.abs(p0 - f0[band - st]),
                np.full(band.size, 1e-12),
            ]
        )
        slope2 = slope2 + sl**2
        back = c - f[band - st]
        fwd = f[band + st] - c
        pos = np.maximum(np.maximum(back, 0) ** 2, np.minimum(fwd, 0) ** 2)
        neg = np.maximum(np.minimum(back, 0) ** 2, np.maximum(fwd, 0) ** 2)
        gsum = gsum + np.where(s > 0, pos, neg)
    g = np.sqrt(slope2) / h
    near_val = c - r * (s * np.abs(c) - p0 / g)
    far_val = c - r * s * (np.sqrt(gsum) / h - 1) * h
    return np.where(near, near_val, far_val)


def principal_directions(psi_pad, band, inv_h):
    """(dirs (6, n), curv (2, n)) as the principal_directions kernel."""
    _pz, py, px = psi_pad.shape[-3:]
    sx, sxy = px, px * py
    f = psi_pad.ravel().astype(np.float64)
    i = band
    g = np.stack(_normal(f, i, sx, sxy))
    inv = 1 / np.sqrt((g**2).sum(axis=0) + 1e-30)
    n = g * inv
    c = f[i]
    H = np.empty((3, 3, i.size))
    for a, sa in enumerate((1, sx, sxy)):
        H[a, a] = f[i + sa] - 2 * c + f[i - sa]
        for b, sb in enumerate((1, sx, sxy)):
            if b > a:
                H[a, b] = H[b, a] = 0.25 * (
                    f[i + sa + sb] - f[i - sa + sb] - f[i + sa - sb] + f[i - sa - sb]
                )
    absn = np.abs(n)
    e = np.zeros_like(n)
    pick = np.where(
        (absn[0] <= absn[1]) & (absn[0] <= absn[2]), 0, np.where(absn[1] <= absn[2], 1, 2)
    )
    e[pick, np.arange(i.size)] = 1
    ta = np.cross(n.T, e.T).T
    with np.errstate(invalid="ignore", divide="ignore"):
        ta /= np.sqrt((ta**2).sum(axis=0))
    tb = np.cross(n.T, ta.T).T
    Ha = np.einsum("abk,bk->ak", H, ta)
    Hb = np.einsum("abk,bk->ak", H, tb)
    p = (ta * Ha).sum(axis=0)
    q = (ta * Hb).sum(axis=0)
    r = (tb * Hb).sum(axis=0)
    mean = 0.5 * (p + r)
    dev = np.sqrt((0.5 * (p - r)) ** 2 + q**2)
    theta = 0.5 * np.arctan2(2 * q, p - r)
    ct, st = np.cos(theta), np.sin(theta)
    dirs = np.concatenate([ct * ta + st * tb, -st * ta + ct * tb])
    scale = inv * inv_h
    k1, k2 = (mean + dev) * scale, (mean - dev) * scale
    return dirs, np.stack([k1 / (1 - c * k1), k2 / (1 - c * k2)])


def turk_step(u_pad, psi_pad, band, beta_pad, dt, da, db, s, offsets, direction=None):
    """New (a, b) band values of one Turk reaction-diffusion step."""
    _nc, pz, py, px = u_pad.shape
    sx, sxy, plane = px, px * py, px * py * pz
    p = psi_pad.ravel().astype(np.float64)
    fa = u_pad[0].ravel().astype(np.float64)
    fb = u_pad[1].ravel().astype(np.float64)

    def div(f, along):
        def flux(j):
            w = heat_flux(f, p, j, offsets, sx, sxy, False)
            if not along:
                return w
            d = [direction.ravel()[k * plane + j] for k in range(3)]
            a = d[0] * w[0] + d[1] * w[1] + d[2] * w[2]
            return [a * d[0], a * d[1], a * d[2]]

        wc = flux(band)
        return sum(np.sign(e) * (wc[k] - flux(band - e)[k]) for k, e in enumerate(offsets))

    a, b = fa[band], fb[band]
    beta = beta_pad.ravel()[band]
    new_a = a + dt * (s * (16 - a * b) + da * div(fa, direction is not None))
    new_b = np.maximum(0, b + dt * (s * (a * b - b - beta) + db * div(fb, False)))
    return np.stack([new_a, new_b])
