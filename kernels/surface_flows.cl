// The other band flows (clpde/surface/flows.py): TV (4.10), harmonic maps (4.11, D.7),
// diffusion along a tangent field (4.15), TV's fidelity and dynamic lambda (C.1, C.2).
// Defines: NC, FLOW_P, HARMONIC, FIDELITY, ALONG, WEIGHTED, LINE_FIELD (the lambda kernels
// use none: the host looks them up with its flow's defines, so they come from the same
// program). Layout and conventions: surface.h.
#include "common.cl"
#include "reduce.h"
#include "surface.h"

#ifndef WEIGHTED
#define WEIGHTED 0
#endif

// ---- the other band flows, one work-item per cell handling all NC channels ----------------
//
// Flux at cell j for channel c: w_c = |N| G P_N v_c (|N| only when WEIGHTED), with
//   G = 1                               FLOW_P 2: heat (4.7/4.8), harmonic map p = 2 (D.7)
//   G = (|P v|^2 + e2)^(-1/2)           FLOW_P 1: TV (4.10), harmonic map p = 1 (4.11)
// where |P v|^2 sums over the channels (the vectorial gradient of appendix D); with ALONG the
// flux is |N| (d . P_N v_c) d for a tangent field d (3 channels of `dir`): eqs. (4.14), (4.15).
// The step is v_c = u_c + r (div w_c / |N| + HARMONIC u_c |P v|^p) - dt lambda (u_c - u0_c)
// (FIDELITY, C.1), with r = dt / h^p (dt / h^2 with ALONG), e2 = (h eps)^2. lambda is a
// one-value device buffer, so the dynamic lambda (tv_lambda_update) never visits the host.
#ifndef FLOW_P
#define FLOW_P 2
#endif
#ifndef HARMONIC
#define HARMONIC 0
#endif
#ifndef FIDELITY
#define FIDELITY 0
#endif
#ifndef ALONG
#define ALONG 0
#endif

// The channel loops are unrolled (#pragma unroll, NC is a constant) so the loop over a run's
// cells is the innermost one, which PoCL's vectoriser widens.
INLINE REAL flow_flux(__global const REAL* restrict u, __global const REAL* restrict psi,
                      __global const REAL* restrict dir, const int j, const int ex,
                      const int ey, const int ez, const int sx, const int sxy, const int plane,
                      const REAL e2, const int ref, REAL w[NC][3])
{
#if LINE_FIELD
    const REAL s0 = line_sign(u, ref, j, plane), s1 = line_sign(u, ref, j + ex, plane);
    const REAL s2 = line_sign(u, ref, j + ey, plane), s3 = line_sign(u, ref, j + ez, plane);
#else
    const REAL s0 = 1, s1 = 1, s2 = 1, s3 = 1;
#endif
    const vec3r n = psi_normal(psi, j, sx, sxy);
    const REAL nn = n.x * n.x + n.y * n.y + n.z * n.z + (REAL)1e-30;
#if WEIGHTED
    const REAL len = SQRT(nn);
#else
    const REAL len = 1;
#endif
    REAL g2 = 0;
    #pragma unroll
    for (int c = 0; c < NC; ++c) {
        const int jc = c * plane + j;
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
    const REAL dx = dir[j], dy = dir[plane + j], dz = dir[2 * plane + j];
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

__kernel void flow_step(__global const REAL* restrict u, __global REAL* restrict v,
                        __global const REAL* restrict psi, __global const REAL* restrict dir,
                        __global const REAL* restrict u0, const REAL r, const REAL dt,
                        __global const REAL* restrict lambda, const REAL e2, const int ex, const int ey,
                        const int ez, const int sx, const int sxy, RUN_ARGS)
{
    FOR_EACH_RUN_CELL(i) {
        REAL wc[NC][3], wx[NC][3], wy[NC][3], wz[NC][3];
        const REAL g2 = flow_flux(u, psi, dir, i, ex, ey, ez, sx, sxy, plane, e2, i, wc);
        flow_flux(u, psi, dir, i - ex, ex, ey, ez, sx, sxy, plane, e2, i, wx);
        flow_flux(u, psi, dir, i - ey, ex, ey, ez, sx, sxy, plane, e2, i, wy);
        flow_flux(u, psi, dir, i - ez, ex, ey, ez, sx, sxy, plane, e2, i, wz);
#if WEIGHTED
        const vec3r n = psi_normal(psi, i, sx, sxy);
        const REAL inv_len = RSQRT(n.x * n.x + n.y * n.y + n.z * n.z + (REAL)1e-30);
#else
        const REAL inv_len = 1;
#endif
        #pragma unroll
        for (int c = 0; c < NC; ++c) {
            const int ic = c * plane + i;
            const REAL div = ONE_SIDED_SIGN(ex) * (wc[c][0] - wx[c][0]) +
                             ONE_SIDED_SIGN(ey) * (wc[c][1] - wy[c][1]) +
                             ONE_SIDED_SIGN(ez) * (wc[c][2] - wz[c][2]);
            REAL rate = div * inv_len;
#if HARMONIC && FLOW_P == 2
            rate += u[ic] * g2;
#elif HARMONIC
            rate += u[ic] * SQRT(g2);
#endif
            REAL val = u[ic] + r * rate;
#if FIDELITY
            val -= dt * lambda[0] * (u[ic] - u0[ic]);
#endif
            v[ic] = val;
        }
    }
}

// Per-cell terms of the surface integrals that set TV's dynamic lambda (C.2) and measure the
// residual: with a smeared delta of half-width eps_cells (grid units),
//   num  = delta (v - v0) . P v / |P v|_e,  area = delta,  resid = delta (u - u0)^2.
__kernel void tv_lambda_terms(__global const REAL* restrict u, __global const REAL* restrict u0,
                              __global const REAL* restrict psi, const REAL inv_h,
                              const REAL eps_cells, const REAL e2, const int ex, const int ey,
                              const int ez, const int sx, const int sxy,
                              __global REAL* restrict num, __global REAL* restrict area,
                              __global REAL* restrict resid, LIST_ARGS)
{
    LIST_RANGE(k0, k1, chan);
    for (int k = k0; k < k1; ++k) {
        const int i = list[k];
        const REAL d = psi[i] * inv_h;
        const REAL delta = FABS(d) < eps_cells
            ? (1 + cos((REAL)M_PI * d / eps_cells)) / (2 * eps_cells) : (REAL)0;
        const vec3r n = psi_normal(psi, i, sx, sxy);
        const REAL nn = n.x * n.x + n.y * n.y + n.z * n.z + (REAL)1e-30;
        const REAL vx = ONE_SIDED_SIGN(ex) * (u[i + ex] - u[i]);
        const REAL vy = ONE_SIDED_SIGN(ey) * (u[i + ey] - u[i]);
        const REAL vz = ONE_SIDED_SIGN(ez) * (u[i + ez] - u[i]);
        const REAL s = (n.x * vx + n.y * vy + n.z * vz) / nn;
        const REAL px = vx - s * n.x, py = vy - s * n.y, pz = vz - s * n.z;
        const REAL ax = vx - ONE_SIDED_SIGN(ex) * (u0[i + ex] - u0[i]);
        const REAL ay = vy - ONE_SIDED_SIGN(ey) * (u0[i + ey] - u0[i]);
        const REAL az = vz - ONE_SIDED_SIGN(ez) * (u0[i + ez] - u0[i]);
        num[k] = delta * (ax * px + ay * py + az * pz) * RSQRT(px * px + py * py + pz * pz + e2);
        area[k] = delta;
        resid[k] = delta * SQR(u[i] - u0[i]);
    }
}

// Partial sums of a band-length array: work-item g adds entries [g*chunk, (g+1)*chunk).
// The host adds the few partials (band / chunk numbers).
__kernel void chunk_sum(__global const REAL* restrict a, const int n, const int chunk,
                        __global REAL* restrict partial)
{
    const int g = get_global_id(0);
    if (g >= max(1, (n + chunk - 1) / chunk)) return;  // past the last chunk (Runtime.items)
    const int end = min((g + 1) * chunk, n);
    partial[g] = sum_rows(a + g * chunk, end - g * chunk);
}

// Dynamic lambda of (C.2) from the chunk sums of tv_lambda_terms' num, area and resid:
// lambda = f max(0, -num / (h sigma^2 area)) (scale = 1 / (h sigma^2)), capped at lam_max,
// the largest lambda the time step keeps stable (capped[0] = 1 then), kept in history[slot].
// f (state[0], starting at 1) corrects (C.2) toward the constraint it is derived from, a
// residual variance of sigma^2: at a steady state the continuous identity
// lambda |u - u0|^2 = -integral (u - u0) div(...) makes (C.2)'s lambda give exactly that,
// but the discrete one does not hold (one-sided differences of one side choice against a
// flow cycling through eight, closest-point re-extension), and for noise at the grid's
// scale the plain formula settled at 1.2-1.6 sigma^2. Once the residual has passed half of
// sigma^2, each update multiplies f by residual / sigma^2, limited to [0.67, 1.5] per
// update and f to [0.1, 10]: f stops moving only where the residual is sigma^2 (on a
// sphere within 1-4% after t = 0.08, 40 updates). inv_sigma2 = 0 keeps f = 1: plain (C.2).
// One work-item: the partial sums are a few hundred numbers.
__kernel void tv_lambda_update(__global const REAL* restrict num, __global const REAL* restrict area,
                               __global const REAL* restrict resid, const int groups,
                               const REAL scale, const REAL inv_sigma2, const REAL lam_max,
                               __global REAL* restrict lambda, __global REAL* restrict state,
                               __global REAL* restrict history, const int slot,
                               __global int* restrict capped)
{
    REAL sum_num = 0, sum_area = 0, sum_resid = 0;
    for (int g = 0; g < groups; ++g) {
        sum_num += num[g];
        sum_area += area[g];
        sum_resid += resid[g];
    }
    const REAL ratio = sum_area > 0 ? sum_resid * inv_sigma2 / sum_area : (REAL)0;
    REAL f = state[0];
    if (ratio > (REAL)0.5) {
        f *= FMIN(FMAX(ratio, (REAL)0.67), (REAL)1.5);
        f = FMIN(FMAX(f, (REAL)0.1), (REAL)10);
        state[0] = f;
    }
    REAL lam = sum_area > 0 ? -sum_num * scale / sum_area : (REAL)0;
    lam = lam > 0 ? f * lam : (REAL)0;
    if (lam > lam_max) {
        lam = lam_max;
        capped[0] = 1;
    }
    lambda[0] = lam;
    history[slot] = lam;
}
