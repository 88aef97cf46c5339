// Inpainting on implicit surfaces (clpde/surface/inpainting.py): data missing over part of the
// surface is filled by a PDE written intrinsically (chapter 4), stepped over the hole's
// cells only; the known cells hold their data, extended along the normals, throughout
// (the Dirichlet condition). Defines: NC. Layout and conventions: surface.h.
#include "common.cl"
#include "surface/surface.h"
#include "surface/flux.h"

// The intrinsic Laplacian (appendix E's scheme, grid units) of channel array u at cell i,
// averaged over the two complementary one-sided choices (forward gradient / backward
// divergence and the reverse): one fixed operator, so the fill has a steady state to
// converge to (the flows' cycling through eight choices has none), and the first-order
// terms of the two choices cancel.
INLINE REAL lb_cell(__global const REAL* restrict u, const int i,
                    __global const REAL* restrict psi, const int sx, const int sxy)
{
    return (REAL)0.5 * (heat_div(u, i, 1, sx, sxy, psi, i, sx, sxy) +
                        heat_div(u, i, -1, -sx, -sxy, psi, i, sx, sxy));
}

// One step of the harmonic fill, Laplace-Beltrami u = 0 in the hole, at the hole's nodes:
// Chebyshev's semi-iterative method (second-order Richardson) in the closest-point form,
//   x_new = u + mom (u - prev) + gain * LB(u),   u = E x,
// u being the node values x re-extended over the hole's reach band (extend.cl's extend_cp:
// the step starts from the extended value, not from x, else x - E x has growing modes).
// mom = 0, gain = r is the explicit heat step. prev takes u; change[c * nlist + k] takes
// |u - prev|, the last step's change, which the host reads every so many steps to stop.
// (Not |x_new - u|: at the steady state of the closest-point form, x differs from its own
// re-extension E x by gain * LB(u), which is of the order of the scheme's error, not 0.)
__kernel void inpaint_harmonic_step(__global const REAL* restrict u, __global REAL* restrict x,
                                    __global REAL* restrict prev,
                                    __global const REAL* restrict psi, const REAL mom,
                                    const REAL gain, __global REAL* restrict change,
                                    const int sx, const int sxy, LIST_ARGS)
{
    LIST_RANGE(k0, k1, chan);
    const int c = get_global_id(1);
    for (int k = k0; k < k1; ++k) {
        const int i = list[k];
        const REAL ui = u[chan + i];
        const REAL moved = ui - prev[chan + i];
        x[chan + i] = ui + mom * moved + gain * lb_cell(u + chan, i, psi, sx, sxy);
        prev[chan + i] = ui;
        change[c * nlist + k] = FABS(moved);
    }
}
