// The intrinsic heat flow (4.7, 4.8) and Turk's reaction-diffusion (4.12-4.14) over a
// surface's band runs (clpde/surface/flows.py). Defines: WEIGHTED, ALONG. Layout and
// conventions: surface.h.
#include "common.h"
#include "surface/surface.h"
#include "surface/flux.h"

// ---- intrinsic heat flow (4.7) / (4.8), discretised as in appendix E -----------------------
// (the flux and its divergence: surface/flux.h, shared with the bricks' kernels).
// One explicit step v = u + r * div(...) over the band (r = dt / h^2), every channel.
__kernel void heat_step(__global const REAL* restrict u, __global REAL* restrict v,
                        __global const REAL* restrict psi, const REAL r, const int ex,
                        const int ey, const int ez, const int sx, const int sxy, RUN_ARGS)
{
    FOR_EACH_RUN_CELL(i) {
        v[chan + i] = u[chan + i] + r * heat_div(u + chan, i, ex, ey, ez, psi, i, sx, sxy);
    }
}

// ---- reaction-diffusion (Turk), eqs. (4.12)-(4.14), in grid units (turk_cell: surface/flux.h)
__kernel void heat_turk_step(__global const REAL* restrict u, __global REAL* restrict v,
                        __global const REAL* restrict psi, __global const REAL* restrict dir,
                        __global const REAL* restrict beta, const REAL dt, const REAL da,
                        const REAL db, const REAL s, const int ex, const int ey, const int ez,
                        const int sx, const int sxy, RUN_ARGS)
{
    FOR_EACH_RUN_CELL(i) {
        const REAL2 ab = turk_cell(u, plane, i, ex, ey, ez, psi, dir, plane, i, sx, sxy, beta[i],
                                   dt, da, db, s);
        v[i] = ab.x;
        v[plane + i] = ab.y;
    }
}
