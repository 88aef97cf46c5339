"""NumPy references of kernels/regions/regions.cl: the same discrete formulas over a band.

Volumes are flat padded arrays (channels * plane values, plane = one padded channel); `band`
holds flat padded indices of channel 0, `sx`/`sxy` the row and slab strides, as on the device.
"""

import numpy as np


def minmod(a, b):
    return np.where(a * b > 0, np.sign(a) * np.minimum(np.abs(a), np.abs(b)), 0.0)


def one_sided(u, i, s):
    m2, m1, c, p1, p2 = (u[i + k * s] for k in (-2, -1, 0, 1, 2))
    q_m, q_c, q_p = m2 - 2 * m1 + c, m1 - 2 * c + p1, c - 2 * p1 + p2
    return (c - m1) + 0.5 * minmod(q_m, q_c), (p1 - c) - 0.5 * minmod(q_c, q_p)


def godunov_axis(dm, dp, v):
    down = np.maximum(np.maximum(dm, 0) ** 2, np.minimum(dp, 0) ** 2)
    up = np.maximum(np.minimum(dm, 0) ** 2, np.maximum(dp, 0) ** 2)
    return np.where(v > 0, up, down)


def upwind_norm(u, i, sx, sxy, v):
    total = 0.0
    for s in (1, sx, sxy):
        dm, dp = one_sided(u, i, s)
        total = total + godunov_axis(dm, dp, v)
    return np.sqrt(total)


def central_grad(u, i, sx, sxy):
    return [0.5 * (u[i + s] - u[i - s]) for s in (1, sx, sxy)]


def curvatures(u, i, sx, sxy):
    gx, gy, gz = central_grad(u, i, sx, sxy)
    c2 = 2 * u[i]
    hxx, hyy, hzz = (u[i + s] - c2 + u[i - s] for s in (1, sx, sxy))

    def mixed(a, b):
        return 0.25 * (u[i + a + b] - u[i - a + b] - u[i + a - b] + u[i - a - b])

    hxy, hxz, hyz = mixed(1, sx), mixed(1, sxy), mixed(sx, sxy)
    g2 = gx**2 + gy**2 + gz**2 + 1e-12
    ghg = (
        gx * gx * hxx
        + gy * gy * hyy
        + gz * gz * hzz
        + 2 * (gx * gy * hxy + gx * gz * hxz + gy * gz * hyz)
    )
    mean = (g2 * (hxx + hyy + hzz) - ghg) / g2**1.5
    axx, ayy, azz = hyy * hzz - hyz**2, hxx * hzz - hxz**2, hxx * hyy - hxy**2
    axy, axz, ayz = hxz * hyz - hxy * hzz, hxy * hyz - hxz * hyy, hxy * hxz - hxx * hyz
    gag = (
        gx * gx * axx
        + gy * gy * ayy
        + gz * gz * azz
        + 2 * (gx * gy * axy + gx * gz * axz + gy * gz * ayz)
    )
    return mean, gag / g2**2


def region_speed(phi, aux, band, scale, mode, sx, sxy, vmax=np.inf):
    """Speeds V at the band cells (in band order)."""
    return np.clip(_raw_speed(phi, aux, band, scale, mode, sx, sxy), -vmax, vmax)


def _raw_speed(phi, aux, band, scale, mode, sx, sxy):
    if mode == 0:
        return np.full(len(band), float(scale))
    if mode in (1, 2):
        mean, gauss = curvatures(phi, band, sx, sxy)
        return scale * (mean if mode == 1 else np.sign(mean) * np.maximum(gauss, 0))
    if mode == 3:
        return scale * (aux[band] - phi[band])
    return scale * aux[band]


def band_cutoff(phi, lo, hi):
    t = np.clip((np.abs(phi) - lo) / (hi - lo), 0, 1)
    return 1 - t * t * (3 - 2 * t)


def region_step(ls, speed, band, dt, eps2, lo, hi, nc, plane, sx, sxy):
    """New values of every channel at the band cells: array (nc, len(band))."""
    v0 = speed[band] * band_cutoff(ls[band], lo, hi)
    out = np.empty((nc, len(band)))
    for c in range(nc):
        j = band + c * plane
        v = v0
        if c:
            f = central_grad(ls, band, sx, sxy)
            g = central_grad(ls, j, sx, sxy)
            dot = sum(a * b for a, b in zip(f, g, strict=False))
            v = v0 * dot / np.sqrt((sum(a * a for a in f) + eps2) * (sum(b * b for b in g) + eps2))
        out[c] = ls[j] + dt * v * upwind_norm(ls, j, sx, sxy, v)
    return out


def advect_step(ls, band, dt, velocity, lo, hi, nc, plane, sx, sxy):
    out = np.empty((nc, len(band)))
    cut = band_cutoff(ls[band], lo, hi)
    for c in range(nc):
        j = band + c * plane
        adv = 0.0
        for u, s in zip(velocity, (1, sx, sxy), strict=False):
            dm, dp = one_sided(ls, j, s)
            adv = adv + u * (dm if u > 0 else dp)
        out[c] = ls[j] - dt * cut * adv
    return out


def reinit_step(u, u0, band, dt, nc, plane, sx, sxy, tol=0.1):
    out = np.empty((nc, len(band)))
    for c in range(nc):
        i = band + c * plane
        c0 = u0[i]
        nb = [u0[i + s] for s in (1, -1, sx, -sx, sxy, -sxy)]
        sgn = np.sign(c0)
        interface = np.zeros(len(i), bool)
        for v in nb:
            interface |= c0 * v < 0
        e0, w0, n0, s0, t0, b0 = nb
        g = 0.5 * np.sqrt((e0 - w0) ** 2 + (n0 - s0) ** 2 + (t0 - b0) ** 2)
        g = np.maximum(g, 0.5 * np.maximum.reduce([np.abs(v - c0) for v in nb]))
        d = c0 / np.maximum(g, 1e-12)
        p = u[i]
        subcell = np.where(np.abs(g - 1) < tol, p, p - dt * (sgn * np.abs(p) - d))
        godunov = p - dt * sgn * (upwind_norm(u, i, sx, sxy, -sgn) - 1)
        out[c] = np.where(interface, subcell, godunov)
    return out


def extend_outer(ls, band, dt, lo, hi, nc, plane, sx, sxy):
    """New values of channels 1..nc-1 at the band cells: array (nc - 1, len(band))."""
    p = ls[band]
    w = 1 - band_cutoff(p, lo, hi)
    g = central_grad(ls, band, sx, sxy)
    s = np.sign(p) / np.sqrt(sum(a * a for a in g) + 1e-12)
    out = np.empty((nc - 1, len(band)))
    for c in range(1, nc):
        j = band + c * plane
        du = 0.0
        for a, st in zip(g, (1, sx, sxy), strict=False):
            a = s * a
            du = du + a * np.where(a > 0, ls[j] - ls[j - st], ls[j + st] - ls[j])
        out[c - 1] = ls[j] - dt * w * du
    return out


def heun_average(u, stage, out, band, nc, plane):
    """heun_average: out with (u + stage) / 2 on the band, every channel."""
    idx = np.concatenate([band + c * plane for c in range(nc)])
    out = out.copy()
    out[idx] = 0.5 * (u[idx] + stage[idx])
    return out


def copy_runs(src, dst, band, nc, plane):
    """copy_runs: dst with src's values on the band, every channel."""
    idx = np.concatenate([band + c * plane for c in range(nc)])
    out = dst.copy()
    out[idx] = src[idx]
    return out


def reinit_heun(acc, stage1, u0, band, dt, nc, plane, sx, sxy):
    """reinit3d_heun: acc with (acc + Euler step of stage1) / 2 on the band, every channel."""
    out = acc.copy()
    new = reinit_step(stage1, u0, band, dt, nc, plane, sx, sxy)
    for c in range(nc):
        i = band + c * plane
        out[i] = 0.5 * (acc[i] + new[c])
    return out


def region_stages(ls, aux, start, band, dt, eps2, lo, hi, scale, mode, vmax, nc, plane, sx, sxy):
    """region_euler and region_heun: the speed from ls at the band cells (region_speed),
    then region_step's update of every channel. Returns (euler, heun, max |V|): euler =
    ls + dt L(ls) and heun = (start + ls + dt L(ls)) / 2 at the band cells, (nc, len(band)),
    and max |V| over the band cells where |Phi| < hi (0 if none)."""
    speed = np.zeros_like(ls[:plane])
    v = region_speed(ls, aux, band, scale, mode, sx, sxy, vmax)
    speed[band] = v
    euler = region_step(ls, speed, band, dt, eps2, lo, hi, nc, plane, sx, sxy)
    starts = np.stack([start[band + c * plane] for c in range(nc)])
    inside = np.abs(ls[band]) < hi
    return euler, 0.5 * (starts + euler), float(np.abs(v[inside]).max(initial=0.0))
