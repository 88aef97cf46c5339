// Explicit steps of the planar flows on ghost-padded fields (unit grid spacing).
// Each step reads `u` and writes every interior cell of `v` and its mirror-image ghosts
// (Neumann borders, MIRROR_GHOSTS), so the host only swaps the two before the next step.
#include "common.cl"

// Heat flow u_t = Lap u (thesis eq. 4.1), five-point Laplacian. Stable for dt <= 1/4.
__kernel void heat_step(__global const REAL* restrict u, __global REAL* restrict v,
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
    return d * EXP(-d * d * inv_k2);  // EXP: inline on PoCL, see common.cl
#else
    return d / (1 + d * d * inv_k2);
#endif
}

__kernel void perona_malik_step(__global const REAL* restrict u, __global REAL* restrict v,
                                const REAL dt, const REAL inv_k2, GRID_ARGS)
{
    FOR_EACH_CELL(i) {
        const REAL c = u[i];
        v[i] = c + dt * (pm_flux(u[i - 1] - c, inv_k2) + pm_flux(u[i + 1] - c, inv_k2) +
                         pm_flux(u[i - sx] - c, inv_k2) + pm_flux(u[i + sx] - c, inv_k2));
    }
    MIRROR_GHOSTS(v);
}

// Total-variation flux d / |grad u|_eps across one cell face, given the normal difference d
// (exact on the face) and the tangential one t (average of the two central differences
// beside the face); |.|_eps = sqrt(|.|^2 + eps^2).
inline REAL tv_flux(const REAL d, const REAL t, const REAL eps2)
{
    return d * RSQRT(d * d + t * t + eps2);
}

// div(grad u / |grad u|_eps) at cell i as a difference of face fluxes: conservative, so
// mass is kept with Neumann borders (mirrored ghosts give zero flux across border faces).
// The 3x3 neighbourhood is loaded once into registers.
#define TV_NEIGHBOURHOOD(u, i)                                                       \
    const REAL c = u[i], e = u[i + 1], w = u[i - 1], n = u[i + sx], s = u[i - sx];   \
    const REAL ne = u[i + 1 + sx], nw = u[i - 1 + sx];                               \
    const REAL se = u[i + 1 - sx], sw = u[i - 1 - sx]
#define TV_FLUX_E tv_flux(e - c, (REAL)0.25 * (n + ne - s - se), eps2)
#define TV_FLUX_W tv_flux(c - w, (REAL)0.25 * (n + nw - s - sw), eps2)
#define TV_FLUX_N tv_flux(n - c, (REAL)0.25 * (e + ne - w - nw), eps2)
#define TV_FLUX_S tv_flux(c - s, (REAL)0.25 * (e + se - w - sw), eps2)
#define TV_DIV (TV_FLUX_E - TV_FLUX_W + TV_FLUX_N - TV_FLUX_S)

// Anisotropic (total variation) flow u_t = div(grad u / |grad u|_eps) (thesis eq. 4.9).
// Every face coefficient is at most 1/eps, so dt <= eps/4 is stable.
__kernel void tv_step(__global const REAL* restrict u, __global REAL* restrict v,
                      const REAL dt, const REAL eps2, GRID_ARGS)
{
    FOR_EACH_CELL(i) {
        TV_NEIGHBOURHOOD(u, i);
        v[i] = c + dt * TV_DIV;
    }
    MIRROR_GHOSTS(v);
}

// Rudin-Osher-Fatemi: u_t = div(grad u / |grad u|_eps) - lambda_c (u - u0), lambda per
// channel read from the device (it may be updated there, see rof_lambda_*).
// Stable for dt <= 1 / (4/eps + lambda).
__kernel void rof_step(__global const REAL* restrict u, __global REAL* restrict v,
                       __global const REAL* restrict u0, __global const REAL* restrict lambda,
                       const REAL dt, const REAL eps2, GRID_ARGS)
{
    const REAL lam = lambda[get_global_id(2)];
    FOR_EACH_CELL(i) {
        TV_NEIGHBOURHOOD(u, i);
        v[i] = c + dt * (TV_DIV - lam * (c - u0[i]));
    }
    MIRROR_GHOSTS(v);
}

// Dynamic fidelity weight (the planar form of thesis eq. C.2). At a steady state
// div(p) = lambda (u - u0) with p the TV flux; multiplying by (u - u0) and summing by parts
// with the same face fluxes gives  lambda = -sum_faces p . grad(u - u0) / sum (u - u0)^2,
// and the target sum (u - u0)^2 = N sigma^2 makes the residual variance tend to sigma^2.
// Pass 1: one partial sum of p . grad(u - u0) per interior row.
__kernel void rof_lambda_rows(__global const REAL* restrict u, __global const REAL* restrict u0,
                              __global REAL* restrict partial, const REAL eps2, GRID_ARGS)
{
#ifdef CLPDE_POCL
    // Let the row sum be reordered, or its fixed order keeps the loop scalar (PoCL).
#pragma clang fp reassociate(on)
#endif
    const int y = get_global_id(1);
    if (y >= ny) return;
    const int row = get_global_id(2) * plane + (y + G) * sx + G;
    REAL acc = 0;
    for (int i = row; i < row + nx; ++i) {
        const REAL wx = (u[i + 1] - u0[i + 1]) - (u[i] - u0[i]);
        const REAL wy = (u[i + sx] - u0[i + sx]) - (u[i] - u0[i]);
        TV_NEIGHBOURHOOD(u, i);
        acc += TV_FLUX_E * wx + TV_FLUX_N * wy;
    }
    partial[get_global_id(2) * ny + y] = acc;
}

// Pass 2: one work-item per channel sums its rows and sets lambda (never negative).
__kernel void rof_lambda_finish(__global const REAL* restrict partial,
                                __global REAL* restrict lambda, const int ny,
                                const REAL inv_n_sigma2)
{
    const int c = get_global_id(0);
    REAL acc = 0;
    for (int y = 0; y < ny; ++y) acc += partial[c * ny + y];
    lambda[c] = fmax((REAL)0, -acc * inv_n_sigma2);
}

// Curvature diffusion u_t = g kappa |grad u| (thesis eq. 3.4), central differences as in
// appendix A:  kappa |grad u| = (uxx uy^2 - 2 ux uy uxy + uyy ux^2) / (ux^2 + uy^2 + eps).
// With HAS_WEIGHT, `g` is a one-channel weight field on the same padded plane.
#ifndef HAS_WEIGHT
#define HAS_WEIGHT 0
#endif
inline REAL curvature_speed(__global const REAL* u, const int i, const int sx, const REAL eps)
{
    const REAL ux = (REAL)0.5 * (u[i + 1] - u[i - 1]);
    const REAL uy = (REAL)0.5 * (u[i + sx] - u[i - sx]);
    const REAL uxx = u[i + 1] - 2 * u[i] + u[i - 1];
    const REAL uyy = u[i + sx] - 2 * u[i] + u[i - sx];
    const REAL uxy = (REAL)0.25 * (u[i + 1 + sx] - u[i - 1 + sx] - u[i + 1 - sx] + u[i - 1 - sx]);
    return (uxx * uy * uy - 2 * ux * uy * uxy + uyy * ux * ux) / (ux * ux + uy * uy + eps);
}

__kernel void curvature_step(__global const REAL* restrict u, __global REAL* restrict v,
                             __global const REAL* restrict g, const REAL dt, const REAL eps,
                             GRID_ARGS)
{
    const int chan = get_global_id(2) * plane;
    FOR_EACH_CELL(i) {
#if HAS_WEIGHT
        const REAL w = g[i - chan];
#else
        const REAL w = 1;
#endif
        v[i] = u[i] + dt * w * curvature_speed(u, i, sx, eps);
    }
    MIRROR_GHOSTS(v);
}
