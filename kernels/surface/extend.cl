// Closest-point re-extension of data on a surface's band, sampling at points, and extension
// along normals by the PDE of section 4.2 (clpde/surface/flows.py, implicit.py). Defines:
// INTERP, NC, NORMALIZE, LINE_FIELD. Layout and conventions: surface.h.
#include "common.h"
#include "surface/surface.h"
#include "extend.h"

// Interpolation nodes and weights along one axis for position p (index units), with the
// first node clamped into [0, n - NODES] so a read never leaves the volume.
#if INTERP == 3
INLINE int axis_weights(const REAL p, const int n, REAL* w)
{
    const REAL f = floor(p);
    const REAL t = p - f;
    // Lagrange cubic through nodes -1, 0, 1, 2 (relative to floor(p)).
    w[0] = -t * (t - 1) * (t - 2) / 6;
    w[1] = (t + 1) * (t - 1) * (t - 2) / 2;
    w[2] = -(t + 1) * t * (t - 2) / 2;
    w[3] = (t + 1) * t * (t - 1) / 6;
    return clamp((int)f - 1, 0, n - NODES);
}
#else
INLINE int axis_weights(const REAL p, const int n, REAL* w)
{
    const REAL f = floor(p);
    const REAL t = p - f;
    w[0] = 1 - t;
    w[1] = t;
    return clamp((int)f, 0, n - NODES);
}
#endif

// Interpolate all NC channels of u (channel stride `plane`) at (px, py, pz) into out[].
INLINE void interpolate(__global const REAL* restrict u, const REAL px, const REAL py,
                        const REAL pz, const int sx, const int sxy, const int pnx,
                        const int pny, const int pnz, const int plane, REAL* out)
{
    REAL wx[NODES], wy[NODES], wz[NODES];
    const int x0 = axis_weights(px, pnx, wx);
    const int y0 = axis_weights(py, pny, wy);
    const int z0 = axis_weights(pz, pnz, wz);
    for (int c = 0; c < NC; ++c) out[c] = 0;
    for (int c = 0; c < NC; ++c) {
        REAL acc = 0;
        for (int a = 0; a < NODES; ++a) {
            REAL acc_y = 0;
            for (int b = 0; b < NODES; ++b) {
                const int row = c * plane + (z0 + a) * sxy + (y0 + b) * sx + x0;
                REAL acc_x = 0;
                for (int e = 0; e < NODES; ++e) acc_x += wx[e] * u[row + e];
                acc_y += wy[b] * acc_x;
            }
            acc += wz[a] * acc_y;
        }
        out[c] = acc;
    }
}

// Whole-band closest-point re-extension: dst(x) = src(cp(x)) for every band cell, all NC
// channels, from the stencils of surface/band.cl's cp_stencils. With NORMALIZE the NC-vector is rescaled to
// unit length (harmonic maps). Tricubic: the 4 nodes of a row are contiguous, so each of
// the 16 rows is one 4-wide load, summed with the y-z weights; one dot product with the x
// weights at the end.
#ifndef NORMALIZE
#define NORMALIZE 0
#endif
__kernel void extend_cp(__global const REAL* restrict src, __global REAL* restrict dst,
                        __global const int* restrict base, __global const REAL* restrict frac,
                        const int sx, const int sxy, LIST_ARGS)
{
    LIST_RANGE(k0, k1, chan);
    for (int k = k0; k < k1; ++k) {
        const int b0 = base[k];
        const REAL tx = frac[k], ty = frac[nlist + k], tz = frac[2 * nlist + k];
        REAL v[NC];
        for (int c = 0; c < NC; ++c) {
            __global const REAL* u = src + c * plane + b0;
#if LINE_FIELD
            // line field: every node's vector turned to the side of floor(cp)'s node
            const int ref = b0 + (NODES / 2 - 1) * (sxy + sx + 1);  // floor(cp)'s node
            const NODE_WEIGHTS wx = node_weights(tx), wy = node_weights(ty), wz = node_weights(tz);
            REAL acc = 0;
            for (int a = 0; a < NODES; ++a)
                for (int b = 0; b < NODES; ++b)
                    for (int e = 0; e < NODES; ++e) {
                        const int p = b0 + a * sxy + b * sx + e;
                        acc += line_sign(src, ref, p, plane) * (wz[a] * wy[b] * wx[e]) * u[p - b0];
                    }
            v[c] = acc;
#elif INTERP == 3
            const REAL4 wy = node_weights(ty), wz = node_weights(tz);
            REAL4 acc = 0;
            for (int a = 0; a < 4; ++a) {
                __global const REAL* slab = u + a * sxy;
                acc += wz[a] * (wy.x * LOAD4(slab) + wy.y * LOAD4(slab + sx) +
                                wy.z * LOAD4(slab + 2 * sx) + wy.w * LOAD4(slab + 3 * sx));
            }
            const REAL4 wx = node_weights(tx);
            v[c] = acc.x * wx.x + acc.y * wx.y + acc.z * wx.z + acc.w * wx.w;
#else
            const REAL2 wx = node_weights(tx), wy = node_weights(ty), wz = node_weights(tz);
            REAL acc = 0;
            for (int a = 0; a < 2; ++a)
                for (int b = 0; b < 2; ++b) {
                    const int row = a * sxy + b * sx;
                    acc += (wz[a] * wy[b]) * (wx.x * u[row] + wx.y * u[row + 1]);
                }
            v[c] = acc;
#endif
        }
#if NORMALIZE
        REAL n2 = 0;
        for (int c = 0; c < NC; ++c) n2 += v[c] * v[c];
        const REAL s = n2 > 0 ? RSQRT(n2) : (REAL)0;
        for (int c = 0; c < NC; ++c) v[c] *= s;
#endif
        const int i = list[k];
        for (int c = 0; c < NC; ++c) dst[c * plane + i] = v[c];
    }
}

// Values of u at arbitrary points (padded index units), out laid out (NC, npoints).
__kernel void extend_sample_points(__global const REAL* restrict u, __global const REAL* restrict px,
                            __global const REAL* restrict py, __global const REAL* restrict pz,
                            const int npoints, __global REAL* restrict out, const int sx,
                            const int sxy, const int pnx, const int pny, const int pnz,
                            const int plane)
{
    const int k = get_global_id(0);
    if (k >= npoints) return;
    REAL v[NC];
    interpolate(u, px[k], py[k], pz[k], sx, sxy, pnx, pny, pnz, plane, v);
    for (int c = 0; c < NC; ++c) out[c * npoints + k] = v[c];
}

// ---- extension along normals by the PDE of section 4.2 ------------------------------------
// u_t + sign(psi) grad u . grad psi / |grad psi| = 0, first-order upwind, r = dt / h (grid
// units; stable for r <= 1/sqrt(3) since the velocity has unit length). sign is smoothed as
// psi / sqrt(psi^2 + h^2) so the surface's own cells barely move. All NC channels.
__kernel void extend_pde_step(__global const REAL* restrict u, __global REAL* restrict v,
                              __global const REAL* restrict psi, const REAL r, const REAL h,
                              const int sx, const int sxy, LIST_ARGS)
{
    LIST_RANGE(k0, k1, chan);
    for (int k = k0; k < k1; ++k) {
        const int i = list[k];
        const vec3r n = psi_normal(psi, i, sx, sxy);
        const REAL inv = RSQRT(n.x * n.x + n.y * n.y + n.z * n.z + (REAL)1e-30);
        const REAL sgn = psi[i] * RSQRT(psi[i] * psi[i] + h * h);
        const REAL ax = sgn * n.x * inv, ay = sgn * n.y * inv, az = sgn * n.z * inv;
        for (int c = 0; c < NC; ++c) {
            const int ic = c * plane + i;
            v[ic] = u[ic] - r * upwind_transport(u, ic, sx, sxy, ax, ay, az);
        }
    }
}
