// Reinitialisation of a surface's psi to a signed distance (clpde/surface/implicit.py).
// Layout and conventions: surface.h.
#include "common.h"
#include "surface/surface.h"
#include "godunov.h"
#include "reinit.h"

// ---- reinitialisation of psi to a signed distance ------------------------------------------
// phi_t + sgn(phi0) (|grad phi| - 1) = 0 with Godunov's upwind norm (Sussman, Smereka, Osher),
// and Russo and Smereka's subcell fix on cells next to the surface: there the update pulls
// phi towards D = phi0 / |grad phi0| (a distance estimate from phi0 itself), so the zero
// level set does not move. World units; r = dt / h. The sign, the Godunov choice per axis
// and both updates are reinit.h's and godunov.h's; what stays here is the surface's own
// variant of the scheme: first-order one-sided differences, the slope per axis below, and
// an interface test with `<= 0` (so phi0 = 0 cells take the subcell fix, never a Godunov
// step with sign 0).

// |d phi0| along one axis for the subcell fix, in grid units: the largest of the central
// and both one-sided differences, at least 1e-12.
INLINE REAL subcell_slope(__global const REAL* restrict p, const int i, const int s)
{
    return FMAX(FMAX(FABS(p[i + s] - p[i - s]) * (REAL)0.5, FABS(p[i + s] - p[i])),
                FMAX(FABS(p[i] - p[i - s]), (REAL)1e-12));
}

__kernel void reinit_step(__global const REAL* restrict phi, __global REAL* restrict out,
                          __global const REAL* restrict phi0, const REAL r, const REAL inv_h,
                          const int sx, const int sxy, LIST_ARGS)
{
    LIST_RANGE(k0, k1, chan);
    for (int k = k0; k < k1; ++k) {
        const int i = list[k];
        const REAL p0 = phi0[i];
        const REAL s = ls_sign(p0);
        const bool near = p0 * phi0[i + 1] <= 0 || p0 * phi0[i - 1] <= 0 ||
                          p0 * phi0[i + sx] <= 0 || p0 * phi0[i - sx] <= 0 ||
                          p0 * phi0[i + sxy] <= 0 || p0 * phi0[i - sxy] <= 0;
        const REAL c = phi[i];
        if (near) {
            // |grad phi0| in world units; each slope is at least 1e-12 grid units, so g is
            // above subcell_update's floor of 1e-12 for h < sqrt(3), where D = p0 / g as is.
            const REAL g = SQRT(SQR(subcell_slope(phi0, i, 1)) + SQR(subcell_slope(phi0, i, sx)) +
                                SQR(subcell_slope(phi0, i, sxy))) * inv_h;
            out[i] = subcell_update(c, p0, g, r, 0);
        } else {
            // godunov.h's V is -sgn, as in reinit.h (s != 0 here: phi0 = 0 is `near`).
            const REAL gx = godunov_axis(c - phi[i - 1], phi[i + 1] - c, -s);
            const REAL gy = godunov_axis(c - phi[i - sx], phi[i + sx] - c, -s);
            const REAL gz = godunov_axis(c - phi[i - sxy], phi[i + sxy] - c, -s);
            out[i] = godunov_update_world(c, s, SQRT(gx + gy + gz), r, inv_h);
        }
    }
}
