// The region term of clpde.track's adaptive discrepancy (clpde/tracking/region_term.py), on
// the device: Chan-Vese-like local statistics of the inside and the outside of the contour
// (u < 0), from Gaussian windows computed at half resolution, and each pixel's
// log-likelihood ratio of the two sides, weighted by how well they separate there.
//
// The steps, one launch each (all sizes are arguments: one build serves every frame size):
//   region_moments   2x2 means (edge-replicated for odd sizes) of the side masks m, 1 - m
//                    and of m f, (1 - m) f, m f^2, (1 - m) f^2 for each of K features f:
//                    2 + 4K planes at half resolution;
//   blur_cols,       a Gaussian blur, separable, clamped at the edges (scipy's 'nearest'),
//   blur_rows        with the host's normalised weights: columns (axis 0) first, as scipy;
//   region_llr       per full-resolution pixel, the half-resolution statistics of its 2x2
//                    block: L = sum_k ((f - mi)^2 - (f - mo)^2) / (vi + vo), and the weight
//                    cover B / (B + separation), B the summed Bhattacharyya distance;
//   (blur_cols, blur_rows again: L pooled over neighbouring pixels)
//   region_speed     speed = scale weight tanh(L / 2) written into the level set's grid.
#include "common.h"

// 2 + 4K planes of (ny2, nx2): m, 1 - m, then per feature k: m f, (1 - m) f, m f^2,
// (1 - m) f^2. u: the level set's padded buffer, the frame's (0, 0) at u[off], rows `sx`
// apart; feats: K dense (ny, nx) planes.
__kernel void region_moments(__global const REAL* restrict u, __global const REAL* restrict feats,
                             __global REAL* restrict out, const int nx, const int ny,
                             const int nx2, const int ny2, const int nfeat, const int off,
                             const int sx)
{
    const int x = get_global_id(0), y = get_global_id(1);
    if (x >= nx2 || y >= ny2) return;
    // the four pixels in the host's order: (2y, 2x), (2y + 1, 2x), (2y, 2x + 1), (2y + 1, 2x + 1)
    const int x0 = 2 * x, x1 = min(2 * x + 1, nx - 1);
    const int y0 = 2 * y, y1 = min(2 * y + 1, ny - 1);
    const int pix[4] = {y0 * nx + x0, y1 * nx + x0, y0 * nx + x1, y1 * nx + x1};
    const int cell[4] = {off + y0 * sx + x0, off + y1 * sx + x0, off + y0 * sx + x1,
                         off + y1 * sx + x1};
    REAL m[4];
    for (int k = 0; k < 4; ++k) m[k] = u[cell[k]] < 0 ? (REAL)1 : (REAL)0;
    const int plane2 = nx2 * ny2, at = y * nx2 + x, plane = nx * ny;
    const REAL q = (REAL)0.25;
    out[at] = q * (m[0] + m[1] + m[2] + m[3]);
    out[plane2 + at] = q * (((REAL)1 - m[0]) + ((REAL)1 - m[1]) + ((REAL)1 - m[2]) + ((REAL)1 - m[3]));
    for (int c = 0; c < nfeat; ++c) {
        REAL f[4], sums[4] = {0, 0, 0, 0};
        for (int k = 0; k < 4; ++k) f[k] = feats[c * plane + pix[k]];
        for (int k = 0; k < 4; ++k) {
            const REAL in = m[k] * f[k], outside = ((REAL)1 - m[k]) * f[k];
            sums[0] += in;
            sums[1] += outside;
            sums[2] += in * f[k];
            sums[3] += outside * f[k];
        }
        for (int s = 0; s < 4; ++s) out[(2 + 4 * c + s) * plane2 + at] = q * sums[s];
    }
}

// out = src blurred along columns (y) with weights w[0..2 RADIUS] (the centre at w[RADIUS]),
// the index clamped to [0, ny): `planes` planes of (ny, nx). RADIUS is a define (it follows
// from the Gaussian's sigma, not from the data's size), so the taps unroll; rows whose window
// lies inside the plane take no clamps.
#ifndef RADIUS
#define RADIUS 9
#endif
__kernel void region_blur_cols(__global const REAL* restrict src, __global REAL* restrict out,
                        __constant REAL* restrict w, const int nx, const int ny,
                        const int planes)
{
    const int x = get_global_id(0), y = get_global_id(1), p = get_global_id(2);
    if (x >= nx || y >= ny || p >= planes) return;
    __global const REAL* s = src + p * nx * ny + x;
    REAL acc = 0;
    if (y >= RADIUS && y + RADIUS < ny) {
        for (int k = 0; k <= 2 * RADIUS; ++k) acc += w[k] * s[(y + k - RADIUS) * nx];
    } else {
        for (int k = 0; k <= 2 * RADIUS; ++k) acc += w[k] * s[clamp(y + k - RADIUS, 0, ny - 1) * nx];
    }
    out[p * nx * ny + y * nx + x] = acc;
}

// out = src blurred along rows (x), as blur_cols.
__kernel void region_blur_rows(__global const REAL* restrict src, __global REAL* restrict out,
                        __constant REAL* restrict w, const int nx, const int ny,
                        const int planes)
{
    const int x = get_global_id(0), y = get_global_id(1), p = get_global_id(2);
    if (x >= nx || y >= ny || p >= planes) return;
    __global const REAL* s = src + (p * ny + y) * nx;
    REAL acc = 0;
    if (x >= RADIUS && x + RADIUS < nx) {
        for (int k = 0; k <= 2 * RADIUS; ++k) acc += w[k] * s[x + k - RADIUS];
    } else {
        for (int k = 0; k <= 2 * RADIUS; ++k) acc += w[k] * s[clamp(x + k - RADIUS, 0, nx - 1)];
    }
    out[(p * ny + y) * nx + x] = acc;
}

// Per pixel of (ny, nx): L and the weight, from the blurred moments `stats`
// (region_moments' planes after the blur) of the pixel's 2x2 block. The last feature (the
// texture measure) gets a quarter of the noise variance as its variance floor.
__kernel void region_llr(__global const REAL* restrict stats, __global const REAL* restrict feats,
                         __global REAL* restrict llr_out, __global REAL* restrict weight_out,
                         const int nx, const int ny, const int nx2,
                         const int ny2, const int nfeat, const REAL noise2,
                         const REAL separation)
{
    const int x = get_global_id(0), y = get_global_id(1);
    if (x >= nx || y >= ny) return;
    const int plane2 = nx2 * ny2, at2 = (y / 2) * nx2 + x / 2, plane = nx * ny, at = y * nx + x;
    const REAL a_in0 = stats[at2], a_out0 = stats[plane2 + at2];
    const REAL cover = clamp(FMIN(a_in0, a_out0) / (REAL)0.05, (REAL)0, (REAL)1);
    const REAL a_in = FMAX(a_in0, (REAL)1e-6), a_out = FMAX(a_out0, (REAL)1e-6);
    REAL llr = 0, bhat = 0;
    for (int c = 0; c < nfeat; ++c) {
        const REAL f = feats[c * plane + at];
        const REAL floor = (c == nfeat - 1 ? (REAL)0.25 * noise2 : noise2) + (REAL)1e-4;
        __global const REAL* s = stats + (2 + 4 * c) * plane2 + at2;
        const REAL mi = s[0] / a_in, mo = s[plane2] / a_out;
        const REAL vi = FMAX(s[2 * plane2] / a_in - mi * mi, (REAL)0) + floor;
        const REAL vo = FMAX(s[3 * plane2] / a_out - mo * mo, (REAL)0) + floor;
        const REAL v = vi + vo;
        llr += (SQR(f - mi) - SQR(f - mo)) / v;
        bhat += (REAL)0.25 * SQR(mi - mo) / v + (REAL)0.5 * log(v / ((REAL)2 * SQRT(vi * vo)));
    }
    llr_out[at] = llr;
    weight_out[at] = cover * bhat / (bhat + separation);
}

// The region speed on the level set's grid: every interior cell (gx, gy) of the grid
// (nxg x nyg cells, the frame inside a frozen margin of `margin` cells, edge-replicated)
// gets scale weight tanh(L / 2), L clipped to [-20, 20]; field[off0 + gy sx + gx] is the
// grid's cell (0, 0).
__kernel void region_speed(__global const REAL* restrict llr, __global const REAL* restrict weight,
                           __global REAL* restrict field, const int nx, const int ny,
                           const int nxg, const int nyg, const int margin, const int off0,
                           const int sx, const REAL scale)
{
    const int gx = get_global_id(0), gy = get_global_id(1);
    if (gx >= nxg || gy >= nyg) return;
    const int x = clamp(gx - margin, 0, nx - 1), y = clamp(gy - margin, 0, ny - 1);
    const REAL l = clamp(llr[y * nx + x], (REAL)-20, (REAL)20);
    field[off0 + gy * sx + gx] = scale * weight[y * nx + x] * tanh((REAL)0.5 * l);
}
