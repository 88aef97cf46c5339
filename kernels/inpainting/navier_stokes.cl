// Navier-Stokes inpainting (Bertalmio, Bertozzi & Sapiro, CVPR 2001): the vorticity
// w = Lap I is transported by the velocity v = grad-perp I = (-I_y, I_x) and diffused
// anisotropically,
//     w_t + v . grad w = nu div(g(|grad w|) grad w),
// in the hole; the image follows from Lap I = w there (poisson.cl's CG).
//
// Fields are plain (channels, ny, nx) arrays of one box around the hole (as in poisson.cl);
// neighbours outside the box count as mirrored (zero differences). Discretisation, at a
// hole pixel p with neighbours e, w, n, s:
//   v = (-(I_n - I_s) / 2, (I_e - I_w) / 2)                              central differences
//   v . grad w: first-order upwind, backward difference where v_x > 0, forward where v_x < 0
//   div(g grad w) = sum over the four faces of g(|w_q - w_p|) (w_q - w_p),
//                   g(s) = 1 / (1 + (s / K)^2)                (edge-stopping, Perona-Malik)
// Stable for dt (|v_x| + |v_y| + 4 nu) <= 1; with I in [0, 1], |v_x| + |v_y| <= 1.
#include "inpainting/box_lists.h"

INLINE REAL ns_g(const REAL d, const REAL inv_k2) { return (REAL)1 / (1 + d * d * inv_k2); }

__kernel void navier_stokes_vorticity_step(__global const REAL* img, __global const REAL* w,
                                __global REAL* wn, const REAL dt, const REAL nu,
                                const REAL inv_k2, const int nx, const int ny, ITEM_ARGS)
{
    FOR_ITEMS(k) {
        const int i = list[k];
        const int y = i / nx, x = i - y * nx;
        const int ie = x < nx - 1 ? i + 1 : i, iw = x > 0 ? i - 1 : i;
        const int in = y < ny - 1 ? i + nx : i, is = y > 0 ? i - nx : i;
        const REAL vx = -(REAL)0.5 * (img[chan + in] - img[chan + is]);
        const REAL vy = (REAL)0.5 * (img[chan + ie] - img[chan + iw]);
        const REAL c = w[chan + i];
        const REAL de = w[chan + ie] - c, dw = c - w[chan + iw];  // forward, backward in x
        const REAL dn = w[chan + in] - c, ds = c - w[chan + is];  // forward, backward in y
        const REAL adv = (vx > 0 ? vx * dw : vx * de) + (vy > 0 ? vy * ds : vy * dn);
        const REAL diff = ns_g(de, inv_k2) * de - ns_g(dw, inv_k2) * dw
                        + ns_g(dn, inv_k2) * dn - ns_g(ds, inv_k2) * ds;
        wn[chan + i] = c + dt * (nu * diff - adv);
    }
}

// w = L I on a list (the known pixels around the hole: the vorticity's boundary values,
// and the hole itself at the start).
__kernel void navier_stokes_laplacian(__global const REAL* img, __global REAL* w, const int nx,
                           const int ny, ITEM_ARGS)
{
    FOR_ITEMS(k) {
        const int i = list[k];
        w[chan + i] = graph_laplacian(img, chan, i, nx, ny);
    }
}

// Partial maxima and sums of |I - prev| over the list, then prev = I.
__kernel void navier_stokes_change(__global const REAL* img, __global REAL* prev,
                        __global REAL* partial_max, __global REAL* partial_sum,
                        const int nx, const int ny, ITEM_ARGS)
{
    REAL m = 0, total = 0;
    FOR_ITEMS(k) {
        const int i = chan + list[k];
        const REAL d = FABS(img[i] - prev[i]);
        m = d > m ? d : m;
        total += d;
        prev[i] = img[i];
    }
    partial_max[c_ * ng + g_] = m;
    partial_sum[c_ * ng + g_] = total;
}
