// The per-cell arithmetic of region tracking (thesis section 2.2), shared by regions.cl
// (padded volumes, band runs) and regions/bricks.cl (brick tiles): the speeds, the coupled
// step of a level set, the narrow band's cut-off and the extension's velocity. Fields are
// LS_SPACE pointers (godunov.h) with row stride sx and slab stride sxy; channel c of a
// cell i lies at c * plane + i. Include after common.h, godunov.h and extend.h.
#ifndef CLPDE_REGIONS_H
#define CLPDE_REGIONS_H

#ifndef NC
#define NC 2  // level sets: Phi and the Phi-hats
#endif
// Non-negative reals as integers of the same bits (their order is the integers' order:
// an integer maximum vectorises where a floating-point one stayed scalar).
#ifdef REAL_IS_DOUBLE
#define REAL_BITS long
#define AS_BITS(x) as_long(x)
#define AS_REAL(b) as_double(b)
#else
#define REAL_BITS int
#define AS_BITS(x) as_int(x)
#define AS_REAL(b) as_float(b)
#endif

// Central-difference gradient.
#define CENTRAL_GRAD(u, i, gx, gy, gz)                                                 \
    const REAL gx = (REAL)0.5 * ((u)[(i) + 1] - (u)[(i) - 1]);                         \
    const REAL gy = (REAL)0.5 * ((u)[(i) + sx] - (u)[(i) - sx]);                       \
    const REAL gz = (REAL)0.5 * ((u)[(i) + sxy] - (u)[(i) - sxy])

// Mean curvature div(grad u / |grad u|) (kappa = 2 / R on a sphere of radius R cells) and
// Gaussian curvature (1 / R^2) of the level set of u through cell i, from central first
// and second differences: kappa = (|g|^2 tr H - g.Hg) / |g|^3, K = g.adj(H)g / |g|^4.
INLINE void curvatures(LS_SPACE const REAL* u, const int i, const int sx, const int sxy,
                       REAL* mean, REAL* gauss)
{
    CENTRAL_GRAD(u, i, gx, gy, gz);
    const REAL c2 = 2 * u[i];
    const REAL hxx = u[i + 1] - c2 + u[i - 1];
    const REAL hyy = u[i + sx] - c2 + u[i - sx];
    const REAL hzz = u[i + sxy] - c2 + u[i - sxy];
    const REAL hxy = (REAL)0.25 * (u[i + 1 + sx] - u[i - 1 + sx] - u[i + 1 - sx] + u[i - 1 - sx]);
    const REAL hxz = (REAL)0.25 * (u[i + 1 + sxy] - u[i - 1 + sxy] - u[i + 1 - sxy] + u[i - 1 - sxy]);
    const REAL hyz = (REAL)0.25 * (u[i + sx + sxy] - u[i - sx + sxy] - u[i + sx - sxy] + u[i - sx - sxy]);
    const REAL g2 = gx * gx + gy * gy + gz * gz + (REAL)1e-12;
    const REAL ghg = gx * gx * hxx + gy * gy * hyy + gz * gz * hzz +
                     2 * (gx * gy * hxy + gx * gz * hxz + gy * gz * hyz);
    *mean = (g2 * (hxx + hyy + hzz) - ghg) / (g2 * SQRT(g2));
    // g . adj(H) g: adj(H) is the cofactor matrix of the symmetric Hessian
    const REAL axx = hyy * hzz - hyz * hyz, ayy = hxx * hzz - hxz * hxz, azz = hxx * hyy - hxy * hxy;
    const REAL axy = hxz * hyz - hxy * hzz, axz = hxy * hyz - hxz * hyy, ayz = hxy * hxz - hxx * hyz;
    const REAL gag = gx * gx * axx + gy * gy * ayy + gz * gz * azz +
                     2 * (gx * gy * axy + gx * gz * axz + gy * gz * ayz);
    *gauss = gag / (g2 * g2);
}

// Speeds fade smoothly to 0 between |Phi| = lo and hi cells (Peng et al.'s narrow-band
// cut-off): cells near the band's edge, whose neighbours outside the band hold stale
// values, stay put, and the reinitialisation rebuilds them from the surface outwards.
// Without it a translated sphere's far side picked up 2-cell errors after 5 cells of motion.
INLINE REAL band_cutoff(const REAL phi, const REAL lo, const REAL hi)
{
    const REAL a = (FABS(phi) - lo) / (hi - lo);
    const REAL t = a < 0 ? (REAL)0 : (a > 1 ? (REAL)1 : a);
    return 1 - t * t * (3 - 2 * t);
}

// ---- the speed V of Phi_t = V |grad Phi| on the band ----------------------------------------
// SPEED 0: V = scale (a constant); 1: V = scale * mean curvature of Phi; 2: V = scale *
// sign(mean curvature) max(Gaussian curvature, 0); 3: V = scale * (aux - Phi) (morphing toward the target whose
// signed distance is aux); 4: V = scale * aux (a user array). Then clamped to [-vmax, vmax].
#ifndef SPEED
#define SPEED 0
#endif
// V at index i of channel 0 (aux_i: the auxiliary volume there).
INLINE REAL region_speed_at(LS_SPACE const REAL* phi, const REAL aux_i, const int i,
                            const REAL scale, const REAL vmax, const int sx, const int sxy)
{
#if SPEED == 0
    REAL v = scale;
#elif SPEED == 1 || SPEED == 2
    REAL mean, gauss;
    curvatures(phi, i, sx, sxy, &mean, &gauss);
    // SPEED 2: |speed| = K+, towards the centres of curvature (sign of the mean
    // curvature): convex and concave elliptic parts both flatten, which unfolds
    const REAL toward = ls_sign(mean);
    REAL v = scale * (SPEED == 1 ? mean : toward * FMAX(gauss, (REAL)0));
#elif SPEED == 3
    REAL v = scale * (aux_i - phi[i]);
#else
    REAL v = scale * aux_i;
#endif
    // |V| <= vmax: curvature of creases finer than the grid is noise, and would set
    // the time step (the host passes a huge vmax for no limit)
    return v < -vmax ? -vmax : (v > vmax ? vmax : v);
}

// The new value of channel c (at j = c * plane + i) after one Euler step of dt, given the
// speed v0 at the cell (the cut-off applied) and Phi's central gradient (fx, fy, fz) with
// f2 = |grad Phi|^2 + eps2: Phi <- Phi + dt V |grad Phi|, Phi-hat <- Phi-hat + dt V (N_Phi .
// N_Phi-hat) |grad Phi-hat|, upwind and slope-limited.
INLINE REAL region_next(LS_SPACE const REAL* ls, const int c, const int j, const REAL v0,
                        const REAL fx, const REAL fy, const REAL fz, const REAL f2,
                        const REAL eps2, const REAL dt, const int sx, const int sxy)
{
    REAL v = v0;
    if (c > 0) {
        CENTRAL_GRAD(ls, j, ux, uy, uz);
        v *= (fx * ux + fy * uy + fz * uz) * RSQRT(f2 * (ux * ux + uy * uy + uz * uz + eps2));
    }
    return ls[j] + dt * v * upwind_norm_3d(ls, j, sx, sxy, v);
}

// The extension's velocity at cell i of Phi (see regions.cl's extend_outer): a = sign(Phi)
// N_Phi, and the weight w = 1 - band_cutoff(Phi, lo, hi) of its step.
INLINE REAL extend_velocity(LS_SPACE const REAL* ls, const int i, const REAL lo, const REAL hi,
                            const int sx, const int sxy, REAL* ax, REAL* ay, REAL* az)
{
    const REAL p = ls[i];
    const REAL w = 1 - band_cutoff(p, lo, hi);
    CENTRAL_GRAD(ls, i, gx, gy, gz);
    const REAL s = ls_sign(p) * RSQRT(gx * gx + gy * gy + gz * gz + (REAL)1e-12);
    *ax = s * gx;
    *ay = s * gy;
    *az = s * gz;
    return w;
}

// Rigid motion (regions.cl's advect_step): u - dt cut U . grad u at j, slope-limited upwind
// differences per axis.
INLINE REAL advect_next(LS_SPACE const REAL* ls, const int j, const REAL cut, const REAL dt,
                        const REAL ux, const REAL uy, const REAL uz, const int sx,
                        const int sxy)
{
    REAL dmx, dpx, dmy, dpy, dmz, dpz;
    LS_ONE_SIDED_AT(ls, j, 1, dmx, dpx);
    LS_ONE_SIDED_AT(ls, j, sx, dmy, dpy);
    LS_ONE_SIDED_AT(ls, j, sxy, dmz, dpz);
    const REAL adv = ux * (ux > 0 ? dmx : dpx) + uy * (uy > 0 ? dmy : dpy) +
                     uz * (uz > 0 ? dmz : dpz);
    return ls[j] - dt * cut * adv;
}

// The reinitialisation's subcell fix (see regions.cl, reinitialisation): cells whose slope
// is within SUBCELL_TOL of 1 are kept, |grad u0| leans on the central estimate.
#ifndef SUBCELL_TOL
#define SUBCELL_TOL 0.1
#endif
#define SUBCELL_STEEP 0.5

#endif
