"""Numpy references of kernels/volumes/volume.cl's schemes, on (nc, nz, ny, nx) float64
arrays with spacing h = (hz, hy, hx): the same discrete operators, written with slices."""

import numpy as np

AXES = (1, 2, 3)  # z, y, x of an (nc, nz, ny, nx) array


def _shift(u, axis, k):
    """u at index + k along axis, the voxel's own value beyond the border (Neumann)."""
    n = u.shape[axis]
    idx = np.clip(np.arange(n) + k, 0, n - 1)
    return np.take(u, idx, axis=axis)


def grad(u, h):
    """Forward differences over the spacing, zero across the far border: (gz, gy, gx)."""
    return [(_shift(u, a, 1) - u) / h[k] for k, a in enumerate(AXES)]


def div(p, h):
    """The negative adjoint of grad: backward differences, p zero behind the near border."""
    out = np.zeros_like(p[0])
    for k, a in enumerate(AXES):
        q = p[k].copy()
        sl = [slice(None)] * 4
        sl[a] = slice(-1, None)
        q[tuple(sl)] = 0  # the component across the far border face is zero
        back = np.roll(q, 1, axis=a)
        sl[a] = slice(0, 1)
        back[tuple(sl)] = 0
        out += (q - back) / h[k]
    return out


def tv_fgp(f, lam, h, iterations, vectorial=False):
    """Fast projected gradient on the dual of min TV(u) + lam/2 |u - f|^2, fixed lambda
    per channel; returns u = f + div(p) / lam."""
    lam = np.asarray(lam, np.float64).reshape(-1, 1, 1, 1)
    tau = 1.0 / (4.0 * sum(1.0 / np.asarray(h) ** 2))
    p = np.zeros((3,) + f.shape)
    p_old = p.copy()
    t, beta = 1.0, 0.0
    for _ in range(iterations):
        q = p + beta * (p - p_old)
        w = lam * f + div(q, h)
        a = q + tau * np.array(grad(w, h))
        norm2 = (a**2).sum(axis=0)
        if vectorial:
            norm2 = np.broadcast_to(norm2.sum(axis=0), norm2.shape)
        p_old, p = p, a / np.maximum(1.0, np.sqrt(norm2))
        t_next = 0.5 * (1.0 + np.sqrt(1.0 + 4.0 * t * t))
        beta, t = (t - 1.0) / t_next, t_next
    return f + div(p, h) / lam


def heat_step(u, dt, h):
    lap = sum((_shift(u, a, 1) + _shift(u, a, -1) - 2 * u) / h[k] ** 2 for k, a in enumerate(AXES))
    return u + dt * lap


def pm_step(u, us, dt, kappa, h, edge="exp"):
    """Perona-Malik with g read across each face from us (us = u: the plain flow)."""

    def g(ds):
        s2 = (ds / kappa) ** 2
        return np.exp(-s2) if edge == "exp" else 1.0 / (1.0 + s2)

    total = 0.0
    for k, a in enumerate(AXES):
        for side in (1, -1):
            d = _shift(u, a, side) - u
            ds = (_shift(us, a, side) - us) / h[k]
            total = total + g(ds) * d / h[k] ** 2
    return u + dt * total


def tv_step(u, dt, eps, h):
    gz, gy, gx = grad(u, h)
    c = 1.0 / np.sqrt(gx**2 + gy**2 + gz**2 + eps**2)
    total = 0.0
    for k, a in enumerate(AXES):
        for side in (1, -1):
            total = total + 0.5 * (_shift(c, a, side) + c) * (_shift(u, a, side) - u) / h[k] ** 2
    return u + dt * total


def gauss(u, weights):
    """Separable Gaussian, weights[k] = w[0..r] for axis z, y, x (offsets +-j), mirrored at
    the border (index -1 reads 0)."""
    for a, w in zip(AXES, weights, strict=True):
        n = u.shape[a]
        out = w[0] * u
        for k in range(1, len(w)):
            for s in (k, -k):
                idx = np.arange(n) + s
                for _ in range(8):
                    idx = np.where(idx < 0, -idx - 1, np.where(idx >= n, 2 * n - idx - 1, idx))
                out = out + w[k] * np.take(u, np.clip(idx, 0, n - 1), axis=a)
        u = out
    return u


def harmonic_sweeps(u, hole, omega, h, sweeps):
    """Red-black SOR of the seven-point Laplace equation over `hole` (nz, ny, nx), the
    neighbours inside the box weighted by 1/h^2; u (nc, nz, ny, nx) is not modified."""
    u = u.copy()
    nz, ny, nx = hole.shape
    z, y, x = np.indices(hole.shape)
    parity = (x + y + z) % 2
    w2 = [1.0 / hk**2 for hk in h]
    for _ in range(sweeps):
        for colour in (0, 1):
            total = np.zeros_like(u)
            weight = np.zeros(hole.shape)
            for k, a in enumerate(AXES):
                n = hole.shape[k]
                pos = (z, y, x)[k]
                for side in (1, -1):
                    inside = (pos + side >= 0) & (pos + side < n)
                    total += w2[k] * inside * _shift(u, a, side)
                    weight += w2[k] * inside
            update = hole & (parity == colour)
            u[:, update] += omega * (total[:, update] / weight[update] - u[:, update])
    return u


def laplacian(u, h):
    """The seven-point Laplacian with spacing, Neumann borders (the voxel's own value)."""
    return sum((_shift(u, a, 1) + _shift(u, a, -1) - 2 * u) / h[k] ** 2 for k, a in enumerate(AXES))


def biharmonic_fill(u, hole, h):
    """The exact discrete biharmonic fill: L(L u) = 0 at the hole's voxels, L the box's
    seven-point Laplacian with spacing and Neumann borders as a sparse matrix, solved
    directly (scipy) for each channel of u (nc, nz, ny, nx); u is not modified."""
    from scipy import sparse
    from scipy.sparse.linalg import spsolve

    def second(n, hk):
        # 1D second difference; beyond the border the voxel itself (u_1 - u_0 at index 0)
        d = sparse.diags([np.ones(n - 1), -2 * np.ones(n), np.ones(n - 1)], [-1, 0, 1]).tolil()
        d[0, 0] = d[n - 1, n - 1] = -1
        return d.tocsr() / hk**2

    nz, ny, nx = hole.shape
    eye = [sparse.identity(n, format="csr") for n in (nz, ny, nx)]
    lap = (
        sparse.kron(sparse.kron(second(nz, h[0]), eye[1]), eye[2])
        + sparse.kron(sparse.kron(eye[0], second(ny, h[1])), eye[2])
        + sparse.kron(sparse.kron(eye[0], eye[1]), second(nx, h[2]))
    ).tocsr()
    bi = (lap @ lap).tocsr()
    unknown = hole.reshape(-1)
    a = bi[unknown][:, unknown].tocsc()
    out = u.copy()
    for c in range(u.shape[0]):
        flat = u[c].reshape(-1)
        rhs = -(bi[unknown][:, ~unknown] @ flat[~unknown])
        out[c].reshape(-1)[unknown] = spsolve(a, rhs)
    return out


def dct4_blocks(blocks, inverse=False):
    """The orthonormal 4-point DCT-II (or its inverse) along the last three axes."""
    k, m = np.meshgrid(np.arange(4), np.arange(4), indexing="ij")
    c = np.where(k == 0, 0.5, np.sqrt(0.5)) * np.cos(np.pi * (2 * m + 1) * k / 8)
    t = c.T if inverse else c
    return np.einsum("ai,bj,ck,...ijk->...abc", t, t, t, blocks)


def spectral_fill(u, hole, levels):
    """Iterative hard thresholding in every 4^3 block of the (nz, ny, nx) box u that holds a
    hole voxel: per threshold, each block's DCT coefficients below it are zeroed (not the
    mean), and each hole voxel becomes the mean of its blocks' values."""
    u = np.array(u, np.float64)
    nz, ny, nx = hole.shape
    corners = [
        (z, y, x)
        for z in range(nz - 3)
        for y in range(ny - 3)
        for x in range(nx - 3)
        if hole[z : z + 4, y : y + 4, x : x + 4].any()
    ]
    o = np.arange(4)
    c = np.array(corners).reshape(-1, 3)
    zz = c[:, 0, None, None, None] + o[:, None, None]
    yy = c[:, 1, None, None, None] + o[None, :, None]
    xx = c[:, 2, None, None, None] + o[None, None, :]
    zz, yy, xx = np.broadcast_arrays(zz, yy, xx)
    hits = np.zeros(u.shape)
    np.add.at(hits, (zz, yy, xx), 1.0)
    held = hole & (hits > 0)
    for level in levels:
        coef = dct4_blocks(u[zz, yy, xx])
        mean = coef[:, 0, 0, 0].copy()
        coef[np.abs(coef) < level] = 0
        coef[:, 0, 0, 0] = mean
        acc = np.zeros(u.shape)
        np.add.at(acc, (zz, yy, xx), dct4_blocks(coef, inverse=True))
        u[held] = acc[held] / hits[held]
    return u


def curvature_step(u, dt, eps, h):
    """Level-set mean curvature flow, central differences over the spacing, a neighbour
    beyond the border the voxel's own index along that axis (diagonals included)."""
    d1 = {a: (_shift(u, a, 1) - _shift(u, a, -1)) / (2 * h[k]) for k, a in enumerate(AXES)}
    d2 = {a: (_shift(u, a, 1) - 2 * u + _shift(u, a, -1)) / h[k] ** 2 for k, a in enumerate(AXES)}

    def mixed(a, b):
        ka, kb = AXES.index(a), AXES.index(b)
        s = [[_shift(_shift(u, a, i), b, j) for j in (1, -1)] for i in (1, -1)]
        return (s[0][0] - s[1][0] - s[0][1] + s[1][1]) / (4 * h[ka] * h[kb])

    z, y, x = AXES
    gz, gy, gx = d1[z], d1[y], d1[x]
    num = (
        (d2[y] + d2[z]) * gx**2
        + (d2[x] + d2[z]) * gy**2
        + (d2[x] + d2[y]) * gz**2
        - 2 * (gx * gy * mixed(x, y) + gx * gz * mixed(x, z) + gy * gz * mixed(y, z))
    )
    return u + dt * num / (gx**2 + gy**2 + gz**2 + eps)
