// Level-set machinery on ghost-padded 2D fields (ghost width 2, unit grid spacing): narrow
// band marking, PDE reinitialisation with the Russo-Smereka subcell fix and the edge map.
// The coupled morphing / tracking step of thesis eqs. (2.3)-(2.6) is tracking/features.cl's
// morph_track (one channel, DISC 0, lam = 0).
//
// The shared stencils and the reinitialisation's update live in godunov.h and reinit.h
// (regions.cl uses them in 3D).
#include "common.h"
#include "godunov.h"
#include "reinit.h"
#include "bricks/bricks2d.h"

// ---- narrow band -----------------------------------------------------------------------

// band = 1 where |u| < w - 1 (inner band), 2 where w - 1 <= |u| < w (the band's edge
// ring), 0 elsewhere and in the outer `margin` cells of the interior, which stay frozen
// (they hold edge-replicated data, so band stencils never reach the ghosts and no ghost
// refresh is needed between steps). Ghost entries of `band` are never written.
__kernel void levelset_mark_band(__global const REAL* restrict u, __global uchar* restrict band,
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
__kernel void levelset_dilate_band_rows(__global const uchar* restrict band, __global uchar* restrict rows,
                               const int reach, GRID_ARGS)
{
    FOR_EACH_CELL(i) {
        uchar any = 0;
        for (int dx = -reach; dx <= reach; ++dx) any |= band[i + dx];
        rows[i] = any != 0;
    }
}

__kernel void levelset_dilate_band_cols(__global const uchar* restrict rows, __global uchar* restrict near,
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
__kernel void levelset_reinit_step(__global const REAL* restrict phi, __global const REAL* restrict phi0,
                          __global REAL* restrict out, const REAL dt, GRID_ARGS)
{
    FOR_EACH_CELL(i) out[i] = reinit_update_2d(phi, phi0, i, sx, dt);
}

// The same update over a compacted list of cells (a band).
__kernel void levelset_reinit_step_list(__global const REAL* restrict phi,
                               __global const REAL* restrict phi0, __global REAL* restrict out,
                               const REAL dt, const int sx, LIST_ARGS)
{
    LIST_RANGE(k0, k1, chan);
    for (int k = k0; k < k1; ++k) {
        const int i = chan + list[k];
        out[i] = reinit_update_2d(phi, phi0, i, sx, dt);
    }
}

// The same update over the bricks of a band (bricks2d.h), at the cells where cells > 0.
__kernel void levelset_reinit_step_bricks(__global const REAL* restrict phi,
                                 __global const REAL* restrict phi0, __global REAL* restrict out,
                                 __global const uchar* restrict cells, const REAL dt,
                                 BRICK2D_ARGS)
{
    FOR_EACH_BRICK_CELL(i) {
        if (cells[i]) out[i] = reinit_update_2d(phi, phi0, i, rs, dt);
    }
}

// bricks[b] = 1 where brick b (bx + nbx by, over the movable region) holds a cell with
// mask > 0: one work-item per brick.
__kernel void levelset_mark_bricks(__global const uchar* restrict mask, __global uchar* restrict flags,
                          const int nbx, const int nby, const int x0, const int y0,
                          const int x1, const int y1, const int rs)
{
    const int b = get_global_id(0);
    if (b >= nbx * nby) return;
    const int ox = x0 + (b % nbx) * BX, oy = y0 + (b / nbx) * BY;
    uchar any = 0;
    for (int y = oy; y < min(oy + BY, y1); ++y)
        for (int x = ox; x < min(ox + BX, x1); ++x) any |= mask[y * rs + x];
    flags[b] = any != 0;
}

// ---- features --------------------------------------------------------------------------

// Edge map |grad I| by central differences.
__kernel void levelset_gradient_magnitude(__global const REAL* restrict img, __global REAL* restrict out,
                                 GRID_ARGS)
{
    FOR_EACH_CELL(i) {
        out[i] = (REAL)0.5 * SQRT(SQR(img[i + 1] - img[i - 1]) + SQR(img[i + sx] - img[i - sx]));
    }
}
