// The per-cell arithmetic of the surface flows (appendix E's one-sided scheme), shared by the
// band lists' kernels on dense volumes (surface/heat.cl, surface/flows.cl) and the bricks'
// on tiles (bricks.cl), so both storages run the same scheme. Include after surface.h.
//
// u is read at cell j of its array, with the signed one-sided offsets ex, ey, ez (+-1, +-sx,
// +-sxy of u's own layout) and channel stride `uplane`, from address space U_SPACE (default
// __global; bricks.cl reads a brick's tile: __private on CPUs, __local on GPUs). psi and the
// tangent field dir are read at cell q of theirs, with strides sx, sxy (dir's channel stride
// `dplane`). On the dense grid q = j and both layouts are the volume's; on bricks u is a tile
// of halo 1 and psi, dir tiles of halo 2 (a flux one cell back reads psi two cells away).
#ifndef CLPDE_SURFACE_FLUX_H
#define CLPDE_SURFACE_FLUX_H

#ifndef U_SPACE
#define U_SPACE __global
#endif
#ifndef WEIGHTED
#define WEIGHTED 0
#endif
#ifndef FLOW_P
#define FLOW_P 2
#endif
#ifndef HARMONIC
#define HARMONIC 0
#endif
#ifndef ALONG
#define ALONG 0
#endif

// psi's one-sided offsets matching u's: the same directions in psi's layout.
#define PSI_STEPS(ex, ey, ez, sx, sxy)                                                    \
    const int qx_ = (ex) > 0 ? 1 : -1, qy_ = (ey) > 0 ? (sx) : -(sx),                    \
              qz_ = (ez) > 0 ? (sxy) : -(sxy)

// ---- heat (4.7, 4.8) ----------------------------------------------------------------------
// Flux at cell j: w = |N| P_N v with v the one-sided gradient of u and N the central-difference
// gradient of psi; |N| only WEIGHTED (eq. 4.7), else the signed distance form (4.8).
INLINE vec3r heat_flux(U_SPACE const REAL* restrict u, const int j, const int ex, const int ey,
                       const int ez, __global const REAL* restrict psi, const int q,
                       const int sx, const int sxy)
{
    const REAL c = u[j];
    vec3r v;
    v.x = ONE_SIDED_SIGN(ex) * (u[j + ex] - c);
    v.y = ONE_SIDED_SIGN(ey) * (u[j + ey] - c);
    v.z = ONE_SIDED_SIGN(ez) * (u[j + ez] - c);
    const vec3r n = psi_normal(psi, q, sx, sxy);
    const REAL nn = n.x * n.x + n.y * n.y + n.z * n.z + (REAL)1e-30;
    const REAL s = (n.x * v.x + n.y * v.y + n.z * v.z) / nn;
    vec3r w;
#if WEIGHTED
    const REAL len = SQRT(nn);
#else
    const REAL len = 1;
#endif
    w.x = len * (v.x - s * n.x);
    w.y = len * (v.y - s * n.y);
    w.z = len * (v.z - s * n.z);
    return w;
}

// The complementary one-sided divergence of the flux at cell i (grid units), over |N| when
// WEIGHTED.
INLINE REAL heat_div(U_SPACE const REAL* restrict u, const int i, const int ex, const int ey,
                     const int ez, __global const REAL* restrict psi, const int q, const int sx,
                     const int sxy)
{
    PSI_STEPS(ex, ey, ez, sx, sxy);
    const vec3r wc = heat_flux(u, i, ex, ey, ez, psi, q, sx, sxy);
    const vec3r wx = heat_flux(u, i - ex, ex, ey, ez, psi, q - qx_, sx, sxy);
    const vec3r wy = heat_flux(u, i - ey, ex, ey, ez, psi, q - qy_, sx, sxy);
    const vec3r wz = heat_flux(u, i - ez, ex, ey, ez, psi, q - qz_, sx, sxy);
    REAL div = ONE_SIDED_SIGN(ex) * (wc.x - wx.x) + ONE_SIDED_SIGN(ey) * (wc.y - wy.y) +
               ONE_SIDED_SIGN(ez) * (wc.z - wz.z);
#if WEIGHTED
    const vec3r n = psi_normal(psi, q, sx, sxy);
    div *= RSQRT(n.x * n.x + n.y * n.y + n.z * n.z + (REAL)1e-30);
#endif
    return div;
}

// ---- reaction-diffusion (Turk), eqs. (4.12)-(4.14), in grid units ---------------------------
// a += dt (s (16 - a b) + Da div(P grad a)), b += dt (s (a b - b - beta) + Db div(P grad b)),
// b clamped at >= 0. With ALONG, a diffuses along the tangent field d only (4.14).
INLINE vec3r along_flux(U_SPACE const REAL* restrict u, const int j, const int ex, const int ey,
                        const int ez, __global const REAL* restrict psi,
                        __global const REAL* restrict dir, const int dplane, const int q,
                        const int sx, const int sxy)
{
    const vec3r w = heat_flux(u, j, ex, ey, ez, psi, q, sx, sxy);
    const REAL dx = dir[q], dy = dir[dplane + q], dz = dir[2 * dplane + q];
    const REAL a = dx * w.x + dy * w.y + dz * w.z;
    vec3r out;
    out.x = a * dx;
    out.y = a * dy;
    out.z = a * dz;
    return out;
}

// The new (a, b) from the old and their diffusion terms.
INLINE REAL2 turk_update(const REAL a, const REAL b, const REAL diff_a, const REAL diff_b,
                         const REAL beta, const REAL dt, const REAL da, const REAL db,
                         const REAL s)
{
    // b clamped at 0 by a select: fmax is an out-of-line call on PoCL (scalar loop)
    const REAL nb = b + dt * (s * (a * b - b - beta) + db * diff_b);
    return (REAL2)(a + dt * (s * (16 - a * b) + da * diff_a), nb > 0 ? nb : (REAL)0);
}

// The new (a, b) at cell i (u: a, then b `uplane` later).
INLINE REAL2 turk_cell(U_SPACE const REAL* restrict u, const int uplane, const int i, const int ex,
                       const int ey, const int ez, __global const REAL* restrict psi,
                       __global const REAL* restrict dir, const int dplane, const int q,
                       const int sx, const int sxy, const REAL beta, const REAL dt,
                       const REAL da, const REAL db, const REAL s)
{
    U_SPACE const REAL* ub = u + uplane;
    const REAL a = u[i], b = ub[i];
#if ALONG
    PSI_STEPS(ex, ey, ez, sx, sxy);
    const vec3r wc = along_flux(u, i, ex, ey, ez, psi, dir, dplane, q, sx, sxy);
    const vec3r wx = along_flux(u, i - ex, ex, ey, ez, psi, dir, dplane, q - qx_, sx, sxy);
    const vec3r wy = along_flux(u, i - ey, ex, ey, ez, psi, dir, dplane, q - qy_, sx, sxy);
    const vec3r wz = along_flux(u, i - ez, ex, ey, ez, psi, dir, dplane, q - qz_, sx, sxy);
    const REAL diff_a = ONE_SIDED_SIGN(ex) * (wc.x - wx.x) + ONE_SIDED_SIGN(ey) * (wc.y - wy.y) +
                        ONE_SIDED_SIGN(ez) * (wc.z - wz.z);
#else
    const REAL diff_a = heat_div(u, i, ex, ey, ez, psi, q, sx, sxy);
#endif
    const REAL diff_b = heat_div(ub, i, ex, ey, ez, psi, q, sx, sxy);
    return turk_update(a, b, diff_a, diff_b, beta, dt, da, db, s);
}

// ---- TV (4.10), harmonic maps (4.11, D.7), diffusion along a field (4.14, 4.15) ----------
//
// Flux at cell j for channel c: w_c = |N| G P_N v_c (|N| only when WEIGHTED), with
//   G = 1                               FLOW_P 2: heat (4.7/4.8), harmonic map p = 2 (D.7)
//   G = (|P v|^2 + e2)^(-1/2)           FLOW_P 1: TV (4.10), harmonic map p = 1 (4.11)
// where |P v|^2 sums over the channels (the vectorial gradient of appendix D); with ALONG the
// flux is |N| (d . P_N v_c) d for a tangent field d (3 channels of `dir`): eqs. (4.14), (4.15).
// The step is v_c = u_c + r (div w_c / |N| + HARMONIC u_c |P v|^p), r = dt / h^p (dt / h^2
// with ALONG), e2 = (h eps)^2; the kernels add TV's fidelity term (C.1).

// +1 or -1: the sign that turns the NC-vector at p to the side of the one at ref (LINE_FIELD;
// surface.h's line_sign on U_SPACE).
INLINE REAL u_line_sign(U_SPACE const REAL* restrict u, const int ref, const int p, const int uplane)
{
    REAL dot = 0;
    #pragma unroll
    for (int c = 0; c < NC; ++c) dot += u[c * uplane + ref] * u[c * uplane + p];
    return dot < 0 ? (REAL)-1 : (REAL)1;
}

// The channel loops are unrolled (#pragma unroll, NC is a constant) so the loop over a run's
// cells is the innermost one, which PoCL's vectoriser widens.
INLINE REAL flow_flux(U_SPACE const REAL* restrict u, const int uplane, const int j, const int ex,
                      const int ey, const int ez, __global const REAL* restrict psi,
                      __global const REAL* restrict dir, const int dplane, const int q,
                      const int sx, const int sxy, const REAL e2, const int ref, REAL w[NC][3])
{
#if LINE_FIELD
    const REAL s0 = u_line_sign(u, ref, j, uplane), s1 = u_line_sign(u, ref, j + ex, uplane);
    const REAL s2 = u_line_sign(u, ref, j + ey, uplane);
    const REAL s3 = u_line_sign(u, ref, j + ez, uplane);
#else
    const REAL s0 = 1, s1 = 1, s2 = 1, s3 = 1;
#endif
    const vec3r n = psi_normal(psi, q, sx, sxy);
    const REAL nn = n.x * n.x + n.y * n.y + n.z * n.z + (REAL)1e-30;
#if WEIGHTED
    const REAL len = SQRT(nn);
#else
    const REAL len = 1;
#endif
    REAL g2 = 0;
    #pragma unroll
    for (int c = 0; c < NC; ++c) {
        const int jc = c * uplane + j;
        const REAL uj = s0 * u[jc];
        const REAL vx = ONE_SIDED_SIGN(ex) * (s1 * u[jc + ex] - uj);
        const REAL vy = ONE_SIDED_SIGN(ey) * (s2 * u[jc + ey] - uj);
        const REAL vz = ONE_SIDED_SIGN(ez) * (s3 * u[jc + ez] - uj);
        const REAL s = (n.x * vx + n.y * vy + n.z * vz) / nn;
        w[c][0] = vx - s * n.x;
        w[c][1] = vy - s * n.y;
        w[c][2] = vz - s * n.z;
        g2 += w[c][0] * w[c][0] + w[c][1] * w[c][1] + w[c][2] * w[c][2];
    }
#if ALONG
    const REAL dx = dir[q], dy = dir[dplane + q], dz = dir[2 * dplane + q];
    #pragma unroll
    for (int c = 0; c < NC; ++c) {
        const REAL a = len * (dx * w[c][0] + dy * w[c][1] + dz * w[c][2]);
        w[c][0] = a * dx;
        w[c][1] = a * dy;
        w[c][2] = a * dz;
    }
#else
#if FLOW_P == 1
    const REAL gain = len * RSQRT(g2 + e2);
#else
    const REAL gain = len;
#endif
    #pragma unroll
    for (int c = 0; c < NC; ++c) {
        w[c][0] *= gain;
        w[c][1] *= gain;
        w[c][2] *= gain;
    }
#endif
    return g2;
}

// A channel's stepped value from its flux divergence `div`, the cell's 1 / |N| (1 unless
// WEIGHTED) and |P v|^2 at the cell (g2, the harmonic maps' term).
INLINE REAL flow_update(const REAL uc, const REAL div, const REAL inv_len, const REAL g2,
                        const REAL r)
{
    REAL rate = div * inv_len;
#if HARMONIC && FLOW_P == 2
    rate += uc * g2;
#elif HARMONIC
    rate += uc * SQRT(g2);
#endif
    return uc + r * rate;
}

// The stepped values of every channel at cell i, fidelity not included: out[c] = u_c + r rate_c.
INLINE void flow_cell(U_SPACE const REAL* restrict u, const int uplane, const int i, const int ex,
                      const int ey, const int ez, __global const REAL* restrict psi,
                      __global const REAL* restrict dir, const int dplane, const int q,
                      const int sx, const int sxy, const REAL e2, const REAL r, REAL out[NC])
{
    PSI_STEPS(ex, ey, ez, sx, sxy);
    REAL wc[NC][3], wx[NC][3], wy[NC][3], wz[NC][3];
    const REAL g2 = flow_flux(u, uplane, i, ex, ey, ez, psi, dir, dplane, q, sx, sxy, e2, i, wc);
    flow_flux(u, uplane, i - ex, ex, ey, ez, psi, dir, dplane, q - qx_, sx, sxy, e2, i, wx);
    flow_flux(u, uplane, i - ey, ex, ey, ez, psi, dir, dplane, q - qy_, sx, sxy, e2, i, wy);
    flow_flux(u, uplane, i - ez, ex, ey, ez, psi, dir, dplane, q - qz_, sx, sxy, e2, i, wz);
#if WEIGHTED
    const vec3r n = psi_normal(psi, q, sx, sxy);
    const REAL inv_len = RSQRT(n.x * n.x + n.y * n.y + n.z * n.z + (REAL)1e-30);
#else
    const REAL inv_len = 1;
#endif
    #pragma unroll
    for (int c = 0; c < NC; ++c) {
        const REAL uc = u[c * uplane + i];
        const REAL div = ONE_SIDED_SIGN(ex) * (wc[c][0] - wx[c][0]) +
                         ONE_SIDED_SIGN(ey) * (wc[c][1] - wy[c][1]) +
                         ONE_SIDED_SIGN(ez) * (wc[c][2] - wz[c][2]);
        out[c] = flow_update(uc, div, inv_len, g2, r);
    }
}

// Per-cell terms of the surface integrals that set TV's dynamic lambda (C.2) and measure the
// residual: with a smeared delta of half-width eps_cells (grid units),
//   num  = delta (v - v0) . P v / |P v|_e,  area = delta,  resid = delta (u - u0)^2.
// u and u0 share a layout (cell i, offsets ex, ey, ez); psi at q.
typedef struct { REAL num, area, resid; } lambda_terms;

INLINE lambda_terms lambda_terms_cell(U_SPACE const REAL* restrict u, U_SPACE const REAL* restrict u0, const int i,
                              const int ex, const int ey, const int ez,
                              __global const REAL* restrict psi, const int q, const int sx,
                              const int sxy, const REAL inv_h, const REAL eps_cells,
                              const REAL e2)
{
    const REAL d = psi[q] * inv_h;
    const REAL delta = FABS(d) < eps_cells
        ? (1 + cos((REAL)M_PI * d / eps_cells)) / (2 * eps_cells) : (REAL)0;
    const vec3r n = psi_normal(psi, q, sx, sxy);
    const REAL nn = n.x * n.x + n.y * n.y + n.z * n.z + (REAL)1e-30;
    const REAL vx = ONE_SIDED_SIGN(ex) * (u[i + ex] - u[i]);
    const REAL vy = ONE_SIDED_SIGN(ey) * (u[i + ey] - u[i]);
    const REAL vz = ONE_SIDED_SIGN(ez) * (u[i + ez] - u[i]);
    const REAL s = (n.x * vx + n.y * vy + n.z * vz) / nn;
    const REAL px = vx - s * n.x, py = vy - s * n.y, pz = vz - s * n.z;
    const REAL ax = vx - ONE_SIDED_SIGN(ex) * (u0[i + ex] - u0[i]);
    const REAL ay = vy - ONE_SIDED_SIGN(ey) * (u0[i + ey] - u0[i]);
    const REAL az = vz - ONE_SIDED_SIGN(ez) * (u0[i + ez] - u0[i]);
    lambda_terms t;
    t.num = delta * (ax * px + ay * py + az * pz) * RSQRT(px * px + py * py + pz * pz + e2);
    t.area = delta;
    t.resid = delta * SQR(u[i] - u0[i]);
    return t;
}

#endif
