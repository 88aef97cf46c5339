// PDEs on implicit surfaces (thesis chapter 4, appendices B-E) over a narrow band.
//
// Volumes are ghost-padded 3D arrays, layout (channels, nz + 2G, ny + 2G, nx + 2G), x
// fastest: `sx` is the row stride, `sxy` the slab stride and `plane` (LIST_ARGS) the channel
// stride. Kernels visit the cells of a compacted band list (flat padded indices, built on
// the device by fields.cl's compaction) and never test for borders: the band keeps clear of
// the ghost layer by construction.
//
// Accuracy: data is kept constant along the normals by closest-point re-extension of the whole
// band after every step (extend_cp). Without it the 2001 scheme drifts off the surface and its
// error grows under refinement.
#include "common.cl"

// INTERP 3: tricubic Lagrange interpolation (4x4x4 nodes); 1: trilinear (2x2x2).
#ifndef INTERP
#define INTERP 3
#endif
// Channels handled together by one work-item in the extension and sampling kernels.
#ifndef NC
#define NC 1
#endif

// ---- band construction ------------------------------------------------------------------

// mask[i] = 1 where |psi| < width on interior cells of the padded volume. Work-item (y, z)
// of the interior walks one row.
__kernel void band_mask(__global const REAL* restrict psi, __global uchar* restrict mask,
                        const REAL width, const int nx, const int ny, const int nz,
                        const int sx, const int sxy, const int G)
{
    const int y = get_global_id(0), z = get_global_id(1);
    if (y >= ny || z >= nz) return;
    const int row = (z + G) * sxy + (y + G) * sx + G;
    for (int x = 0; x < nx; ++x) mask[row + x] = fabs(psi[row + x]) < width;
}

// Closest points x - psi grad(psi) / |grad(psi)| of the band cells, in padded index units
// (grad by central differences; psi in grid units = world units / spacing).
__kernel void closest_points(__global const REAL* restrict psi, const REAL inv_h,
                             __global REAL* restrict cpx, __global REAL* restrict cpy,
                             __global REAL* restrict cpz, const int sx, const int sxy,
                             LIST_ARGS)
{
    LIST_RANGE(k0, k1, chan);
    for (int k = k0; k < k1; ++k) {
        const int i = list[k];
        const REAL gx = psi[i + 1] - psi[i - 1];
        const REAL gy = psi[i + sx] - psi[i - sx];
        const REAL gz = psi[i + sxy] - psi[i - sxy];
        const REAL d = psi[i] * inv_h * RSQRT(gx * gx + gy * gy + gz * gz + (REAL)1e-30);
        const int z = i / sxy, y = (i - z * sxy) / sx, x = i - z * sxy - y * sx;
        cpx[k] = x - d * gx;
        cpy[k] = y - d * gy;
        cpz[k] = z - d * gz;
    }
}

// ---- interpolation ------------------------------------------------------------------------

// Interpolation nodes and weights along one axis for position p (index units), with the
// first node clamped into [0, n - NODES] so a read never leaves the volume.
#if INTERP == 3
#define NODES 4
inline int axis_weights(const REAL p, const int n, REAL* w)
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
#define NODES 2
inline int axis_weights(const REAL p, const int n, REAL* w)
{
    const REAL f = floor(p);
    const REAL t = p - f;
    w[0] = 1 - t;
    w[1] = t;
    return clamp((int)f, 0, n - NODES);
}
#endif

// Interpolate all NC channels of u (channel stride `plane`) at (px, py, pz) into out[].
inline void interpolate(__global const REAL* restrict u, const REAL px, const REAL py,
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
// channels. With NORMALIZE the NC-vector is rescaled to unit length (harmonic maps).
#ifndef NORMALIZE
#define NORMALIZE 0
#endif
__kernel void extend_cp(__global const REAL* restrict src, __global REAL* restrict dst,
                        __global const REAL* restrict cpx, __global const REAL* restrict cpy,
                        __global const REAL* restrict cpz, const int sx, const int sxy,
                        const int pnx, const int pny, const int pnz, LIST_ARGS)
{
    LIST_RANGE(k0, k1, chan);
    for (int k = k0; k < k1; ++k) {
        REAL v[NC];
        interpolate(src, cpx[k], cpy[k], cpz[k], sx, sxy, pnx, pny, pnz, plane, v);
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
__kernel void sample_points(__global const REAL* restrict u, __global const REAL* restrict px,
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

// ---- intrinsic heat flow (4.7) / (4.8), discretised as in appendix E -----------------------
//
// Flux at cell j: w = |N| P_N v with v the one-sided gradient of u (difference offsets ex,
// ey, ez: +stride forward, -stride backward, times sign so v approximates grad u) and N the
// central-difference gradient of psi. The update is the complementary one-sided divergence,
// divided by |N| (WEIGHTED, eq. 4.7) or not (signed distance form, eq. 4.8).
#ifndef WEIGHTED
#define WEIGHTED 0
#endif

#define ONE_SIDED_SIGN(e) ((e) > 0 ? (REAL)1 : (REAL)-1)

typedef struct { REAL x, y, z; } vec3r;

inline vec3r psi_normal(__global const REAL* restrict psi, const int j, const int sx,
                        const int sxy)
{
    vec3r n;
    n.x = (REAL)0.5 * (psi[j + 1] - psi[j - 1]);
    n.y = (REAL)0.5 * (psi[j + sx] - psi[j - sx]);
    n.z = (REAL)0.5 * (psi[j + sxy] - psi[j - sxy]);
    return n;
}

// |N| P_N v (or P_N v) at cell j.
inline vec3r heat_flux(__global const REAL* restrict u, __global const REAL* restrict psi,
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
inline REAL heat_div(__global const REAL* restrict u, __global const REAL* restrict psi,
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
                        const int ey, const int ez, const int sx, const int sxy, LIST_ARGS)
{
    LIST_RANGE(k0, k1, chan);
    __global const REAL* uc = u + chan;
    for (int k = k0; k < k1; ++k) {
        const int i = list[k];
        v[chan + i] = uc[i] + r * heat_div(uc, psi, i, ex, ey, ez, sx, sxy);
    }
}
