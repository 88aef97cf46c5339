"""NumPy / SciPy references of the inpainting methods' discrete formulas (clpde.inpainting).

Each function is a direct, slow transcription of the formula the kernel implements, on
(channels, rows, cols) float64 data: the Poisson family as sparse matrices solved by
scipy.sparse.linalg.spsolve, coherence transport shell by shell, Navier-Stokes one step.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import spsolve


def graph_laplacian_matrix(ny: int, nx: int) -> sp.csr_matrix:
    """L of the ny x nx pixel grid: (L u)(p) = sum over in-grid 4-neighbours q of u(q) - u(p)."""

    def path(n):
        main = -np.full(n, 2.0)
        main[0] = main[-1] = -1.0
        if n == 1:
            main[:] = 0.0
        return sp.diags([np.ones(n - 1), main, np.ones(n - 1)], [-1, 0, 1])

    return (sp.kron(sp.identity(ny), path(nx)) + sp.kron(path(ny), sp.identity(nx))).tocsr()


def graph_laplacian(u: np.ndarray) -> np.ndarray:
    """L applied to one (ny, nx) plane."""
    p = np.pad(u, 1, mode="edge")  # a mirrored neighbour contributes u(q) - u(p) = 0
    return p[:-2, 1:-1] + p[2:, 1:-1] + p[1:-1, :-2] + p[1:-1, 2:] - 4 * u


def poisson_fill(data, omega, kind="harmonic", f=None):
    """Solve L u = f (harmonic) or L L u = f (biharmonic) in omega, u = data elsewhere."""
    nc, ny, nx = data.shape
    L = graph_laplacian_matrix(ny, nx)
    A = L if kind == "harmonic" else (L @ L).tocsr()
    inside = np.flatnonzero(omega)
    outside = np.flatnonzero(~omega)
    A_oo = A[inside][:, inside].tocsc()
    A_ok = A[inside][:, outside]
    out = data.astype(np.float64).copy()
    for c in range(nc):
        flat = out[c].reshape(-1)
        rhs = -(A_ok @ flat[outside])
        if f is not None:
            rhs = rhs + np.asarray(f[c], np.float64).reshape(-1)[inside]
        flat[inside] = spsolve(A_oo, rhs)
    return out


# ---------------------------------------------------------------------------------------
# Coherence transport


def gaussian_taps(s: float) -> np.ndarray:
    r = max(1, int(np.ceil(3 * s)))
    x = np.arange(-r, r + 1)
    w = np.exp(-0.5 * (x / s) ** 2)
    return w / w.sum()


def _sep(p, taps, shape):
    ny, nx = shape
    tmp = sum(t * p[:, j : j + nx] for j, t in enumerate(taps))  # (ny + len(taps) - 1, nx)
    return sum(t * tmp[j : j + ny, :] for j, t in enumerate(taps))


def normalized_smooth(values, weight, s):
    """(K_s * (weight values)) / (K_s * weight), 0 where the weights vanish."""
    taps = gaussian_taps(s)
    r = len(taps) // 2
    num = _sep(np.pad(values * weight, r), taps, values.shape)
    den = _sep(np.pad(weight, r), taps, values.shape)
    return np.where(den > 1e-12, num / np.maximum(den, 1e-30), 0.0), den


def structure_tensor(data, known, sigma, rho):
    """The tensor of coherence transport: J = K_rho * sum_c grad u_c,sigma grad u_c,sigma^T,
    with u_sigma the normalized convolution of the known pixels and the gradients (central
    differences) counted only where both neighbours of each difference are known; the
    rho smoothing is normalized by those counts too. Returns (J11, J12, J22)."""
    m = known.astype(np.float64)
    ux_all, uy_all = [], []
    for c in range(data.shape[0]):
        us, _ = normalized_smooth(data[c], m, sigma)
        p = np.pad(us, 1)
        ux_all.append(0.5 * (p[1:-1, 2:] - p[1:-1, :-2]))
        uy_all.append(0.5 * (p[2:, 1:-1] - p[:-2, 1:-1]))
    pm = np.pad(m, 1)
    valid = pm[1:-1, 2:] * pm[1:-1, :-2] * pm[2:, 1:-1] * pm[:-2, 1:-1] * m
    j11 = sum(ux * ux for ux in ux_all)
    j12 = sum(ux * uy for ux, uy in zip(ux_all, uy_all, strict=False))
    j22 = sum(uy * uy for uy in uy_all)
    out = [normalized_smooth(j, valid, rho)[0] for j in (j11, j12, j22)]
    return tuple(out)


def coherence_weights(j11, j12, j22, kappa):
    """Per pixel: the unit normal n = c-perp (eigenvector of the larger eigenvalue) and the
    guidance strength mu = kappa * ((l1 - l2) / (l1 + l2))^2."""
    tr = j11 + j22
    d = np.sqrt((j11 - j22) ** 2 + 4 * j12**2)
    l1, l2 = 0.5 * (tr + d), 0.5 * (tr - d)
    # eigenvector of l1: (j12, l1 - j11) or (l1 - j22, j12), whichever is longer
    a = np.stack([j12, l1 - j11])
    b = np.stack([l1 - j22, j12])
    v = np.where((a**2).sum(0) >= (b**2).sum(0), a, b)
    norm = np.sqrt((v**2).sum(0))
    v = np.where(norm > 0, v / np.maximum(norm, 1e-300), np.array([1.0, 0.0])[:, None, None])
    coh = np.where(tr > 1e-12, (l1 - l2) / np.maximum(l1 + l2, 1e-300), 0.0) ** 2
    return v[0], v[1], kappa * coh


def coherence_shells(omega):
    """Shell number of each hole pixel: ceil of its Euclidean distance to the known pixels."""
    from scipy import ndimage

    dist = ndimage.distance_transform_edt(omega)
    return np.where(omega, np.ceil(dist - 1e-9).astype(int), 0)


def coherence_transport(data, omega, epsilon=5.0, kappa=25.0, sigma=1.4, rho=4.0):
    """Fill omega shell by shell: every pixel of a shell gets the weighted mean of the
    pixels known before that shell within distance epsilon,
        w(x, y) = exp(-mu^2 / (2 eps^2) <n(x), y - x>^2) / |y - x|,
    n, mu from the structure tensor of the known pixels (all channels together)."""
    out = data.astype(np.float64).copy()
    shells = coherence_shells(omega)
    known = ~omega
    ny, nx = omega.shape
    r = int(np.floor(epsilon))
    offsets = [
        (dy, dx)
        for dy in range(-r, r + 1)
        for dx in range(-r, r + 1)
        if 0 < dy * dy + dx * dx <= epsilon * epsilon
    ]
    for s in range(1, shells.max() + 1):
        j11, j12, j22 = structure_tensor(out, known, sigma, rho)
        n1, n2, mu = coherence_weights(j11, j12, j22, kappa)
        ys, xs = np.nonzero(shells == s)
        new = np.zeros((out.shape[0], ys.size))
        for k, (y, x) in enumerate(zip(ys, xs, strict=False)):
            num = np.zeros(out.shape[0])
            den = 0.0
            num_iso = np.zeros(out.shape[0])
            den_iso = 0.0
            for dy, dx in offsets:
                yy, xx = y + dy, x + dx
                if 0 <= yy < ny and 0 <= xx < nx and known[yy, xx]:
                    dist = np.sqrt(dx * dx + dy * dy)
                    along = n1[y, x] * dx + n2[y, x] * dy
                    w = np.exp(-(mu[y, x] ** 2) / (2 * epsilon**2) * along**2) / dist
                    num += w * out[:, yy, xx]
                    den += w
                    num_iso += out[:, yy, xx] / dist
                    den_iso += 1 / dist
            new[:, k] = num / den if den > 1e-6 * den_iso else num_iso / den_iso
        out[:, ys, xs] = new
        known = known.copy()
        known[ys, xs] = True
    return out


# ---------------------------------------------------------------------------------------
# Navier-Stokes inpainting


def _neighbours(a):
    """(east, west, north, south) of each pixel, mirrored at the border (zero differences)."""
    p = np.pad(a, 1, mode="edge")
    return p[1:-1, 2:], p[1:-1, :-2], p[2:, 1:-1], p[:-2, 1:-1]


def ns_vorticity_step(img, w, omega, dt, nu, contrast):
    """One explicit step of w_t + v . grad w = nu div(g grad w) at the hole's pixels
    (first-order upwind transport, face fluxes g(|w_q - w_p|)(w_q - w_p))."""
    out = w.copy()

    def g(d):
        return 1 / (1 + (d / contrast) ** 2)

    for c in range(img.shape[0]):
        ie, iw, i_n, i_s = _neighbours(img[c])
        we, ww, wn, ws = _neighbours(w[c])
        vx, vy = -0.5 * (i_n - i_s), 0.5 * (ie - iw)
        de, dw, dn, ds = we - w[c], w[c] - ww, wn - w[c], w[c] - ws
        adv = np.where(vx > 0, vx * dw, vx * de) + np.where(vy > 0, vy * ds, vy * dn)
        diff = g(de) * de - g(dw) * dw + g(dn) * dn - g(ds) * ds
        out[c] = np.where(omega, w[c] + dt * (nu * diff - adv), w[c])
    return out


def transport_residual(img, omega):
    """Mean over the hole of |grad(L I) . grad-perp(I)| / (|grad L I| |grad I|), central
    differences: 0 where the Laplacian is constant along the isophotes."""
    num = den = 0.0
    for c in range(img.shape[0]):
        lap = graph_laplacian(img[c])
        ie, iw, i_n, i_s = _neighbours(img[c])
        le, lw, ln, ls = _neighbours(lap)
        ix, iy = 0.5 * (ie - iw), 0.5 * (i_n - i_s)
        lx, ly = 0.5 * (le - lw), 0.5 * (ln - ls)
        num += np.abs(lx * -iy + ly * ix)[omega].sum()
        den += (np.hypot(lx, ly) * np.hypot(ix, iy))[omega].sum()
    return num / max(den, 1e-300)
