// Upwind level-set stencils shared by the level-set kernels (levelset.cl and
// tracking/features.cl in 2D, regions.cl and surface/reinit.cl in 3D): the sign function,
// minmod, slope-limited one-sided differences (second-order ENO, Osher-Sethian) and the
// Godunov gradient norm for u_t = V |grad u|. Unit grid spacing (godunov_axis takes any
// differences); `sx` is the row stride, `sxy` the slab stride. Include after common.h.
#ifndef CLPDE_GODUNOV_H
#define CLPDE_GODUNOV_H

// The address space of the fields the stencil functions here, in reinit.h and in extend.h
// read: __global volumes by default; regions/bricks.cl defines it as its tiles' (private on
// CPUs) before including them, so the brick kernels run the same functions on a tile.
#ifndef LS_SPACE
#define LS_SPACE __global
#endif

// sign(a) in {-1, 0, 1}, as selects (PoCL keeps sign() out of line, and loops scalar).
INLINE REAL ls_sign(const REAL a)
{
    return (a > 0) ? (REAL)1 : ((a < 0) ? (REAL)-1 : (REAL)0);
}

// minmod(a, b): the smaller-magnitude argument when both have the same sign, else 0.
INLINE REAL minmod(const REAL a, const REAL b)
{
    const REAL m = FMIN(FABS(a), FABS(b));
    return (a * b > 0) ? COPYSIGN(m, a) : (REAL)0;
}

// Slope-limited one-sided differences at c along one axis, given the values two cells
// either side (m2, m1, c, p1, p2): the first-order difference corrected by half the minmod
// of the neighbouring second differences (second-order ENO, Osher-Sethian).
#define LS_ONE_SIDED(m2, m1, c, p1, p2, dm, dp)                                        \
    {                                                                                  \
        const REAL q_m = (m2) - 2 * (m1) + (c);                                        \
        const REAL q_c = (m1) - 2 * (c) + (p1);                                        \
        const REAL q_p = (c) - 2 * (p1) + (p2);                                        \
        dm = ((c) - (m1)) + (REAL)0.5 * minmod(q_m, q_c);                              \
        dp = ((p1) - (c)) - (REAL)0.5 * minmod(q_c, q_p);                              \
    }

// The slope-limited one-sided differences of u at padded index i along stride s.
#define LS_ONE_SIDED_AT(u, i, s, dm, dp)                                               \
    LS_ONE_SIDED((u)[(i) - 2 * (s)], (u)[(i) - (s)], (u)[i], (u)[(i) + (s)],            \
                 (u)[(i) + 2 * (s)], dm, dp)

// One axis' contribution to the squared Godunov gradient norm for u_t = V |grad u|.
// V < 0 (the level sets move toward larger u): the upwind side is the one u increases
// away from; V > 0: the mirror choice.
INLINE REAL godunov_axis(const REAL dm, const REAL dp, const REAL v)
{
    const REAL down = FMAX(SQR(FMAX(dm, (REAL)0)), SQR(FMIN(dp, (REAL)0)));
    const REAL up = FMAX(SQR(FMIN(dm, (REAL)0)), SQR(FMAX(dp, (REAL)0)));
    return (v > 0) ? up : down;
}

// Slope-limited upwind |grad u| at padded index i for u_t = V |grad u| in 2D.
INLINE REAL upwind_norm_2d(LS_SPACE const REAL* u, const int i, const int sx, const REAL v)
{
    REAL dmx, dpx, dmy, dpy;
    LS_ONE_SIDED_AT(u, i, 1, dmx, dpx);
    LS_ONE_SIDED_AT(u, i, sx, dmy, dpy);
    return SQRT(godunov_axis(dmx, dpx, v) + godunov_axis(dmy, dpy, v));
}

// The same in 3D.
INLINE REAL upwind_norm_3d(LS_SPACE const REAL* u, const int i, const int sx, const int sxy,
                           const REAL v)
{
    REAL dmx, dpx, dmy, dpy, dmz, dpz;
    LS_ONE_SIDED_AT(u, i, 1, dmx, dpx);
    LS_ONE_SIDED_AT(u, i, sx, dmy, dpy);
    LS_ONE_SIDED_AT(u, i, sxy, dmz, dpz);
    return SQRT(godunov_axis(dmx, dpx, v) + godunov_axis(dmy, dpy, v) +
                godunov_axis(dmz, dpz, v));
}

#endif
