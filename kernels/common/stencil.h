// Stencils of the planar schemes on the 3x3 neighbourhood of a cell of a padded field
// (unit grid spacing, row stride sx). Include after common.h.
#ifndef CLPDE_STENCIL_H
#define CLPDE_STENCIL_H

// The 3x3 neighbourhood of padded cell i, loaded once into registers: c the cell, e/w/n/s
// its neighbours at +-1 and +-sx, ne/nw/se/sw the corners.
#define NEIGHBOURS_3X3(u, i)                                                         \
    const REAL c = u[i], e = u[i + 1], w = u[i - 1], n = u[i + sx], s = u[i - sx];   \
    const REAL ne = u[i + 1 + sx], nw = u[i - 1 + sx];                               \
    const REAL se = u[i + 1 - sx], sw = u[i - 1 - sx]

// Total-variation flux d / |grad u|_eps across one cell face, given the normal difference d
// (exact on the face) and the tangential one t (average of the two central differences
// beside the face); |.|_eps = sqrt(|.|^2 + eps^2).
inline REAL tv_flux(const REAL d, const REAL t, const REAL eps2)
{
    return d * RSQRT(d * d + t * t + eps2);
}

// div(grad u / |grad u|_eps) at a cell as a difference of face fluxes, from the names
// NEIGHBOURS_3X3 defines and `eps2`: conservative, so mass is kept with Neumann borders
// (mirrored ghosts give zero flux across border faces).
#define TV_FLUX_E tv_flux(e - c, (REAL)0.25 * (n + ne - s - se), eps2)
#define TV_FLUX_W tv_flux(c - w, (REAL)0.25 * (n + nw - s - sw), eps2)
#define TV_FLUX_N tv_flux(n - c, (REAL)0.25 * (e + ne - w - nw), eps2)
#define TV_FLUX_S tv_flux(c - s, (REAL)0.25 * (e + se - w - sw), eps2)
#define TV_DIV (TV_FLUX_E - TV_FLUX_W + TV_FLUX_N - TV_FLUX_S)

// kappa |grad u|, the curvature of the level lines times the gradient's length, with
// appendix A's central differences:
//     kappa |grad u| = (uxx uy^2 - 2 ux uy uxy + uyy ux^2) / (ux^2 + uy^2 + eps).
inline REAL curvature_speed(const REAL c, const REAL e, const REAL w, const REAL n,
                            const REAL s, const REAL ne, const REAL nw, const REAL se,
                            const REAL sw, const REAL eps)
{
    const REAL ux = (REAL)0.5 * (e - w);
    const REAL uy = (REAL)0.5 * (n - s);
    const REAL uxx = e - 2 * c + w;
    const REAL uyy = n - 2 * c + s;
    const REAL uxy = (REAL)0.25 * (ne - nw - se + sw);
    return (uxx * uy * uy - 2 * ux * uy * uxy + uyy * ux * ux) / (ux * ux + uy * uy + eps);
}

#endif
