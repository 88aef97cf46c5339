// Harmonic, biharmonic and Poisson fills of a hole by conjugate gradients on the device.
//
// Fields are plain (channels, ny, nx) arrays of one box around the hole, with no ghost
// layer: the operators are the graph Laplacian of the box's pixel grid,
//     (L u)(p) = sum over the 4-neighbours q inside the box of (u(q) - u(p)),
// which is the 5-point Laplacian in the interior and its Neumann form at the box border
// (the mirrored-ghost Laplacian). L is symmetric, so both systems below are SPD:
//     harmonic / Poisson   -L_OO x = b,         L u = f in the hole O,
//     biharmonic           (L L)_OO x = b,      L L u = f in O  (one 13-point pass),
// with the known pixels moved to b. The CG vectors live on the whole box and are zero
// off the hole (p, q) so that the operators can gather neighbours without tests for
// membership; only the lists' cells are visited.
// Work distribution and reductions: box_lists.h.
#include "inpainting/box_lists.h"
#include "reduce.h"

// (L L u)(i) directly from u: the 13-point stencil where all of it lies in the box, the
// graph Laplacian of the graph Laplacian (25 reads) within two pixels of its border.
INLINE REAL bilaplacian(__global const REAL* u, const int chan, const int i, const int nx,
                        const int ny)
{
    const int y = i / nx, x = i - y * nx;
    if (x >= 2 && y >= 2 && x < nx - 2 && y < ny - 2) {
        // in differences from the centre (the weights sum to 0): less cancellation
        const __global REAL* c = u + chan + i;
        const REAL c0 = c[0];
        return -8 * ((c[1] - c0) + (c[-1] - c0) + (c[nx] - c0) + (c[-nx] - c0))
             + 2 * ((c[1 + nx] - c0) + (c[1 - nx] - c0) + (c[-1 + nx] - c0) + (c[-1 - nx] - c0))
             + ((c[2] - c0) + (c[-2] - c0) + (c[2 * nx] - c0) + (c[-2 * nx] - c0));
    }
    const REAL lc = graph_laplacian(u, chan, i, nx, ny);
    REAL s = 0;
    if (x > 0) s += graph_laplacian(u, chan, i - 1, nx, ny) - lc;
    if (x < nx - 1) s += graph_laplacian(u, chan, i + 1, nx, ny) - lc;
    if (y > 0) s += graph_laplacian(u, chan, i - nx, nx, ny) - lc;
    if (y < ny - 1) s += graph_laplacian(u, chan, i + nx, nx, ny) - lc;
    return s;
}

// dst = a * L^order(src) + b * f on the list (order 1: the Laplacian, 2: the bilaplacian);
// partial sums of dot * dst. (`dot` may be dst.)
__kernel void poisson_operator_axpy_dot(__global const REAL* src, __global REAL* dst,
                                __global const REAL* f, const REAL a, const REAL b,
                                __global const REAL* dot, __global REAL* partial,
                                const int order, const int nx, const int ny, ITEM_ARGS)
{
    REAL acc = 0;
    FOR_ITEMS(k) {
        const int i = list[k];
        const REAL op = order == 2 ? bilaplacian(src, chan, i, nx, ny)
                                   : graph_laplacian(src, chan, i, nx, ny);
        const REAL v = a * op + b * f[chan + i];
        dst[chan + i] = v;
        acc += dot[chan + i] * v;
    }
    partial[c_ * ng + g_] = acc;
}

// x += alpha p, r -= alpha q with alpha = r.r / p.q (from the partials of both); writes
// the partials of the new r.r into rr_new. A channel's sum of its partials is reduce.h's
// sum_rows(partial + c * ng, ng): the same order in every item that needs it.
__kernel void poisson_cg_update(__global REAL* x, __global REAL* r, __global const REAL* p,
                        __global const REAL* q, __global const REAL* rr_old,
                        __global const REAL* pq, __global REAL* rr_new,
                        const int nx, const int ny, ITEM_ARGS)
{
    const REAL den = sum_rows(pq + get_global_id(1) * ng, ng);
    const REAL alpha = den > 0 ? sum_rows(rr_old + get_global_id(1) * ng, ng) / den : (REAL)0;
    REAL acc = 0;
    FOR_ITEMS(k) {
        const int i = chan + list[k];
        x[i] += alpha * p[i];
        const REAL ri = r[i] - alpha * q[i];
        r[i] = ri;
        acc += ri * ri;
    }
    rr_new[c_ * ng + g_] = acc;
}

// p = r + beta p with beta = new r.r / old r.r.
__kernel void poisson_cg_direction(__global REAL* p, __global const REAL* r,
                           __global const REAL* rr_old, __global const REAL* rr_new,
                           const int nx, const int ny, ITEM_ARGS)
{
    const REAL old = sum_rows(rr_old + get_global_id(1) * ng, ng);
    const REAL beta = old > 0 ? sum_rows(rr_new + get_global_id(1) * ng, ng) / old : (REAL)0;
    FOR_ITEMS(k) {
        const int i = chan + list[k];
        p[i] = r[i] + beta * p[i];
    }
}

// ---- multigrid preconditioner (a V-cycle on nested boxes, clpde.inpainting.poisson) ----
// Level l's operator is A = s * op, op = L (bi = 0) or L L (bi = 1), on vectors that are
// zero off the level's hole; damped Jacobi smoothing with weight w = omega / diag(A).
INLINE REAL mg_op(__global const REAL* x, const int chan, const int i, const int nx,
                  const int ny, const int bi)
{
    return bi ? bilaplacian(x, chan, i, nx, ny) : graph_laplacian(x, chan, i, nx, ny);
}

// y = x + w (b - s op(x)) on the list
__kernel void poisson_mg_smooth(__global const REAL* x, __global REAL* y, __global const REAL* b,
                        const REAL s, const REAL w, const int bi, const int nx, const int ny,
                        ITEM_ARGS)
{
    FOR_ITEMS(k) {
        const int i = list[k];
        y[chan + i] = x[chan + i] + w * (b[chan + i] - s * mg_op(x, chan, i, nx, ny, bi));
    }
}

// x = w b (the first sweep, from zero)
__kernel void poisson_mg_scale(__global const REAL* b, __global REAL* x, const REAL w, const int nx,
                       const int ny, ITEM_ARGS)
{
    FOR_ITEMS(k) { x[chan + list[k]] = w * b[chan + list[k]]; }
}

// r = b - s op(x)
__kernel void poisson_mg_residual(__global const REAL* x, __global const REAL* b, __global REAL* r,
                          const REAL s, const int bi, const int nx, const int ny, ITEM_ARGS)
{
    FOR_ITEMS(k) {
        const int i = list[k];
        r[chan + i] = b[chan + i] - s * mg_op(x, chan, i, nx, ny, bi);
    }
}

// Coarse cell (Y, X) covers fine cells (2Y - 2 + {0, 1}, 2X - 2 + {0, 1}): the coarse box
// has a ring of cells outside the hole all around. b_c = the sum of the children's r
// (r is zero off the fine hole). The list is the coarse hole; nx, ny the coarse box.
__kernel void poisson_mg_restrict(__global const REAL* r, __global REAL* bc, const int nxf,
                          const int nyf, const int nx, const int ny, ITEM_ARGS)
{
    FOR_ITEMS(k) {
        const int I = list[k];
        const int Y = I / nx, X = I - Y * nx;
        const int fine = c_ * nxf * nyf;
        REAL sum = 0;
        for (int dy = 0; dy < 2; ++dy) {
            const int y = 2 * Y - 2 + dy;
            if (y < 0 || y >= nyf) continue;
            for (int dx = 0; dx < 2; ++dx) {
                const int x = 2 * X - 2 + dx;
                if (x >= 0 && x < nxf) sum += r[fine + y * nxf + x];
            }
        }
        bc[chan + I] = sum;
    }
}

// x += the parent's value (piecewise-constant interpolation); the list is the fine hole.
__kernel void poisson_mg_prolong(__global REAL* x, __global const REAL* xc, const int nxc,
                         const int nyc, const int nx, const int ny, ITEM_ARGS)
{
    FOR_ITEMS(k) {
        const int i = list[k];
        const int y = i / nx, xx = i - y * nx;
        x[chan + i] += xc[c_ * nxc * nyc + (y / 2 + 1) * nxc + xx / 2 + 1];
    }
}

// partial sums of a . b
__kernel void poisson_dot_partial(__global const REAL* a, __global const REAL* b,
                          __global REAL* partial, const int nx, const int ny, ITEM_ARGS)
{
    REAL acc = 0;
    FOR_ITEMS(k) { acc += a[chan + list[k]] * b[chan + list[k]]; }
    partial[c_ * ng + g_] = acc;
}
