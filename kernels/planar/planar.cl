// Explicit steps of the planar flows on ghost-padded fields (unit grid spacing).
// Each step reads `u` and writes every interior cell of `v` and its mirror-image ghosts
// (Neumann borders, MIRROR_GHOSTS), so the host only swaps the two before the next step.
#include "common.h"
#include "reduce.h"
#include "stencil.h"

// Heat flow u_t = Lap u (thesis eq. 4.1), five-point Laplacian. Stable for dt <= 1/4.
__kernel void planar_heat_step(__global const REAL* restrict u, __global REAL* restrict v,
                        const REAL dt, GRID_ARGS)
{
    FOR_EACH_CELL(i) {
        v[i] = u[i] + dt * (u[i - 1] + u[i + 1] + u[i - sx] + u[i + sx] - 4 * u[i]);
    }
    MIRROR_GHOSTS(v);
}

// Perona-Malik u_t = div(c(|grad u|) grad u), with c evaluated on each neighbour
// difference. EDGE_STOP 0: c(d) = exp(-(d/K)^2); 1: c(d) = 1 / (1 + (d/K)^2).
// c <= 1, so dt <= 1/4 is stable.
#ifndef EDGE_STOP
#define EDGE_STOP 0
#endif
inline REAL pm_flux(const REAL d, const REAL inv_k2)
{
#if EDGE_STOP == 0
    return d * EXP(-d * d * inv_k2);  // EXP: inline on PoCL, see common.h
#else
    return d / (1 + d * d * inv_k2);
#endif
}

__kernel void planar_perona_malik_step(__global const REAL* restrict u, __global REAL* restrict v,
                                const REAL dt, const REAL inv_k2, GRID_ARGS)
{
    FOR_EACH_CELL(i) {
        const REAL c = u[i];
        v[i] = c + dt * (pm_flux(u[i - 1] - c, inv_k2) + pm_flux(u[i + 1] - c, inv_k2) +
                         pm_flux(u[i - sx] - c, inv_k2) + pm_flux(u[i + sx] - c, inv_k2));
    }
    MIRROR_GHOSTS(v);
}

// Anisotropic (total variation) flow u_t = div(grad u / |grad u|_eps) (thesis eq. 4.9).
// Every face coefficient is at most 1/eps, so dt <= eps/4 is stable.
__kernel void planar_tv_step(__global const REAL* restrict u, __global REAL* restrict v,
                      const REAL dt, const REAL eps2, GRID_ARGS)
{
    FOR_EACH_CELL(i) {
        NEIGHBOURS_3X3(u, i);
        v[i] = c + dt * TV_DIV;
    }
    MIRROR_GHOSTS(v);
}

// Rudin-Osher-Fatemi: u_t = div(grad u / |grad u|_eps) - lambda_c (u - u0), lambda per
// channel read from the device (it may be updated there, see rof_lambda_*).
// Stable for dt <= 1 / (4/eps + lambda).
__kernel void planar_rof_step(__global const REAL* restrict u, __global REAL* restrict v,
                       __global const REAL* restrict u0, __global const REAL* restrict lambda,
                       const REAL dt, const REAL eps2, GRID_ARGS)
{
    const REAL lam = lambda[get_global_id(2)];
    FOR_EACH_CELL(i) {
        NEIGHBOURS_3X3(u, i);
        v[i] = c + dt * (TV_DIV - lam * (c - u0[i]));
    }
    MIRROR_GHOSTS(v);
}

// Dynamic fidelity weight (the planar form of thesis eq. C.2). At a steady state
// div(p) = lambda (u - u0) with p the TV flux; multiplying by (u - u0) and summing by parts
// with the same face fluxes gives  lambda = -sum_faces p . grad(u - u0) / sum (u - u0)^2,
// and the target sum (u - u0)^2 = N sigma^2 makes the residual variance tend to sigma^2.
// Pass 1: one partial sum of p . grad(u - u0) per interior row.
__kernel void planar_rof_lambda_rows(__global const REAL* restrict u, __global const REAL* restrict u0,
                              __global REAL* restrict partial, const REAL eps2, GRID_ARGS)
{
    REASSOCIATE_SUMS
    ROW_OF_ITEM(y, row);
    REAL acc = 0;
    for (int i = row; i < row + nx; ++i) {
        const REAL wx = (u[i + 1] - u0[i + 1]) - (u[i] - u0[i]);
        const REAL wy = (u[i + sx] - u0[i + sx]) - (u[i] - u0[i]);
        NEIGHBOURS_3X3(u, i);
        acc += TV_FLUX_E * wx + TV_FLUX_N * wy;
    }
    partial[get_global_id(2) * ny + y] = acc;
}

// Pass 2: one work-item per channel sums its rows and sets lambda (never negative).
__kernel void planar_rof_lambda_finish(__global const REAL* restrict partial,
                                __global REAL* restrict lambda, const int ny,
                                const REAL inv_n_sigma2)
{
    const int c = get_global_id(0);
    lambda[c] = fmax((REAL)0, -sum_rows(partial + c * ny, ny) * inv_n_sigma2);
}

// Curvature diffusion u_t = g kappa |grad u| (thesis eq. 3.4), central differences as in
// appendix A (curvature_speed, stencil.h). With HAS_WEIGHT, `g` is a one-channel weight
// field on the same padded plane.
#ifndef HAS_WEIGHT
#define HAS_WEIGHT 0
#endif

__kernel void planar_curvature_step(__global const REAL* restrict u, __global REAL* restrict v,
                             __global const REAL* restrict g, const REAL dt, const REAL eps,
                             GRID_ARGS)
{
    const int chan = get_global_id(2) * plane;
    FOR_EACH_CELL(i) {
#if HAS_WEIGHT
        const REAL weight = g[i - chan];
#else
        const REAL weight = 1;
#endif
        NEIGHBOURS_3X3(u, i);
        v[i] = c + dt * weight * curvature_speed(c, e, w, n, s, ne, nw, se, sw, eps);
    }
    MIRROR_GHOSTS(v);
}
