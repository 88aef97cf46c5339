// The intrinsic heat flow (4.7, 4.8) and Turk's reaction-diffusion (4.12-4.14) over a
// surface's band runs (clpde/surface/flows.py). Defines: WEIGHTED, ALONG. Layout and
// conventions: surface.h.
#include "common.cl"
#include "surface.h"

// ---- intrinsic heat flow (4.7) / (4.8), discretised as in appendix E -----------------------
//
// Flux at cell j: w = |N| P_N v with v the one-sided gradient of u (difference offsets ex,
// ey, ez: +stride forward, -stride backward, times sign so v approximates grad u) and N the
// central-difference gradient of psi. The update is the complementary one-sided divergence,
// divided by |N| (WEIGHTED, eq. 4.7) or not (signed distance form, eq. 4.8).
#ifndef WEIGHTED
#define WEIGHTED 0
#endif

// |N| P_N v (or P_N v) at cell j.
INLINE vec3r heat_flux(__global const REAL* restrict u, __global const REAL* restrict psi,
                       const int j, const int ex, const int ey, const int ez, const int sx,
                       const int sxy)
{
    const REAL c = u[j];
    vec3r v;
    v.x = ONE_SIDED_SIGN(ex) * (u[j + ex] - c);
    v.y = ONE_SIDED_SIGN(ey) * (u[j + ey] - c);
    v.z = ONE_SIDED_SIGN(ez) * (u[j + ez] - c);
    const vec3r n = psi_normal(psi, j, sx, sxy);
    const REAL nn = n.x * n.x + n.y * n.y + n.z * n.z + (REAL)1e-30;
    const REAL s = (n.x * v.x + n.y * v.y + n.z * v.z) / nn;
    vec3r w;
#if WEIGHTED
    const REAL len = SQRT(nn);
#else
    const REAL len = 1;
#endif
    w.x = len * (v.x - s * n.x);
    w.y = len * (v.y - s * n.y);
    w.z = len * (v.z - s * n.z);
    return w;
}

// The appendix-E divergence of the flux at cell i (grid units).
INLINE REAL heat_div(__global const REAL* restrict u, __global const REAL* restrict psi,
                     const int i, const int ex, const int ey, const int ez, const int sx,
                     const int sxy)
{
    const vec3r wc = heat_flux(u, psi, i, ex, ey, ez, sx, sxy);
    const vec3r wx = heat_flux(u, psi, i - ex, ex, ey, ez, sx, sxy);
    const vec3r wy = heat_flux(u, psi, i - ey, ex, ey, ez, sx, sxy);
    const vec3r wz = heat_flux(u, psi, i - ez, ex, ey, ez, sx, sxy);
    REAL div = ONE_SIDED_SIGN(ex) * (wc.x - wx.x) + ONE_SIDED_SIGN(ey) * (wc.y - wy.y) +
               ONE_SIDED_SIGN(ez) * (wc.z - wz.z);
#if WEIGHTED
    const vec3r n = psi_normal(psi, i, sx, sxy);
    div *= RSQRT(n.x * n.x + n.y * n.y + n.z * n.z + (REAL)1e-30);
#endif
    return div;
}

// One explicit step v = u + r * div(...) over the band (r = dt / h^2), every channel.
__kernel void heat_step(__global const REAL* restrict u, __global REAL* restrict v,
                        __global const REAL* restrict psi, const REAL r, const int ex,
                        const int ey, const int ez, const int sx, const int sxy, RUN_ARGS)
{
    FOR_EACH_RUN_CELL(i) {
        v[chan + i] = u[chan + i] + r * heat_div(u + chan, psi, i, ex, ey, ez, sx, sxy);
    }
}

// ---- reaction-diffusion (Turk), eqs. (4.12)-(4.14), in grid units ---------------------------
// a += dt (s (16 - a b) + Da div(P grad a)), b += dt (s (a b - b - beta) + Db div(P grad b)),
// b clamped at >= 0. With ALONG, a diffuses along the tangent field d only (4.14).
INLINE vec3r along_flux(__global const REAL* restrict u, __global const REAL* restrict psi,
                        __global const REAL* restrict dir, const int j, const int ex,
                        const int ey, const int ez, const int sx, const int sxy, const int plane)
{
    const vec3r w = heat_flux(u, psi, j, ex, ey, ez, sx, sxy);
    const REAL dx = dir[j], dy = dir[plane + j], dz = dir[2 * plane + j];
    const REAL a = dx * w.x + dy * w.y + dz * w.z;
    vec3r out;
    out.x = a * dx;
    out.y = a * dy;
    out.z = a * dz;
    return out;
}

__kernel void turk_step(__global const REAL* restrict u, __global REAL* restrict v,
                        __global const REAL* restrict psi, __global const REAL* restrict dir,
                        __global const REAL* restrict beta, const REAL dt, const REAL da,
                        const REAL db, const REAL s, const int ex, const int ey, const int ez,
                        const int sx, const int sxy, RUN_ARGS)
{
    __global const REAL* ub = u + plane;
    FOR_EACH_RUN_CELL(i) {
        const REAL a = u[i], b = ub[i];
#if ALONG
        const vec3r wc = along_flux(u, psi, dir, i, ex, ey, ez, sx, sxy, plane);
        const vec3r wx = along_flux(u, psi, dir, i - ex, ex, ey, ez, sx, sxy, plane);
        const vec3r wy = along_flux(u, psi, dir, i - ey, ex, ey, ez, sx, sxy, plane);
        const vec3r wz = along_flux(u, psi, dir, i - ez, ex, ey, ez, sx, sxy, plane);
        const REAL diff_a = ONE_SIDED_SIGN(ex) * (wc.x - wx.x) + ONE_SIDED_SIGN(ey) * (wc.y - wy.y) +
                            ONE_SIDED_SIGN(ez) * (wc.z - wz.z);
#else
        const REAL diff_a = heat_div(u, psi, i, ex, ey, ez, sx, sxy);
#endif
        const REAL diff_b = heat_div(ub, psi, i, ex, ey, ez, sx, sxy);
        v[i] = a + dt * (s * (16 - a * b) + da * diff_a);
        // b clamped at 0 by a select: fmax is an out-of-line call on PoCL (scalar loop)
        const REAL nb = b + dt * (s * (a * b - b - beta[i]) + db * diff_b);
        v[plane + i] = nb > 0 ? nb : (REAL)0;
    }
}
