// Level-set machinery on ghost-padded 2D fields (ghost width 2, unit grid spacing):
// slope-limited upwind gradient norms (Osher-Sethian), central-difference normals, narrow
// band marking, PDE reinitialisation with the Russo-Smereka subcell fix, and the coupled
// morphing / tracking step of thesis eqs. (2.3)-(2.6).
//
// The shared stencils and the reinitialisation's update live in godunov.h and reinit.h
// (regions.cl uses them in 3D).
#include "common.cl"
#include "godunov.h"
#include "reinit.h"

// ---- narrow band -----------------------------------------------------------------------

// band = 1 where |u| < w - 1 (inner band), 2 where w - 1 <= |u| < w (the band's edge
// ring), 0 elsewhere and in the outer `margin` cells of the interior, which stay frozen
// (they hold edge-replicated data, so band stencils never reach the ghosts and no ghost
// refresh is needed between steps). Ghost entries of `band` are never written.
__kernel void mark_band(__global const REAL* restrict u, __global uchar* restrict band,
                        const REAL w, const int margin, GRID_ARGS)
{
    FOR_EACH_CELL(i) {
        const int cell = i % plane;
        const int x = cell % sx - G, y = cell / sx - G;
        const int movable = (x >= margin) & (x < nx - margin) & (y >= margin) & (y < ny - margin);
        const REAL a = FABS(u[i]);
        band[i] = (movable && a < w) ? ((a < w - 1) ? 1 : 2) : 0;
    }
}

// near = 1 where a band cell lies within `reach` cells (Chebyshev distance, reach <= 3)
// of a movable cell: the region a rebuild reinitialises. Separable, in two passes:
// dilate_band_rows takes the maximum along x into `rows` (reads stay inside the buffer:
// at most G + 1 cells past an interior row's end, into the next or previous ghost
// column, where the band is 0), then dilate_band_cols along y, with the rows clamped to
// the buffer. `rows` starts as zeros, so its ghost entries read as 0.
__kernel void dilate_band_rows(__global const uchar* restrict band, __global uchar* restrict rows,
                               const int reach, GRID_ARGS)
{
    FOR_EACH_CELL(i) {
        uchar any = 0;
        for (int dx = -reach; dx <= reach; ++dx) any |= band[i + dx];
        rows[i] = any != 0;
    }
}

__kernel void dilate_band_cols(__global const uchar* restrict rows, __global uchar* restrict near,
                               const int reach, const int margin, GRID_ARGS)
{
    FOR_EACH_CELL(i) {
        const int cell = i % plane;
        const int x = cell % sx - G, y = cell / sx - G;
        const int movable = (x >= margin) & (x < nx - margin) & (y >= margin) & (y < ny - margin);
        uchar any = 0;
        const int lo = max(-reach, -(y + G)), hi = min(reach, ny + G - 1 - y);
        for (int dy = lo; dy <= hi; ++dy) any |= rows[i + dy * sx];
        near[i] = movable && any;
    }
}

// ---- reinitialisation ------------------------------------------------------------------
// phi_t + S(phi0) (|grad phi| - 1) = 0, explicit Godunov steps; cells beside the interface
// (phi0 changes sign towards a 4-neighbour) use Russo and Smereka's subcell fix as published
// (reinit.h's reinit_update_2d), so the zero level set does not move.
__kernel void reinit_step(__global const REAL* restrict phi, __global const REAL* restrict phi0,
                          __global REAL* restrict out, const REAL dt, GRID_ARGS)
{
    FOR_EACH_CELL(i) out[i] = reinit_update_2d(phi, phi0, i, sx, dt);
}

// The same update over a compacted list of cells (a band).
__kernel void reinit_step_list(__global const REAL* restrict phi,
                               __global const REAL* restrict phi0, __global REAL* restrict out,
                               const REAL dt, const int sx, LIST_ARGS)
{
    LIST_RANGE(k0, k1, chan);
    for (int k = k0; k < k1; ++k) {
        const int i = chan + list[k];
        out[i] = reinit_update_2d(phi, phi0, i, sx, dt);
    }
}

// ---- features --------------------------------------------------------------------------

// Edge map |grad I| by central differences.
__kernel void gradient_magnitude(__global const REAL* restrict img, __global REAL* restrict out,
                                 GRID_ARGS)
{
    FOR_EACH_CELL(i) {
        out[i] = (REAL)0.5 * SQRT(SQR(img[i + 1] - img[i - 1]) + SQR(img[i + sx] - img[i - sx]));
    }
}

// ---- the coupled morphing / tracking step (thesis eqs. 2.3-2.6) ---------------------------
// Over the band cells: beta = F2 - F1;
//     F1 <- F1 + dt beta |grad F1|                   (morphing, upwind for velocity beta)
//     u  <- u  + dt beta (N_F1 . N_u) |grad u|        (tracking, projected velocity)
// with slope-limited upwind norms and central-difference normals; |grad|_eps in the
// normals' denominators keeps them finite where a field is flat (no information there,
// so the projected velocity fades to zero).
// Work-item g of the launch's n items writes three maxima over its cells for the host's
// check every few steps: stats[g] = |du/dt| (the contour's speed, for the stopping test),
// stats[n + g] = |beta| and stats[2n + g] = |grad F1| (for the next stable time step);
// stats[3n] is set to 1 when an edge-ring cell of the band comes within `near` of the zero
// level set, which asks the host to rebuild the band.
// The coupled update of one cell; returns |du/dt| and folds |beta|, |grad F1| and the
// edge test into the running maxima.
INLINE REAL morph_cell(__global const REAL* u, __global const REAL* f1,
                       __global const REAL* f2, __global const uchar* band,
                       __global REAL* u_out, __global REAL* f1_out, const int i, const int sx,
                       const REAL dt, const REAL eps_f2, const REAL eps_u2, const REAL near,
                       REAL* beta_max, REAL* grad_max, int* touched)
{
    const REAL beta = f2[i] - f1[i];
    const REAL grad_f = upwind_norm_2d(f1, i, sx, beta);
    f1_out[i] = f1[i] + dt * beta * grad_f;

    const REAL fx = (REAL)0.5 * (f1[i + 1] - f1[i - 1]);
    const REAL fy = (REAL)0.5 * (f1[i + sx] - f1[i - sx]);
    const REAL ux = (REAL)0.5 * (u[i + 1] - u[i - 1]);
    const REAL uy = (REAL)0.5 * (u[i + sx] - u[i - sx]);
    const REAL dot = (fx * ux + fy * uy) *
                     RSQRT((SQR(fx) + SQR(fy) + eps_f2) * (SQR(ux) + SQR(uy) + eps_u2));
    const REAL bhat = beta * dot;
    const REAL rate = bhat * upwind_norm_2d(u, i, sx, bhat);
    const REAL un = u[i] + dt * rate;
    u_out[i] = un;
    *beta_max = FMAX(*beta_max, FABS(beta));
    *grad_max = FMAX(*grad_max, grad_f);
    *touched |= (band[i] == 2) & (FABS(un) < near);
    return FABS(rate);
}

__kernel void morph_step(__global const REAL* restrict u, __global const REAL* restrict f1,
                         __global const REAL* restrict f2, __global const uchar* restrict band,
                         __global REAL* restrict u_out, __global REAL* restrict f1_out,
                         __global REAL* restrict stats, const REAL dt, const REAL eps_f2,
                         const REAL eps_u2, const REAL near, const int sx, LIST_ARGS)
{
    LIST_RANGE(k0, k1, chan);
    REAL fastest = 0, beta_max = 0, grad_max = 0;
    int touched = 0;
    for (int k = k0; k < k1; ++k) {
        const REAL r = morph_cell(u, f1, f2, band, u_out, f1_out, chan + list[k], sx, dt,
                                  eps_f2, eps_u2, near, &beta_max, &grad_max, &touched);
        fastest = FMAX(fastest, r);
    }
    const int g = get_global_id(0), n = get_global_size(0);
    stats[g] = fastest;
    stats[n + g] = beta_max;
    stats[2 * n + g] = grad_max;
    if (touched) stats[3 * n] = 1;  // every writer stores the same value
}

