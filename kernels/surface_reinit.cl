// Reinitialisation of a surface's psi to a signed distance (clpde/surface/implicit.py).
// Layout and conventions: surface.h.
#include "common.cl"
#include "surface.h"

// ---- reinitialisation of psi to a signed distance ------------------------------------------
// phi_t + sgn(phi0) (|grad phi| - 1) = 0 with Godunov's upwind norm (Sussman, Smereka, Osher),
// and Russo and Smereka's subcell fix on cells next to the surface: there the update pulls
// phi towards D = phi0 / |grad phi0| (a distance estimate from phi0 itself), so the zero
// level set does not move. World units; r = dt / h.
INLINE REAL godunov_sq(const REAL back, const REAL fwd, const REAL s)
{
    return s > 0 ? FMAX(SQR(FMAX(back, (REAL)0)), SQR(FMIN(fwd, (REAL)0)))
                 : FMAX(SQR(FMIN(back, (REAL)0)), SQR(FMAX(fwd, (REAL)0)));
}

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
        const REAL s = p0 > 0 ? (REAL)1 : (p0 < 0 ? (REAL)-1 : (REAL)0);
        const bool near = p0 * phi0[i + 1] <= 0 || p0 * phi0[i - 1] <= 0 ||
                          p0 * phi0[i + sx] <= 0 || p0 * phi0[i - sx] <= 0 ||
                          p0 * phi0[i + sxy] <= 0 || p0 * phi0[i - sxy] <= 0;
        const REAL c = phi[i];
        if (near) {
            const REAL g = SQRT(SQR(subcell_slope(phi0, i, 1)) + SQR(subcell_slope(phi0, i, sx)) +
                                SQR(subcell_slope(phi0, i, sxy))) * inv_h;
            out[i] = c - r * (s * FABS(c) - p0 / g);
        } else {
            const REAL gx = godunov_sq(c - phi[i - 1], phi[i + 1] - c, s);
            const REAL gy = godunov_sq(c - phi[i - sx], phi[i + sx] - c, s);
            const REAL gz = godunov_sq(c - phi[i - sxy], phi[i + sxy] - c, s);
            out[i] = c - r * s * (SQRT(gx + gy + gz) * inv_h - 1) / inv_h;
        }
    }
}
