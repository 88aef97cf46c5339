// Features and discrepancies for tracking real video (clpde.track): local
// contrast normalisation of a frame, and the generalised morphing step over the band with
// several feature channels, a choice of discrepancy and a pull towards a prior level set,
// over a list of band cells (morph_track) or over bricks (bricks2d.h: morph_track_bricks,
// and morph_track_tiled, whose NCC window sums slide over each brick).
//
// Defines (set by the host):
//   NCH   feature channels (1 grey, 3 colour, or a user's count), planes `fplane` apart
//   DISC  0: beta = F2 - F1 (the thesis);  1: local normalised cross-correlation over a
//         (2 WIN + 1)^2 window;  2: Huber, beta = clamp(F2 - F1, -delta, delta)
//   WIN   window radius of DISC 1 (band cells lie MARGIN + G = 4 cells inside the buffer,
//         so WIN <= 4 reads stay inside it)
#include "common.h"
#include "godunov.h"
#include "bricks/bricks2d.h"

#ifndef NCH
#define NCH 1
#endif
#ifndef DISC
#define DISC 0
#endif
#ifndef WIN
#define WIN 3
#endif

// ---- local contrast normalisation ------------------------------------------------------
// out = scale (I - mean) / sqrt(var + eps^2), mean and variance over the (2r + 1)^2 box
// around the cell, its coordinates clamped to the interior (the frame's edge repeats).
// A local change of brightness and contrast, I -> a I + b with a > 0 slowly varying,
// leaves it unchanged up to eps.
__kernel void features_local_contrast(__global const REAL* restrict img, __global REAL* restrict out,
                             const int r, const REAL eps2, const REAL scale, GRID_ARGS)
{
    FOR_EACH_CELL(i) {
        const int c = i % plane, base = i - c;
        const int x = c % sx - G, y = c / sx - G;
        REAL s = 0, s2 = 0;
        for (int dy = -r; dy <= r; ++dy) {
            const int yy = clamp(y + dy, 0, ny - 1);
            for (int dx = -r; dx <= r; ++dx) {
                const int xx = clamp(x + dx, 0, nx - 1);
                const REAL v = img[base + (yy + G) * sx + xx + G];
                s += v;
                s2 += v * v;
            }
        }
        const REAL n = (REAL)((2 * r + 1) * (2 * r + 1));
        const REAL mean = s / n;
        const REAL var = FMAX(s2 / n - mean * mean, (REAL)0);
        out[i] = scale * (img[i] - mean) * RSQRT(var + eps2);
    }
}

// ---- discrepancies ---------------------------------------------------------------------

// The NCC's beta from the window's sums of F1, F2, F1^2, F2^2 and F1 F2, at a cell where
// F1 = a and F2 = b.
INLINE REAL ncc_beta(const REAL s1, const REAL s2, const REAL s11, const REAL s22,
                     const REAL s12, const REAL a, const REAL b, const REAL delta)
{
    const REAL n = (REAL)((2 * WIN + 1) * (2 * WIN + 1));
    const REAL m1 = s1 / n, m2 = s2 / n;
    const REAL v1 = FMAX(s11 / n - m1 * m1, (REAL)0) + delta * delta;
    const REAL v2 = FMAX(s22 / n - m2 * m2, (REAL)0) + delta * delta;
    const REAL rho = (s12 / n - m1 * m2) * RSQRT(v1 * v2);
    return SQRT(v1 / v2) * (b - m2) - rho * (a - m1);
}

// beta of one channel at padded index i (f1, f2 point at that channel's plane).
INLINE REAL discrepancy(__global const REAL* f1, __global const REAL* f2, const int i,
                        const int sx, const REAL delta)
{
#if DISC == 1
    // The steepest ascent of the window's correlation rho(F1, F2) with respect to F1(x),
    // scaled by sigma1 to keep F1's units:
    //     beta = (sigma1 / sigma2) (F2 - mu2) - rho (F1 - mu1).
    // Zero where F2 is locally an increasing affine map of F1 (a change of brightness
    // and contrast); delta^2 regularises the variances of flat windows.
    REAL s1 = 0, s2 = 0, s11 = 0, s22 = 0, s12 = 0;
    for (int dy = -WIN; dy <= WIN; ++dy) {
        for (int dx = -WIN; dx <= WIN; ++dx) {
            const int j = i + dy * sx + dx;
            const REAL a = f1[j], b = f2[j];
            s1 += a; s2 += b; s11 += a * a; s22 += b * b; s12 += a * b;
        }
    }
    return ncc_beta(s1, s2, s11, s22, s12, f1[i], f2[i], delta);
#elif DISC == 2
    return clamp(f2[i] - f1[i], -delta, delta);
#else
    return f2[i] - f1[i];
#endif
}

// ---- the generalised morphing step -----------------------------------------------------
// Over the band cells, for each channel c: beta_c from `discrepancy`, and
//     F1_c <- F1_c + dt beta_c |grad F1_c|                         (morphing, upwind)
//     u    <- u + dt [ sum_c beta_c (grad F1_c . grad u)
//                       / sqrt((sum_c |grad F1_c|^2 + eps_f^2) (|grad u|^2 + eps_u^2))
//                       |grad u|_upwind + lam (prior - u) ]
// With one channel, DISC 0 and lam = 0 this is the thesis' coupled step (eqs. 2.3-2.6;
// tests/reference/levelset.py's morph_step): the contour moves with the projection of the
// channels' morphing velocities on its normal, channels with stronger edges weighing more.
// eps_f and eps_u keep the normals finite where a field is flat (no information there, so
// the projected velocity fades to zero). The lam term relaxes u towards the prior level set
// (the frame's predicted start), which holds the contour where the features say nothing
// and damps leaks.
// stats per work-item g of n: [g] max |du/dt|, [n+g] max |beta|, [2n+g] max |grad F1|,
// [3n+g] sum over its cells of the channels' mean |beta|, [4n+g] its cell count; [5n] the
// edge flag: set to 1 when an edge-ring cell of the band (band == 2) comes within `near` of
// the zero level set, which asks the host to rebuild the band.

// What a work-item gathers over its cells for the host's checks.
typedef struct {
    REAL fastest, beta_max, grad_max, beta_sum, cells;
    int touched;
} MorphStats;

// The step at band cell i given each channel's beta there (any band layout: the list and
// brick kernels below call it).
INLINE void morph_cell_beta(__global const REAL* restrict u, __global const REAL* restrict f1,
                            __global const uchar* restrict band,
                            __global const REAL* restrict prior, __global REAL* restrict u_out,
                            __global REAL* restrict f1_out, const int i, const REAL dt,
                            const REAL eps_f2, const REAL eps_u2, const REAL near,
                            const REAL lam, const int sx, const int fplane,
                            const REAL* betas, MorphStats* s)
{
    const REAL ux = (REAL)0.5 * (u[i + 1] - u[i - 1]);
    const REAL uy = (REAL)0.5 * (u[i + sx] - u[i - sx]);
    REAL proj = 0, gsum = 0, babs = 0;
    for (int c = 0; c < NCH; ++c) {
        const int j = i + c * fplane;
        const REAL beta = betas[c];
        const REAL grad_f = upwind_norm_2d(f1 + c * fplane, i, sx, beta);
        f1_out[j] = f1[j] + dt * beta * grad_f;
        const REAL fx = (REAL)0.5 * (f1[j + 1] - f1[j - 1]);
        const REAL fy = (REAL)0.5 * (f1[j + sx] - f1[j - sx]);
        proj += beta * (fx * ux + fy * uy);
        gsum += SQR(fx) + SQR(fy);
        s->beta_max = FMAX(s->beta_max, FABS(beta));
        s->grad_max = FMAX(s->grad_max, grad_f);
        babs += FABS(beta);
    }
    const REAL bhat = proj * RSQRT((gsum + eps_f2) * (SQR(ux) + SQR(uy) + eps_u2));
    const REAL rate = bhat * upwind_norm_2d(u, i, sx, bhat) + lam * (prior[i] - u[i]);
    const REAL un = u[i] + dt * rate;
    u_out[i] = un;
    s->fastest = FMAX(s->fastest, FABS(rate));
    s->beta_sum += babs / NCH;
    s->cells += 1;
    s->touched |= (band[i] == 2) & (FABS(un) < near);
}

// The same with beta from `discrepancy`, cell by cell.
INLINE void morph_cell(__global const REAL* restrict u, __global const REAL* restrict f1,
                       __global const REAL* restrict f2, __global const uchar* restrict band,
                       __global const REAL* restrict prior, __global REAL* restrict u_out,
                       __global REAL* restrict f1_out, const int i, const REAL dt,
                       const REAL eps_f2, const REAL eps_u2, const REAL near, const REAL lam,
                       const REAL delta, const int sx, const int fplane, MorphStats* s)
{
    REAL betas[NCH];
    for (int c = 0; c < NCH; ++c)
        betas[c] = discrepancy(f1 + c * fplane, f2 + c * fplane, i, sx, delta);
    morph_cell_beta(u, f1, band, prior, u_out, f1_out, i, dt, eps_f2, eps_u2, near, lam, sx,
                    fplane, betas, s);
}

INLINE void morph_stats_store(__global REAL* restrict stats, const MorphStats* s)
{
    const int g = get_global_id(0), n = get_global_size(0);
    stats[g] = s->fastest;
    stats[n + g] = s->beta_max;
    stats[2 * n + g] = s->grad_max;
    stats[3 * n + g] = s->beta_sum;
    stats[4 * n + g] = s->cells;
    if (s->touched) stats[5 * n] = 1;
}

#define MORPH_ARGS                                                                        \
    __global const REAL* restrict u, __global const REAL* restrict f1,                    \
    __global const REAL* restrict f2, __global const uchar* restrict band,                \
    __global const REAL* restrict prior, __global REAL* restrict u_out,                   \
    __global REAL* restrict f1_out, __global REAL* restrict stats, const REAL dt,         \
    const REAL eps_f2, const REAL eps_u2, const REAL near, const REAL lam,                \
    const REAL delta, const int sx, const int fplane
#define MORPH_CELL(i)                                                                     \
    morph_cell(u, f1, f2, band, prior, u_out, f1_out, i, dt, eps_f2, eps_u2, near, lam,   \
               delta, sx, fplane, &s)

__kernel void features_morph_track(MORPH_ARGS, LIST_ARGS)
{
    LIST_RANGE(k0, k1, chan);
    MorphStats s = {0, 0, 0, 0, 0, 0};
    for (int k = k0; k < k1; ++k) MORPH_CELL(chan + list[k]);
    morph_stats_store(stats, &s);
}

// The same step over the band's bricks (bricks2d.h), at the cells where band > 0.
__kernel void features_morph_track_bricks(MORPH_ARGS, BRICK2D_ARGS)
{
    MorphStats s = {0, 0, 0, 0, 0, 0};
    FOR_EACH_BRICK_CELL(i) {
        if (band[i]) MORPH_CELL(i);
    }
    morph_stats_store(stats, &s);
}

#if DISC == 1 && !GROUP_PER_BRICK
// morph_track_bricks with the NCC's window sums slid over each brick instead of summed
// cell by cell: per brick row, each tile column's vertical sums are updated by one row in
// and one out, then slid along the row. About 3x fewer reads and adds than 49 per cell; the
// sums round differently from discrepancy's, so results agree with it to rounding only.
__kernel void features_morph_track_tiled(MORPH_ARGS, BRICK2D_ARGS)
{
    MorphStats s = {0, 0, 0, 0, 0, 0};
    const int b0 = get_global_id(0) * per_item, b1 = min(b0 + per_item, nbricks);
    for (int b = b0; b < b1; ++b) {
        const int ox = x0 + (bricks[b] % nbx) * BX, oy = y0 + (bricks[b] / nbx) * BY;
        const int nxb = min(BX, x1 - ox), nyb = min(BY, y1 - oy), ncol = nxb + 2 * WIN;
        REAL betas[BY * BX * NCH];
        for (int c = 0; c < NCH; ++c) {
            __global const REAL* a = f1 + c * fplane;
            __global const REAL* q = f2 + c * fplane;
            REAL col[5][BX + 2 * WIN];
            for (int y = 0; y < nyb; ++y) {
                const int row = (oy + y) * sx + ox - WIN;
                for (int t = 0; t < ncol; ++t) {
                    if (y == 0) {
                        REAL c1 = 0, c2 = 0, c11 = 0, c22 = 0, c12 = 0;
                        for (int dy = -WIN; dy <= WIN; ++dy) {
                            const REAL va = a[row + dy * sx + t], vb = q[row + dy * sx + t];
                            c1 += va; c2 += vb; c11 += va * va; c22 += vb * vb; c12 += va * vb;
                        }
                        col[0][t] = c1; col[1][t] = c2; col[2][t] = c11; col[3][t] = c22;
                        col[4][t] = c12;
                    } else {
                        const int in = row + WIN * sx + t, out = row - (WIN + 1) * sx + t;
                        const REAL ia = a[in], ib = q[in], oa = a[out], ob = q[out];
                        col[0][t] += ia - oa;
                        col[1][t] += ib - ob;
                        col[2][t] += ia * ia - oa * oa;
                        col[3][t] += ib * ib - ob * ob;
                        col[4][t] += ia * ib - oa * ob;
                    }
                }
                REAL h[5] = {0, 0, 0, 0, 0};
                for (int t = 0; t < 2 * WIN + 1; ++t)
                    for (int k = 0; k < 5; ++k) h[k] += col[k][t];
                for (int x = 0; x < nxb; ++x) {
                    if (x > 0)
                        for (int k = 0; k < 5; ++k) h[k] += col[k][x + 2 * WIN] - col[k][x - 1];
                    const int i = row + WIN + x;
                    betas[(y * BX + x) * NCH + c] =
                        ncc_beta(h[0], h[1], h[2], h[3], h[4], a[i], q[i], delta);
                }
            }
        }
        for (int y = 0; y < nyb; ++y)
            for (int x = 0; x < nxb; ++x) {
                const int i = (oy + y) * sx + ox + x;
                if (band[i])
                    morph_cell_beta(u, f1, band, prior, u_out, f1_out, i, dt, eps_f2, eps_u2,
                                    near, lam, sx, fplane, betas + (y * BX + x) * NCH, &s);
            }
    }
    morph_stats_store(stats, &s);
}
#endif
