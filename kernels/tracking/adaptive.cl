// The adaptive morphing step of clpde.track (discrepancy='adaptive'): over the band, per
// feature channel, beta blends the local normalised cross-correlation's steepest ascent and
// the plain difference F2 - F1 by how much contrast the window holds against the frame's
// noise; the contour's speed adds a region term (a foreground / background likelihood
// field computed on the host from the statistics near the contour) and a curvature term.
//
// Defines (set by the host):
//   NCH   feature channels, planes `fplane` apart
//   WIN   window radius of the correlation (band cells lie MARGIN + G = 4 cells inside the
//         buffer, so WIN <= 4 reads stay inside it)
//   FRONT_ONLY  1: the stopping test reads the speed at the cells next to the contour only
//         (|u| < 1), for the region and curvature terms, which keep the band's outer cells
//         moving; 0: at every band cell, as morph_track's test does
#include "common.h"
#include "godunov.h"
#include "bricks/bricks2d.h"

#ifndef NCH
#define NCH 1
#endif
#ifndef WIN
#define WIN 3
#endif
#ifndef FRONT_ONLY
#define FRONT_ONLY 1
#endif

// beta of one channel at padded index i: w beta_ncc + (1 - w) (F2 - F1), where
//     beta_ncc = (sigma1 / sigma2) (F2 - mu2) - rho (F1 - mu1)
// (delta^2 regularising the variances, as track_features.cl's ncc_beta) and
//     w = s / (s + noise2),   s = min(var1, var2)
// the windows' smaller variance against the frame's noise variance: a patch with contrast
// well above the noise is compared by its correlation (blind to light), a flat or noisy
// one by its grey levels (the correlation of noise is noise).
INLINE REAL adaptive_beta_of_sums(const REAL s1, const REAL s2, const REAL s11, const REAL s22,
                                  const REAL s12, const REAL a, const REAL b, const REAL delta,
                                  const REAL noise2)
{
    const REAL n = (REAL)((2 * WIN + 1) * (2 * WIN + 1));
    const REAL m1 = s1 / n, m2 = s2 / n;
    const REAL c1 = FMAX(s11 / n - m1 * m1, (REAL)0), c2 = FMAX(s22 / n - m2 * m2, (REAL)0);
    const REAL v1 = c1 + delta * delta, v2 = c2 + delta * delta;
    const REAL rho = (s12 / n - m1 * m2) * RSQRT(v1 * v2);
    const REAL ncc = SQRT(v1 / v2) * (b - m2) - rho * (a - m1);
    const REAL s = FMIN(c1, c2);
    const REAL w = s / (s + noise2);
    return w * ncc + ((REAL)1 - w) * (b - a);
}

// (the window's sums s1, s2, s11, s22, s12 of F1, F2, F1^2, F2^2, F1 F2, then the formula)
INLINE REAL adaptive_beta(__global const REAL* f1, __global const REAL* f2, const int i,
                          const int sx, const REAL delta, const REAL noise2)
{
    REAL s1 = 0, s2 = 0, s11 = 0, s22 = 0, s12 = 0;
    for (int dy = -WIN; dy <= WIN; ++dy) {
        for (int dx = -WIN; dx <= WIN; ++dx) {
            const int j = i + dy * sx + dx;
            const REAL a = f1[j], b = f2[j];
            s1 += a; s2 += b; s11 += a * a; s22 += b * b; s12 += a * b;
        }
    }
    return adaptive_beta_of_sums(s1, s2, s11, s22, s12, f1[i], f2[i], delta, noise2);
}

#if NCH > 1 && NCH <= 4
#ifdef REAL_IS_DOUBLE
#define REALV double4
#else
#define REALV float4
#endif
// adaptive_beta of NCH (2 to 4) channels at once, planes `fplane` apart, into beta[c]: the
// channels' window sums in the lanes of 4-vectors, each lane's in adaptive_beta's order
// (the same values), so that the channels' chains of dependent additions run side by side,
// not one after another (colour=True's step 1.5x faster on PoCL; issue 35, docs/tracking.md).
INLINE void adaptive_betas(__global const REAL* f1, __global const REAL* f2, const int i,
                           const int sx, const int fplane, const REAL delta, const REAL noise2,
                           REAL* beta)
{
    REALV s1 = 0, s2 = 0, s11 = 0, s22 = 0, s12 = 0;
    for (int dy = -WIN; dy <= WIN; ++dy) {
        for (int dx = -WIN; dx <= WIN; ++dx) {
            const int j = i + dy * sx + dx;
            REALV a = 0, b = 0;
            a.s0 = f1[j]; b.s0 = f2[j];
            a.s1 = f1[j + fplane]; b.s1 = f2[j + fplane];
#if NCH > 2
            a.s2 = f1[j + 2 * fplane]; b.s2 = f2[j + 2 * fplane];
#endif
#if NCH > 3
            a.s3 = f1[j + 3 * fplane]; b.s3 = f2[j + 3 * fplane];
#endif
            s1 += a; s2 += b; s11 += a * a; s22 += b * b; s12 += a * b;
        }
    }
    const REAL t1[4] = {s1.s0, s1.s1, s1.s2, s1.s3}, t2[4] = {s2.s0, s2.s1, s2.s2, s2.s3};
    const REAL t11[4] = {s11.s0, s11.s1, s11.s2, s11.s3};
    const REAL t22[4] = {s22.s0, s22.s1, s22.s2, s22.s3};
    const REAL t12[4] = {s12.s0, s12.s1, s12.s2, s12.s3};
    for (int c = 0; c < NCH; ++c) {
        const int k = i + c * fplane;
        beta[c] = adaptive_beta_of_sums(t1[c], t2[c], t11[c], t22[c], t12[c], f1[k], f2[k],
                                        delta, noise2);
    }
}
#endif

typedef struct {
    REAL fastest, beta_max, grad_max, beta_sum, cells;
    int touched;
} AdaptiveStats;

// One cell:  F1_c <- F1_c + dt beta_c |grad F1_c|  and
//   u <- u + dt [ S |grad u|_upwind(S) + mu kappa |grad u| + lam (prior - u) ],
//   S = kd sum_c beta_c (grad F1_c . grad u) / sqrt((sum_c |grad F1_c|^2 + eps_f^2)
//       (|grad u|^2 + eps_u^2)) + region,
// kappa |grad u| by central differences (u negative inside: positive S or kappa shrink).
INLINE void adaptive_cell(__global const REAL* restrict u, __global const REAL* restrict f1,
                          __global const REAL* restrict f2, __global const uchar* restrict band,
                          __global const REAL* restrict prior, __global REAL* restrict u_out,
                          __global REAL* restrict f1_out, __global const REAL* restrict region,
                          const int i, const REAL dt, const REAL eps_f2, const REAL eps_u2,
                          const REAL near, const REAL lam, const REAL delta, const REAL noise2,
                          const REAL mu, const REAL kd, const int sx, const int fplane,
                          AdaptiveStats* s)
{
    const REAL ux = (REAL)0.5 * (u[i + 1] - u[i - 1]);
    const REAL uy = (REAL)0.5 * (u[i + sx] - u[i - sx]);
    REAL proj = 0, gsum = 0, babs = 0;
#if NCH > 1 && NCH <= 4
    REAL betas[NCH];
    adaptive_betas(f1, f2, i, sx, fplane, delta, noise2, betas);
#endif
    for (int c = 0; c < NCH; ++c) {
        const int j = i + c * fplane;
#if NCH > 1 && NCH <= 4
        const REAL beta = betas[c];
#else
        const REAL beta = adaptive_beta(f1 + c * fplane, f2 + c * fplane, i, sx, delta, noise2);
#endif
        const REAL grad_f = upwind_norm_2d(f1 + c * fplane, i, sx, beta);
        f1_out[j] = f1[j] + dt * beta * grad_f;
        const REAL fx = (REAL)0.5 * (f1[j + 1] - f1[j - 1]);
        const REAL fy = (REAL)0.5 * (f1[j + sx] - f1[j - sx]);
        proj += beta * (fx * ux + fy * uy);
        gsum += SQR(fx) + SQR(fy);
        s->grad_max = FMAX(s->grad_max, grad_f);
        s->beta_max = FMAX(s->beta_max, FABS(beta));
        babs += FABS(beta);
    }
    const REAL g2 = SQR(ux) + SQR(uy);
    const REAL speed = kd * proj * RSQRT((gsum + eps_f2) * (g2 + eps_u2)) + region[i];
    const REAL uxx = u[i + 1] - 2 * u[i] + u[i - 1];
    const REAL uyy = u[i + sx] - 2 * u[i] + u[i - sx];
    const REAL uxy = (REAL)0.25 * (u[i + sx + 1] - u[i + sx - 1] - u[i - sx + 1] + u[i - sx - 1]);
    const REAL curv = (uxx * SQR(uy) - 2 * ux * uy * uxy + uyy * SQR(ux)) / (g2 + eps_u2);
    const REAL rate = speed * upwind_norm_2d(u, i, sx, speed) + mu * curv
                      + lam * (prior[i] - u[i]);
    const REAL un = u[i] + dt * rate;
    u_out[i] = un;
    s->beta_max = FMAX(s->beta_max, FABS(speed));
    // Whether the contour has stopped: with FRONT_ONLY, the speed at the cells next to it
    // (the region term keeps the band's outer cells moving towards their own balance).
    if (!FRONT_ONLY || FABS(u[i]) < (REAL)1) s->fastest = FMAX(s->fastest, FABS(rate));
    s->beta_sum += babs / NCH;
    s->cells += 1;
    s->touched |= (band[i] == 2) & (FABS(un) < near);
}

INLINE void adaptive_stats_store(__global REAL* restrict stats, const AdaptiveStats* s)
{
    const int g = get_global_id(0), n = get_global_size(0);
    stats[g] = s->fastest;
    stats[n + g] = s->beta_max;
    stats[2 * n + g] = s->grad_max;
    stats[3 * n + g] = s->beta_sum;
    stats[4 * n + g] = s->cells;
    if (s->touched) stats[5 * n] = 1;
}

// Arguments: track_features.cl's morph_track's, then the region field, the noise variance
// the curvature weight and the discrepancy's weight kd; stats as morph_track's (max |beta| covers the speed S).
#define ADAPTIVE_ARGS                                                                     \
    __global const REAL* restrict u, __global const REAL* restrict f1,                    \
    __global const REAL* restrict f2, __global const uchar* restrict band,                \
    __global const REAL* restrict prior, __global REAL* restrict u_out,                   \
    __global REAL* restrict f1_out, __global REAL* restrict stats, const REAL dt,         \
    const REAL eps_f2, const REAL eps_u2, const REAL near, const REAL lam,                \
    const REAL delta, const int sx, const int fplane,                                     \
    __global const REAL* restrict region, const REAL noise2, const REAL mu, const REAL kd
#define ADAPTIVE_CELL(i)                                                                  \
    adaptive_cell(u, f1, f2, band, prior, u_out, f1_out, region, i, dt, eps_f2, eps_u2,   \
                  near, lam, delta, noise2, mu, kd, sx, fplane, &s)

__kernel void adaptive_morph_adaptive(ADAPTIVE_ARGS, LIST_ARGS)
{
    LIST_RANGE(k0, k1, chan);
    AdaptiveStats s = {0, 0, 0, 0, 0, 0};
    for (int k = k0; k < k1; ++k) ADAPTIVE_CELL(chan + list[k]);
    adaptive_stats_store(stats, &s);
}

// The same over the band's bricks (bricks2d.h), at the cells where band > 0.
__kernel void adaptive_morph_adaptive_bricks(ADAPTIVE_ARGS, BRICK2D_ARGS)
{
    AdaptiveStats s = {0, 0, 0, 0, 0, 0};
    FOR_EACH_BRICK_CELL(i) {
        if (band[i]) ADAPTIVE_CELL(i);
    }
    adaptive_stats_store(stats, &s);
}
