// Coherence transport (after Bornemann & Maerz, J. Math. Imaging Vision 28, 2007), one
// distance shell of the hole at a time.
//
// Fields are plain (planes, ny, nx) arrays of one box around the hole; `known` (ny, nx) is
// 1 for the pixels known before the current shell (the image's and the earlier shells').
// Per shell the host runs:
//   1. ct_smooth_rows / ct_smooth_cols: u_sigma = (K_sigma * (known u)) / (K_sigma * known),
//      the Gaussian smoothing of the known pixels only, each channel;
//   2. ct_products: the products of the central-difference gradients of u_sigma summed
//      over the channels (one tensor for colour), J11, J12, J22, times `valid` (the pixel
//      and its four neighbours known), plus `valid` itself; ct_tensor_rows: their K_rho
//      row pass;
//   3. ct_fill over the shell's pixels: the K_rho column pass at the pixel (normalized by
//      the valid weight), the tensor's eigenvector n of the larger eigenvalue (across the
//      structure) and the coherence ((l1 - l2) / (l1 + l2))^2, and the weighted mean of the
//      known pixels y in the disc |y - x| <= epsilon,
//          w(x, y) = exp(-mu^2 / (2 eps^2) <n, y - x>^2) / |y - x|,   mu = kappa coherence;
//   4. ct_mark: the shell's pixels become known.
// Borders of the box: the smoothing sums are normalized, so pixels outside simply count as
// unknown.
#include "common.h"

// The full-box passes walk runs of `xrun` pixels of one row (a whole row on CPUs, where
// the innermost loops over x vectorise; one pixel on GPUs), tap by tap, accumulating into
// the output row; a tap's x range is clipped to the row, so there is no per-pixel test.
#define RUN_RANGE                                                                     \
    const int y = get_global_id(1);                                                   \
    const int x0 = get_global_id(0) * xrun;                                           \
    const int x1 = min(x0 + xrun, nx);                                                \
    if (y >= ny || x0 >= nx) return;                                                  \
    const int plane = nx * ny, row = y * nx

// Row pass of a normalized Gaussian smoothing: planes c < nin of `out` get
// sum_j taps_j weight(x+j) in_c(x+j), plane nin the weights' sum.
__kernel void coherence_smooth_rows(__global const REAL* in, __global const REAL* weight,
                             __global REAL* out, __constant REAL* taps, const int r,
                             const int nin, const int nx, const int ny, const int xrun)
{
    RUN_RANGE;
    for (int c = 0; c <= nin; ++c)
        for (int x = x0; x < x1; ++x) out[c * plane + row + x] = 0;
    for (int j = -r; j <= r; ++j) {
        const REAL t = taps[j + r];
        const int xa = max(x0, -j), xb = min(x1, nx - j);
        for (int x = xa; x < xb; ++x) out[nin * plane + row + x] += t * weight[row + x + j];
        for (int c = 0; c < nin; ++c)
            for (int x = xa; x < xb; ++x)
                out[c * plane + row + x] += t * weight[row + x + j] * in[c * plane + row + x + j];
    }
}

// Column pass: out_c = (sum_j taps_j h_c(y+j)) / (sum_j taps_j h_nin(y+j)), 0 where the
// weights vanish; plane nin of `out` keeps the weights' sum.
__kernel void coherence_smooth_cols(__global const REAL* h, __global REAL* out,
                             __constant REAL* taps, const int r, const int nin,
                             const int nx, const int ny, const int xrun)
{
    RUN_RANGE;
    for (int c = 0; c <= nin; ++c)
        for (int x = x0; x < x1; ++x) out[c * plane + row + x] = 0;
    for (int j = max(-r, -y); j <= min(r, ny - 1 - y); ++j) {
        const REAL t = taps[j + r];
        const int src = row + j * nx;
        for (int c = 0; c <= nin; ++c)
            for (int x = x0; x < x1; ++x) out[c * plane + row + x] += t * h[c * plane + src + x];
    }
    for (int x = x0; x < x1; ++x) {
        const REAL w = out[nin * plane + row + x];
        const REAL inv = w > (REAL)1e-12 ? (REAL)1 / w : (REAL)0;
        for (int c = 0; c < nin; ++c) out[c * plane + row + x] *= inv;
    }
}

// The gradient products of u_sigma (nc planes) summed over the channels, times `valid`
// (the pixel and its four neighbours known): out planes J11, J12, J22, valid.
__kernel void coherence_products(__global const REAL* us, __global const REAL* known,
                          __global REAL* out, const int nc, const int nx, const int ny,
                          const int xrun)
{
    RUN_RANGE;
    for (int x = x0; x < x1; ++x) {
        const int i = row + x;
        REAL p0 = 0, p1 = 0, p2 = 0, p3 = 0;
        if (x >= 1 && y >= 1 && x < nx - 1 && y < ny - 1 &&
            known[i] * known[i - 1] * known[i + 1] * known[i - nx] * known[i + nx] != 0) {
            for (int c = 0; c < nc; ++c) {
                const int k = c * plane + i;
                const REAL ux = (REAL)0.5 * (us[k + 1] - us[k - 1]);
                const REAL uy = (REAL)0.5 * (us[k + nx] - us[k - nx]);
                p0 += ux * ux;
                p1 += ux * uy;
                p2 += uy * uy;
            }
            p3 = 1;
        }
        out[i] = p0;
        out[plane + i] = p1;
        out[2 * plane + i] = p2;
        out[3 * plane + i] = p3;
    }
}

// The K_rho row pass of the four product planes.
__kernel void coherence_tensor_rows(__global const REAL* prod, __global REAL* out,
                             __constant REAL* taps, const int r, const int nx, const int ny,
                             const int xrun)
{
    RUN_RANGE;
    for (int q = 0; q < 4; ++q)
        for (int x = x0; x < x1; ++x) out[q * plane + row + x] = 0;
    for (int j = -r; j <= r; ++j) {
        const REAL t = taps[j + r];
        const int xa = max(x0, -j), xb = min(x1, nx - j);
        for (int q = 0; q < 4; ++q)
            for (int x = xa; x < xb; ++x)
                out[q * plane + row + x] += t * prod[q * plane + row + x + j];
    }
}

// One shell: list entries [first, first + count) of `list` (flat indices y * nx + x).
__kernel void coherence_fill(__global REAL* u, __global const REAL* known, __global const REAL* t,
                      __constant REAL* taps, const int r, __global const int* list,
                      const int first, const int count, const REAL epsilon,
                      const REAL kappa, const int nc, const int nx, const int ny)
{
    const int k = get_global_id(0);
    if (k >= count) return;
    const int i = list[first + k];
    const int y = i / nx, x = i - y * nx;
    const int plane = nx * ny;
    // the column pass of K_rho at this pixel
    const int a = max(y - r, 0) - y, b = min(y + r, ny - 1) - y;
    REAL J[4] = {0, 0, 0, 0};
    for (int j = a; j <= b; ++j)
        for (int q = 0; q < 4; ++q) J[q] += taps[j + r] * t[q * plane + (y + j) * nx + x];
    REAL n1 = 1, n2 = 0, mu = 0;
    if (J[3] > (REAL)1e-12) {
        const REAL j11 = J[0] / J[3], j12 = J[1] / J[3], j22 = J[2] / J[3];
        const REAL tr = j11 + j22;
        const REAL d = SQRT((j11 - j22) * (j11 - j22) + 4 * j12 * j12);
        const REAL l1 = (REAL)0.5 * (tr + d), l2 = (REAL)0.5 * (tr - d);
        // the eigenvector of l1: whichever of the two forms is better conditioned
        REAL a1 = j12, a2 = l1 - j11, b1 = l1 - j22, b2 = j12;
        if (a1 * a1 + a2 * a2 < b1 * b1 + b2 * b2) { a1 = b1; a2 = b2; }
        const REAL norm = SQRT(a1 * a1 + a2 * a2);
        if (norm > 0) { n1 = a1 / norm; n2 = a2 / norm; }
        if (tr > (REAL)1e-12) {
            const REAL coh = (l1 - l2) / (l1 + l2);
            mu = kappa * coh * coh;
        }
    }
    const REAL g = mu * mu / (2 * epsilon * epsilon);
    const int R = (int)floor(epsilon);
    const REAL eps2 = epsilon * epsilon;
    // pass 0: the coherence weights; pass 1 (only where no known pixel lies near the
    // coherence line, so that those weights all but vanish): the isotropic 1 / |y - x|
    REAL num[MAX_CHANNELS];
    REAL den = 0, den_iso = 0;
    for (int pass = 0; pass < 2; ++pass) {
        for (int c = 0; c < nc; ++c) num[c] = 0;
        den = 0;
        for (int dy = max(-R, -y); dy <= min(R, ny - 1 - y); ++dy) {
            for (int dx = max(-R, -x); dx <= min(R, nx - 1 - x); ++dx) {
                const int d2 = dx * dx + dy * dy;
                if (d2 == 0 || (REAL)d2 > eps2) continue;
                const int jy = (y + dy) * nx + x + dx;
                if (known[jy] == 0) continue;
                const REAL inv = RSQRT((REAL)d2);
                const REAL along = n1 * dx + n2 * dy;
                const REAL w = pass == 0 ? EXP(-g * along * along) * inv : inv;  // EXP: common.h
                den += w;
                if (pass == 0) den_iso += inv;
                for (int c = 0; c < nc; ++c) num[c] += w * u[c * plane + jy];
            }
        }
        if (pass == 0 && den > (REAL)1e-6 * den_iso) break;
    }
    if (den > 0)
        for (int c = 0; c < nc; ++c) u[c * plane + i] = num[c] / den;
}

__kernel void coherence_mark(__global REAL* known, __global const int* list, const int first,
                      const int count)
{
    const int k = get_global_id(0);
    if (k < count) known[list[first + k]] = 1;
}
