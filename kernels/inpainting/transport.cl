// Image inpainting (thesis chapter 3, appendix A) on compacted index lists.
//
// Every kernel visits the cells of a list of padded plane indices (LIST_ARGS), once per
// channel, and reads its neighbours through the row stride `sx`. Fields carry two ghost
// layers (the transport stencil reaches two cells). The host builds the lists once per
// resolution level, on the device:
//   omega  = Omega                       (the only cells the transport step changes),
//   band   = Omega-epsilon with g > 0    (where the anisotropic diffusion runs).
// A kernel writes every cell of its list into `v`; cells off the list keep whatever `v`
// held, so the host keeps both buffers of a ping-pong pair equal off the list.
#include "common.h"
#include "stencil.h"

#ifndef STENCIL
#define STENCIL 0  // 0: central differences (appendix A); 1: isotropic (Scharr) derivatives
#endif
#ifndef SCALING
#define SCALING 0  // 0: I_t as in eq. (3.6); 1: sign(I_t) |I_t|^(1/4) as in appendix A
#endif
// Appendix A applies the quartic root to 8-bit data (0..255). Our data lies in [0, 1]; with
// s = 255, sign(c) |c s^2|^(1/4) / s = sign(c) |c|^(1/4) / sqrt(s), so the same dt means the
// same motion as in the appendix.
#define QUARTIC_GAIN ((REAL)0.06262242910851495)  // 1 / sqrt(255)

#define NEG(a) ((a) < 0 ? (a) : (REAL)0)
#define POS(a) ((a) > 0 ? (a) : (REAL)0)

// One transport step, eqs. (3.5)-(3.11):
//   delta L = (L(x+1) - L(x-1), L(y+1) - L(y-1))                           (3.7)
//   N / |N| = rot * (-I_y, I_x) / |grad I|, central differences             (3.9)
//   beta    = delta L . N / |N|                                              (3.10)
//   I_t     = beta * |grad I|_limited                                        (3.11)
// The slope limiter upwinds I_t = beta |grad I| like a Hamilton-Jacobi equation: for
// beta > 0 it keeps the backward differences that are negative and the forward ones that
// are positive, for beta < 0 the reverse (appendix A's code; eq. 3.11 as printed has
// I_ybM where I_ybm belongs). rot = +1 rotates the gradient counter-clockwise, -1 clockwise.
__kernel void transport_step(__global const REAL* restrict u, __global REAL* restrict v,
                                const REAL dt, const REAL rot, const REAL grad_eps2,
                                const int sx, LIST_ARGS)
{
    LIST_RANGE(k0, k1, chan);
    for (int k = k0; k < k1; ++k) {
        const int i = chan + list[k];
#if STENCIL == 0
        // The 13-cell diamond of radius 2, loaded once: the Laplacian L (eq. 3.8) is needed
        // at the four neighbours, so it is computed here rather than in a separate pass.
        const REAL c = u[i], e = u[i + 1], w = u[i - 1], n = u[i + sx], s = u[i - sx];
        const REAL ne = u[i + 1 + sx], nw = u[i - 1 + sx], se = u[i + 1 - sx], sw = u[i - 1 - sx];
        const REAL ee = u[i + 2], ww = u[i - 2], nn = u[i + 2 * sx], ss = u[i - 2 * sx];
        const REAL le = ee + c + ne + se - 4 * e, lw = c + ww + nw + sw - 4 * w;
        const REAL ln = ne + nw + nn + c - 4 * n, ls = se + sw + c + ss - 4 * s;
        const REAL ix = (REAL)0.5 * (e - w), iy = (REAL)0.5 * (n - s);
        const REAL dlx = le - lw, dly = ln - ls;
#else
        // STENCIL 1, isotropic: the same equations with Scharr's derivative (weights 3, 10,
        // 3 across) for grad I in N and for delta L, and the 5-point L at the 3x3
        // neighbours (a 5x5 block less its corners). With central differences, the
        // discrete delta L and grad I of a sharp straight edge at 30 or 60 degrees are not
        // parallel, so the exact image is no steady state; this stencil cuts that residual
        // several-fold (docs/inpainting.md has the residuals on sharp stripes and edges).
        // (written out, not as loops over private arrays: PoCL keeps those in memory, many
        // times slower; docs/inpainting_methods.md)
        const REAL c = u[i], e = u[i + 1], w = u[i - 1], n = u[i + sx], s = u[i - sx];
        const REAL ne = u[i + 1 + sx], nw = u[i - 1 + sx], se = u[i + 1 - sx], sw = u[i - 1 - sx];
        const REAL ee = u[i + 2], ww = u[i - 2], nn = u[i + 2 * sx], ss = u[i - 2 * sx];
        const REAL een = u[i + 2 + sx], ees = u[i + 2 - sx], wwn = u[i - 2 + sx], wws = u[i - 2 - sx];
        const REAL nne = u[i + 1 + 2 * sx], nnw = u[i - 1 + 2 * sx];
        const REAL sse = u[i + 1 - 2 * sx], ssw = u[i - 1 - 2 * sx];
        const REAL l_e = ee + c + ne + se - 4 * e, l_w = c + ww + nw + sw - 4 * w;
        const REAL l_n = ne + nw + nn + c - 4 * n, l_s = se + sw + c + ss - 4 * s;
        const REAL l_ne = een + n + nne + e - 4 * ne, l_nw = n + wwn + nnw + w - 4 * nw;
        const REAL l_se = ees + s + e + sse - 4 * se, l_sw = s + wws + w + ssw - 4 * sw;
        const REAL K0 = (REAL)(3.0 / 32.0), K1 = (REAL)(10.0 / 32.0);
        const REAL ix = K0 * (ne - nw + se - sw) + K1 * (e - w);
        const REAL iy = K0 * (ne - se + nw - sw) + K1 * (n - s);
        // delta L spans two cells (eq. 3.7): twice the derivative
        const REAL dlx = 2 * (K0 * (l_ne - l_nw + l_se - l_sw) + K1 * (l_e - l_w));
        const REAL dly = 2 * (K0 * (l_ne - l_se + l_nw - l_sw) + K1 * (l_n - l_s));
#endif
        const REAL beta = rot * (dly * ix - dlx * iy) * RSQRT(ix * ix + iy * iy + grad_eps2);
        const REAL xb = c - w, xf = e - c, yb = c - s, yf = n - c;
        // (NEG/POS: min/max with 0 as plain selects, which PoCL compiles far better than fmin)
        const REAL up = SQR(NEG(xb)) + SQR(POS(xf)) + SQR(NEG(yb)) + SQR(POS(yf));
        const REAL down = SQR(POS(xb)) + SQR(NEG(xf)) + SQR(POS(yb)) + SQR(NEG(yf));
        REAL rate = beta * SQRT(beta > 0 ? up : down);
#if SCALING == 1
        rate = COPYSIGN(SQRT(SQRT(FABS(rate))), rate) * QUARTIC_GAIN;
#endif
        v[i] = c + dt * rate;
    }
}

// One step of the anisotropic diffusion (3.4), I_t = g kappa |grad I|, with appendix A's
// central differences (stencil.h's curvature_speed). `g` is a one-channel plane: 1 in
// Omega, falling smoothly to 0 at the edge of Omega-epsilon.
__kernel void transport_diffusion(__global const REAL* restrict u, __global REAL* restrict v,
                                __global const REAL* restrict g, const REAL dt, const REAL eps,
                                const int sx, LIST_ARGS)
{
    LIST_RANGE(k0, k1, chan);
    for (int k = k0; k < k1; ++k) {
        const int i = chan + list[k];
        NEIGHBOURS_3X3(u, i);
        v[i] = c + dt * g[list[k]] * curvature_speed(c, e, w, n, s, ne, nw, se, sw, eps);
    }
}

// Start inside Omega: one Jacobi step of Laplace's equation (the harmonic fill).
__kernel void transport_fill(__global const REAL* restrict u, __global REAL* restrict v,
                           const int sx, LIST_ARGS)
{
    LIST_RANGE(k0, k1, chan);
    for (int k = k0; k < k1; ++k) {
        const int i = chan + list[k];
        v[i] = (REAL)0.25 * (u[i + 1] + u[i - 1] + u[i + sx] + u[i - sx]);
    }
}

// Largest |a - b| over the listed cells: one partial per work-item, (channel, item) order.
// The host reads the few partials at check time only.
__kernel void transport_max_change(__global const REAL* restrict a, __global const REAL* restrict b,
                                 __global REAL* restrict partial, LIST_ARGS)
{
    LIST_RANGE(k0, k1, chan);
    REAL m = 0;
    for (int k = k0; k < k1; ++k) {
        const int i = chan + list[k];
        const REAL d = FABS(a[i] - b[i]);
        m = (d == d) ? FMAX(m, d) : (REAL)INFINITY;  // fmax alone would hide a NaN
    }
    partial[get_global_id(1) * get_global_size(0) + get_global_id(0)] = m;
}

// Sum of |a - b| over the listed cells: one partial per work-item, (channel, item) order.
// The host adds the partials and divides by the list's length: the mean change in Omega,
// which (unlike the largest) is not held up by a handful of pixels in a limit cycle.
__kernel void transport_sum_change(__global const REAL* restrict a, __global const REAL* restrict b,
                                 __global REAL* restrict partial, LIST_ARGS)
{
    LIST_RANGE(k0, k1, chan);
    REAL total = 0;
    for (int k = k0; k < k1; ++k) {
        const int i = chan + list[k];
        total += FABS(a[i] - b[i]);  // a NaN propagates into the sum
    }
    partial[get_global_id(1) * get_global_size(0) + get_global_id(0)] = total;
}

// Neumann ghosts, only where the lists reach the border: pairs (ghost, source) of padded
// plane indices, the source being the ghost's mirror image across the border (as
// Field.fill_ghosts does). One tiny launch instead of refilling the whole ghost frame.
__kernel void transport_ghosts(__global REAL* u, __global const int2* restrict pairs,
                             const int npairs, const int plane)
{
    const int k = get_global_id(0);
    if (k >= npairs) return;
    const int chan = get_global_id(1) * plane;
    const int2 p = pairs[k];
    u[chan + p.x] = u[chan + p.y];
}

// Soft masks: u = v = u + w (obs - u) on the listed cells, w a one-channel plane in [0, 1)
// (1 - the degree of damage). Written into both buffers of the pair, which stay equal.
__kernel void transport_fidelity(__global REAL* restrict u, __global REAL* restrict v,
                               __global const REAL* restrict obs, __global const REAL* restrict w,
                               LIST_ARGS)
{
    LIST_RANGE(k0, k1, chan);
    for (int k = k0; k < k1; ++k) {
        const int i = chan + list[k];
        const REAL r = u[i] + w[list[k]] * (obs[i] - u[i]);
        u[i] = r;
        v[i] = r;
    }
}
