// Regularised Perona-Malik (Catte, Lions, Morel and Coll 1992):
//     u_t = div(c(|grad (G_s * u)|) grad u),
// the diffusivity read from a Gaussian-smoothed copy of u, so that an isolated noise spike,
// whose own gradient is large, no longer stops its own diffusion. The flux of each face is
// the plain Perona-Malik one (planar.cl's perona_malik_step), with the edge-stopping c taken
// from the smoothed field's difference across that face: with s -> 0 the smoothed copy is u
// and the step is perona_malik_step exactly.
//
// The smoothing is separable: gauss_rows then gauss_cols, each a 1-D convolution of radius
// r with weights w[0..r] (w[k] for offsets +-k), mirrored at the border (index -1 reads 0),
// the same Neumann border as the flows' ghosts. Radius and weights are arguments, not
// defines, so no new program is built per scale.
#include "common.h"
#include "stencil.h"

inline int mirror_index(int k, const int n)
{
    // reflections until inside: radii larger than the image repeat the reflection
    for (int pass = 0; pass < 8 && (k < 0 || k >= n); ++pass)
        k = k < 0 ? -k - 1 : 2 * n - k - 1;
    return clamp(k, 0, n - 1);
}

__kernel void catte_gauss_rows(__global const REAL* restrict u, __global REAL* restrict v,
                         __global const REAL* restrict w, const int radius, GRID_ARGS)
{
    FOR_EACH_CELL(i) {
        const int x = i - row0_;
        REAL acc = w[0] * u[i];
        for (int k = 1; k <= radius; ++k)
            acc += w[k] * (u[row0_ + mirror_index(x - k, nx)] +
                           u[row0_ + mirror_index(x + k, nx)]);
        v[i] = acc;
    }
    MIRROR_GHOSTS(v);
}

__kernel void catte_gauss_cols(__global const REAL* restrict u, __global REAL* restrict v,
                         __global const REAL* restrict w, const int radius, GRID_ARGS)
{
    FOR_EACH_CELL(i) {
        const int col = i - row_y_ * sx;  // the same column's cell in row 0
        REAL acc = w[0] * u[i];
        for (int k = 1; k <= radius; ++k)
            acc += w[k] * (u[col + mirror_index(row_y_ - k, ny) * sx] +
                           u[col + mirror_index(row_y_ + k, ny) * sx]);
        v[i] = acc;
    }
    MIRROR_GHOSTS(v);
}

#ifndef EDGE_STOP
#define EDGE_STOP 0
#endif
// d the face's difference of u, ds that of the smoothed field
inline REAL catte_flux(const REAL d, const REAL ds, const REAL inv_k2)
{
#if EDGE_STOP == 0
    return d * EXP(-ds * ds * inv_k2);
#else
    return d / (1 + ds * ds * inv_k2);
#endif
}

__kernel void catte_perona_malik_step(__global const REAL* restrict u,
                                      __global const REAL* restrict us,
                                      __global REAL* restrict v, const REAL dt,
                                      const REAL inv_k2, GRID_ARGS)
{
    FOR_EACH_CELL(i) {
        const REAL c = u[i], cs = us[i];
        v[i] = c + dt * (catte_flux(u[i - 1] - c, us[i - 1] - cs, inv_k2) +
                         catte_flux(u[i + 1] - c, us[i + 1] - cs, inv_k2) +
                         catte_flux(u[i - sx] - c, us[i - sx] - cs, inv_k2) +
                         catte_flux(u[i + sx] - c, us[i + sx] - cs, inv_k2));
    }
    MIRROR_GHOSTS(v);
}
