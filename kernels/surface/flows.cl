// The other band flows (clpde/surface/flows.py): TV (4.10), harmonic maps (4.11, D.7),
// diffusion along a tangent field (4.15), TV's fidelity and dynamic lambda (C.1, C.2).
// Defines: NC, FLOW_P, HARMONIC, FIDELITY, ALONG, WEIGHTED, LINE_FIELD (the lambda kernels
// use none: the host looks them up with its flow's defines, so they come from the same
// program). Layout and conventions: surface.h.
#include "common.h"
#include "reduce.h"
#include "surface/surface.h"
#include "surface/flux.h"

// ---- the other band flows, one work-item per cell handling all NC channels ----------------
// (the fluxes and the stepped values: surface/flux.h's flow_cell, shared with the bricks). The
// step is flow_cell's v_c minus dt lambda (u_c - u0_c) (FIDELITY, C.1). lambda is a one-value
// device buffer, so the dynamic lambda (tv_lambda_update) never visits the host.
#ifndef FIDELITY
#define FIDELITY 0
#endif

__kernel void flows_step(__global const REAL* restrict u, __global REAL* restrict v,
                        __global const REAL* restrict psi, __global const REAL* restrict dir,
                        __global const REAL* restrict u0, const REAL r, const REAL dt,
                        __global const REAL* restrict lambda, const REAL e2, const int ex,
                        const int ey, const int ez, const int sx, const int sxy, RUN_ARGS)
{
    FOR_EACH_RUN_CELL(i) {
        REAL val[NC];
        flow_cell(u, plane, i, ex, ey, ez, psi, dir, plane, i, sx, sxy, e2, r, val);
        #pragma unroll
        for (int c = 0; c < NC; ++c) {
            const int ic = c * plane + i;
#if FIDELITY
            val[c] -= dt * lambda[0] * (u[ic] - u0[ic]);
#endif
            v[ic] = val[c];
        }
    }
}

// The per-cell terms of TV's dynamic lambda (C.2) over the node band (lambda_terms_cell).
__kernel void flows_tv_lambda_terms(__global const REAL* restrict u, __global const REAL* restrict u0,
                              __global const REAL* restrict psi, const REAL inv_h,
                              const REAL eps_cells, const REAL e2, const int ex, const int ey,
                              const int ez, const int sx, const int sxy,
                              __global REAL* restrict num, __global REAL* restrict area,
                              __global REAL* restrict resid, LIST_ARGS)
{
    LIST_RANGE(k0, k1, chan);
    for (int k = k0; k < k1; ++k) {
        const int i = list[k];
        const lambda_terms t = lambda_terms_cell(u, u0, i, ex, ey, ez, psi, i, sx, sxy, inv_h,
                                                 eps_cells, e2);
        num[k] = t.num;
        area[k] = t.area;
        resid[k] = t.resid;
    }
}

// Partial sums of a band-length array: work-item g adds entries [g*chunk, (g+1)*chunk).
// The host adds the few partials (band / chunk numbers).
__kernel void flows_chunk_sum(__global const REAL* restrict a, const int n, const int chunk,
                        __global REAL* restrict partial)
{
    const int g = get_global_id(0);
    if (g >= max(1, (n + chunk - 1) / chunk)) return;  // past the last chunk (Runtime.items)
    const int end = min((g + 1) * chunk, n);
    partial[g] = sum_rows(a + g * chunk, end - g * chunk);
}

// Dynamic lambda of (C.2) from the chunk sums of tv_lambda_terms' num, area and resid:
// lambda = f max(0, -num / (h sigma^2 area)) (scale = 1 / (h sigma^2)), capped at lam_max,
// the largest lambda the time step keeps stable (capped[0] = 1 then), kept in history[slot].
// f (state[0], starting at 1) corrects (C.2) toward the constraint it is derived from, a
// residual variance of sigma^2: at a steady state the continuous identity
// lambda |u - u0|^2 = -integral (u - u0) div(...) makes (C.2)'s lambda give exactly that,
// but the discrete one does not hold (one-sided differences of one side choice against a
// flow cycling through eight, closest-point re-extension), and for noise at the grid's
// scale the plain formula settled above sigma^2 (docs/surface.md has the figures). Once
// the residual has passed half of sigma^2, each update multiplies f by residual / sigma^2,
// limited to [0.67, 1.5] per update and f to [0.1, 10]: f stops moving only where the
// residual is sigma^2 (docs/surface.md measures how close on a sphere). inv_sigma2 = 0
// keeps f = 1: plain (C.2).
// One work-item: the partial sums are a few hundred numbers.
__kernel void flows_tv_lambda_update(__global const REAL* restrict num, __global const REAL* restrict area,
                               __global const REAL* restrict resid, const int groups,
                               const REAL scale, const REAL inv_sigma2, const REAL lam_max,
                               __global REAL* restrict lambda, __global REAL* restrict state,
                               __global REAL* restrict history, const int slot,
                               __global int* restrict capped)
{
    REAL sum_num = 0, sum_area = 0, sum_resid = 0;
    for (int g = 0; g < groups; ++g) {
        sum_num += num[g];
        sum_area += area[g];
        sum_resid += resid[g];
    }
    const REAL ratio = sum_area > 0 ? sum_resid * inv_sigma2 / sum_area : (REAL)0;
    REAL f = state[0];
    if (ratio > (REAL)0.5) {
        f *= FMIN(FMAX(ratio, (REAL)0.67), (REAL)1.5);
        f = FMIN(FMAX(f, (REAL)0.1), (REAL)10);
        state[0] = f;
    }
    REAL lam = sum_area > 0 ? -sum_num * scale / sum_area : (REAL)0;
    lam = lam > 0 ? f * lam : (REAL)0;
    if (lam > lam_max) {
        lam = lam_max;
        capped[0] = 1;
    }
    lambda[0] = lam;
    history[slot] = lam;
}
