// PDE reinitialisation of a level set to a signed distance, shared by levelset.cl (2D),
// regions.cl (3D) and surface/reinit.cl (3D bands, world units): explicit Godunov steps of
//     u_t + S(u0) (|grad u| - 1) = 0,
// with Russo and Smereka's subcell fix at the cells beside the interface (u0 changes sign
// towards one of their 4 or 6 neighbours): there u relaxes towards D = u0 / |grad u0|, the
// distance to the interface estimated from u0 itself, so the zero level set does not move.
// Unit grid spacing unless said otherwise. Include after common.h and godunov.h.
#ifndef CLPDE_REINIT_H
#define CLPDE_REINIT_H

// |grad u0| for the subcell fix from the central estimate (its square summed over the axes,
// `central_sq`, in differences across two cells) and the steepest one-sided slope: the
// larger of |grad|_central and steep_weight times the steepest slope. Russo-Smereka's
// choice is steep_weight 1, which stays right when the interface cuts close to a node; a
// weight below 1 leans on the central estimate, which on a signed distance is 1 up to
// O(h^2 / R^2) (see regions.cl for why the 3D tracker wants that).
INLINE REAL subcell_gradient(const REAL central_sq, const REAL steep, const REAL steep_weight)
{
    return FMAX((REAL)0.5 * SQRT(central_sq), steep_weight * steep);
}

// One step of the subcell fix at a cell beside the interface: p relaxes towards
// D = c0 / g. Cells whose slope g is already within `tol` of 1 are kept as they are
// (tol = 0 keeps none).
INLINE REAL subcell_update(const REAL p, const REAL c0, const REAL g, const REAL dt,
                           const REAL tol)
{
    const REAL d = c0 / FMAX(g, (REAL)1e-12);
    return FABS(g - 1) < tol ? p : p - dt * (ls_sign(c0) * FABS(p) - d);
}

// One Godunov step away from the interface, given the upwind norm taken with V = -sgn.
INLINE REAL godunov_update(const REAL p, const REAL sgn, const REAL norm, const REAL dt)
{
    return p - dt * sgn * (norm - 1);
}

// godunov_update for a field in world units (surface/reinit.cl): `norm` the upwind norm in
// grid units, r = dt / h. The same step as godunov_update(p, sgn, norm * inv_h, r / inv_h),
// but rounded as the surface's reinitialisation always has (dividing by inv_h last), so that
// its results stay bit for bit what they were.
INLINE REAL godunov_update_world(const REAL p, const REAL sgn, const REAL norm, const REAL r,
                                 const REAL inv_h)
{
    return p - r * sgn * (norm * inv_h - 1) / inv_h;
}

// The new value of u at padded index i of a 2D field after one step of dt: Russo and
// Smereka's fix as published (steep_weight 1, no tolerance). -DPLAIN_REINIT=1 drops the fix
// (for comparisons only).
INLINE REAL reinit_update_2d(LS_SPACE const REAL* u, LS_SPACE const REAL* u0, const int i,
                             const int sx, const REAL dt)
{
    const REAL c0 = u0[i];
    const REAL e0 = u0[i + 1], w0 = u0[i - 1], n0 = u0[i + sx], s0 = u0[i - sx];
    const REAL sgn = ls_sign(c0);
    const REAL p = u[i];
#ifndef PLAIN_REINIT
    const int at_interface = (c0 * e0 < 0) | (c0 * w0 < 0) | (c0 * n0 < 0) | (c0 * s0 < 0);
    if (at_interface) {
        const REAL central_sq = SQR(e0 - w0) + SQR(n0 - s0);
        const REAL steep = FMAX(FMAX(FABS(e0 - c0), FABS(c0 - w0)),
                                FMAX(FABS(n0 - c0), FABS(c0 - s0)));
        return subcell_update(p, c0, subcell_gradient(central_sq, steep, 1), dt, 0);
    }
#endif
    return godunov_update(p, sgn, upwind_norm_2d(u, i, sx, -sgn), dt);
}

// The same at padded index i (any channel) of a 3D volume, with the subcell gradient's
// steep_weight and tol as given.
INLINE REAL reinit_update_3d(LS_SPACE const REAL* u, LS_SPACE const REAL* u0, const int i,
                             const int sx, const int sxy, const REAL dt,
                             const REAL steep_weight, const REAL tol)
{
    const REAL c0 = u0[i];
    const REAL e0 = u0[i + 1], w0 = u0[i - 1];
    const REAL n0 = u0[i + sx], s0 = u0[i - sx];
    const REAL t0 = u0[i + sxy], b0 = u0[i - sxy];
    const REAL sgn = ls_sign(c0);
    const int at_interface = (c0 * e0 < 0) | (c0 * w0 < 0) | (c0 * n0 < 0) |
                             (c0 * s0 < 0) | (c0 * t0 < 0) | (c0 * b0 < 0);
    const REAL p = u[i];
    if (at_interface) {
        const REAL central_sq = SQR(e0 - w0) + SQR(n0 - s0) + SQR(t0 - b0);
        REAL steep = FMAX(FMAX(FABS(e0 - c0), FABS(c0 - w0)), FMAX(FABS(n0 - c0), FABS(c0 - s0)));
        steep = FMAX(steep, FMAX(FABS(t0 - c0), FABS(c0 - b0)));
        return subcell_update(p, c0, subcell_gradient(central_sq, steep, steep_weight), dt, tol);
    }
    return godunov_update(p, sgn, upwind_norm_3d(u, i, sx, sxy, -sgn), dt);
}

// The subcell fix's part of the 3D update depends on u0 alone, so a reinitialisation can
// compute it once for all its iterations: the cell's target, +INFINITY away from the
// interface (a Godunov step), -INFINITY where the slope is within tol of 1 (kept as it is),
// else D = u0 / |grad u0|. Each iteration then reads one value instead of u0's 6 neighbours
// and skips the slope (about a third of the sweep's time at 256^3); the results are the
// same, bit for bit, as reinit_update_3d's.
INLINE REAL subcell_target_3d(LS_SPACE const REAL* u0, const int i, const int sx,
                              const int sxy, const REAL steep_weight, const REAL tol)
{
    const REAL c0 = u0[i];
    const REAL e0 = u0[i + 1], w0 = u0[i - 1];
    const REAL n0 = u0[i + sx], s0 = u0[i - sx];
    const REAL t0 = u0[i + sxy], b0 = u0[i - sxy];
    const int at_interface = (c0 * e0 < 0) | (c0 * w0 < 0) | (c0 * n0 < 0) |
                             (c0 * s0 < 0) | (c0 * t0 < 0) | (c0 * b0 < 0);
    const REAL central_sq = SQR(e0 - w0) + SQR(n0 - s0) + SQR(t0 - b0);
    REAL steep = FMAX(FMAX(FABS(e0 - c0), FABS(c0 - w0)), FMAX(FABS(n0 - c0), FABS(c0 - s0)));
    steep = FMAX(steep, FMAX(FABS(t0 - c0), FABS(c0 - b0)));
    const REAL g = subcell_gradient(central_sq, steep, steep_weight);
    const REAL d = c0 / FMAX(g, (REAL)1e-12);
    return !at_interface ? (REAL)INFINITY : (FABS(g - 1) < tol ? (REAL)-INFINITY : d);
}

// reinit_update_3d at index i of u from the cell's start value c0 and its target t of
// subcell_target_3d (given as values: the brick kernels read them from other buffers than u).
INLINE REAL reinit_update_at(LS_SPACE const REAL* u, const int i, const int sx, const int sxy,
                             const REAL c0, const REAL t, const REAL dt)
{
    const REAL p = u[i];
    const REAL sgn = ls_sign(c0);
    if (t > (REAL)1e30) return godunov_update(p, sgn, upwind_norm_3d(u, i, sx, sxy, -sgn), dt);
    if (t < (REAL)-1e30) return p;
    return p - dt * (sgn * FABS(p) - t);
}

// reinit_update_3d from the targets of subcell_target_3d.
INLINE REAL reinit_update_target(LS_SPACE const REAL* u, LS_SPACE const REAL* u0,
                                 LS_SPACE const REAL* target, const int i, const int sx,
                                 const int sxy, const REAL dt)
{
    return reinit_update_at(u, i, sx, sxy, u0[i], target[i], dt);
}

#endif
