// Extension of data along a level set's normals, shared by regions.cl (extend_outer: the
// Phi-hat carried out from the surface) and surface/extend.cl (extend_pde_step: data on a
// surface's band, section 4.2): explicit first-order upwind steps of
//     u_t + a . grad u = 0,   a = sign(psi) grad psi / |grad psi|,
// so values travel away from the zero level set along its normals. The two callers build
// the velocity a differently (regions.cl: the sign itself and a 1e-12 guard on |grad Phi|^2;
// surface/extend.cl: the smoothed sign psi / sqrt(psi^2 + h^2), a 1e-30 guard, and the
// product taken in another order), and scale the step differently (dt times a cutoff
// weight, or r = dt / h), so each keeps those; the transport term is the part they share.
// Unit grid spacing; `sx` is the row stride, `sxy` the slab stride. Include after common.h.
#ifndef CLPDE_EXTEND_H
#define CLPDE_EXTEND_H

#ifndef LS_SPACE
#define LS_SPACE __global  // the fields' address space (see godunov.h)
#endif

// a . grad u at padded index j, each axis' difference one-sided from the side the velocity
// comes from (upwind), summed x, y, z in that order (callers' results depend on it).
INLINE REAL upwind_transport(LS_SPACE const REAL* u, const int j, const int sx,
                             const int sxy, const REAL ax, const REAL ay, const REAL az)
{
    const REAL c = u[j];
    return ax * (ax > 0 ? c - u[j - 1] : u[j + 1] - c) +
           ay * (ay > 0 ? c - u[j - sx] : u[j + sx] - c) +
           az * (az > 0 ? c - u[j - sxy] : u[j + sxy] - c);
}

#endif
