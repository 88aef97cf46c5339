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
#include "reduce.h"

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
    for (int x = 0; x < nx; ++x) mask[row + x] = FABS(psi[row + x]) < width;
}

// Band runs: maximal stretches of consecutive cells along x in a band list. flags[k] = 1
// where entry k starts a run; the host compacts the flags into run offsets (the positions
// of the run starts in the list).
__kernel void band_run_starts(__global const int* restrict list, const int n,
                              __global uchar* restrict flags)
{
    const int k = get_global_id(0);
    if (k >= n) return;
    flags[k] = k == 0 || list[k - 1] != list[k] - 1;
}

// Cell ranges [start, end) of the runs, each lengthened to a multiple of `pad` cells where
// its row's interior and the next run leave room: a vectorised loop then ends without a
// scalar remainder (about as slow per cell as a whole vector). The extra cells' stepped
// values are never read (re-extension reads only the band's nodes).
__kernel void band_run_bounds(__global const int* restrict list,
                              __global const int* restrict offsets, const int nruns,
                              const int n, const int pad, const int nx, const int sx,
                              const int G, __global int* restrict start,
                              __global int* restrict end)
{
    const int r = get_global_id(0);
    if (r >= nruns) return;
    const int first = list[offsets[r]];
    const int count = (r + 1 < nruns ? offsets[r + 1] : n) - offsets[r];
    const int row_end = first - first % sx + G + nx;
    int last = min(first + (count + pad - 1) / pad * pad, row_end);
    if (r + 1 < nruns) last = min(last, list[offsets[r + 1]]);
    start[r] = first;
    end[r] = max(last, first + count);
}

// (RUN_ARGS and FOR_EACH_RUN_CELL, the loops over these runs, are in common.cl.)

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
#define NODES 2
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

// The interpolation stencil of each closest point, computed once (psi is fixed): the flat
// padded index of its first node (x0, y0, z0) in base[k] and its position relative to
// floor(p) in frac[k], frac[nlist + k], frac[2 nlist + k]. The same nodes and weights as
// interpolate() above; the re-extension then needs no floor, clamp or index arithmetic.
__kernel void cp_stencils(__global const REAL* restrict cpx, __global const REAL* restrict cpy,
                          __global const REAL* restrict cpz, const int sx, const int sxy,
                          const int pnx, const int pny, const int pnz,
                          __global int* restrict base, __global REAL* restrict frac, LIST_ARGS)
{
    LIST_RANGE(k0, k1, chan);
    for (int k = k0; k < k1; ++k) {
        REAL wx[NODES], wy[NODES], wz[NODES];
        const int x0 = axis_weights(cpx[k], pnx, wx);
        const int y0 = axis_weights(cpy[k], pny, wy);
        const int z0 = axis_weights(cpz[k], pnz, wz);
        base[k] = z0 * sxy + y0 * sx + x0;
        frac[k] = cpx[k] - floor(cpx[k]);
        frac[nlist + k] = cpy[k] - floor(cpy[k]);
        frac[2 * nlist + k] = cpz[k] - floor(cpz[k]);
    }
}

#ifdef REAL_IS_DOUBLE
#define REAL2 double2
#define REAL4 double4
#else
#define REAL2 float2
#define REAL4 float4
#endif
// Four consecutive REALs read as one vector at any REAL-aligned address (PoCL's vload4 is an
// out-of-line call; this is a plain unaligned vector load).
typedef REAL4 __attribute__((aligned(sizeof(REAL)))) unaligned_real4;
#define LOAD4(p) (*(__global const unaligned_real4*)(p))

// The cells a step must update: the interpolation nodes of the band's closest points
// (base from cp_stencils). Every other band cell's new value comes from re-extension alone.
// Concurrent work-items may mark the same node: they all write 1.
__kernel void mark_nodes(__global const int* restrict base, __global uchar* restrict mask,
                         const int sx, const int sxy, LIST_ARGS)
{
    LIST_RANGE(k0, k1, chan);
    for (int k = k0; k < k1; ++k)
        for (int a = 0; a < NODES; ++a)
            for (int b = 0; b < NODES; ++b)
                for (int e = 0; e < NODES; ++e) mask[base[k] + a * sxy + b * sx + e] = 1;
}

// The cells the steps read around the listed ones: the cell, its 6 face and 12 edge
// neighbours (appendix E's one-sided stencils, over all eight side choices). These need
// fresh re-extended values after every step.
__kernel void mark_stencil(__global uchar* restrict mask, const int sx, const int sxy,
                           LIST_ARGS)
{
    LIST_RANGE(k0, k1, chan);
    for (int k = k0; k < k1; ++k) {
        const int i = list[k];
        for (int dz = -1; dz <= 1; ++dz)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx)
                    if (abs(dx) + abs(dy) + abs(dz) <= 2) mask[i + dz * sxy + dy * sx + dx] = 1;
    }
}

// Weights of the nodes along one axis from the position t in [0, 1) relative to floor(p):
// axis_weights' polynomials, the four cubic ones expanded in powers of t and computed at once.
#if INTERP == 3
#define NODE_WEIGHTS REAL4
INLINE REAL4 node_weights(const REAL t)
{
    const REAL4 c3 = (REAL4)(-1, 3, -3, 1) / 6;
    const REAL4 c2 = (REAL4)(3, -6, 3, 0) / 6;
    const REAL4 c1 = (REAL4)(-2, -3, 6, -1) / 6;
    const REAL4 c0 = (REAL4)(0, 1, 0, 0);
    return ((c3 * t + c2) * t + c1) * t + c0;
}
#else
#define NODE_WEIGHTS REAL2
INLINE REAL2 node_weights(const REAL t) { return (REAL2)(1 - t, t); }
#endif

// LINE_FIELD: u is a line field (u and -u mean the same line, e.g. principal directions):
// every vector a step or the re-extension reads is first turned to the side of a reference
// vector u(ref) (the updated cell's own; floor(cp)'s node), so sign flips between neighbours
// are not mistaken for jumps.
#ifndef LINE_FIELD
#define LINE_FIELD 0
#endif

// +1 or -1: the sign that turns the NC-vector at p to the side of the one at ref.
INLINE REAL line_sign(__global const REAL* restrict u, const int ref, const int p,
                      const int plane)
{
    REAL dot = 0;
    #pragma unroll
    for (int c = 0; c < NC; ++c) dot += u[c * plane + ref] * u[c * plane + p];
    return dot < 0 ? (REAL)-1 : (REAL)1;
}

// Whole-band closest-point re-extension: dst(x) = src(cp(x)) for every band cell, all NC
// channels, from the stencils of cp_stencils. With NORMALIZE the NC-vector is rescaled to
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

INLINE vec3r psi_normal(__global const REAL* restrict psi, const int j, const int sx,
                        const int sxy)
{
    vec3r n;
    n.x = (REAL)0.5 * (psi[j + 1] - psi[j - 1]);
    n.y = (REAL)0.5 * (psi[j + sx] - psi[j - sx]);
    n.z = (REAL)0.5 * (psi[j + sxy] - psi[j - sxy]);
    return n;
}

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

// ---- the other band flows, one work-item per cell handling all NC channels ----------------
//
// Flux at cell j for channel c: w_c = |N| G P_N v_c (|N| only when WEIGHTED), with
//   G = 1                               FLOW_P 2: heat (4.7/4.8), harmonic map p = 2 (D.7)
//   G = (|P v|^2 + e2)^(-1/2)           FLOW_P 1: TV (4.10), harmonic map p = 1 (4.11)
// where |P v|^2 sums over the channels (the vectorial gradient of appendix D); with ALONG the
// flux is |N| (d . P_N v_c) d for a tangent field d (3 channels of `dir`): eqs. (4.14), (4.15).
// The step is v_c = u_c + r (div w_c / |N| + HARMONIC u_c |P v|^p) - dt lambda (u_c - u0_c)
// (FIDELITY, C.1), with r = dt / h^p (dt / h^2 with ALONG), e2 = (h eps)^2. lambda is a
// one-value device buffer, so the dynamic lambda (tv_lambda_update) never visits the host.
#ifndef FLOW_P
#define FLOW_P 2
#endif
#ifndef HARMONIC
#define HARMONIC 0
#endif
#ifndef FIDELITY
#define FIDELITY 0
#endif
#ifndef ALONG
#define ALONG 0
#endif

// The channel loops are unrolled (#pragma unroll, NC is a constant) so the loop over a run's
// cells is the innermost one, which PoCL's vectoriser widens.
INLINE REAL flow_flux(__global const REAL* restrict u, __global const REAL* restrict psi,
                      __global const REAL* restrict dir, const int j, const int ex,
                      const int ey, const int ez, const int sx, const int sxy, const int plane,
                      const REAL e2, const int ref, REAL w[NC][3])
{
#if LINE_FIELD
    const REAL s0 = line_sign(u, ref, j, plane), s1 = line_sign(u, ref, j + ex, plane);
    const REAL s2 = line_sign(u, ref, j + ey, plane), s3 = line_sign(u, ref, j + ez, plane);
#else
    const REAL s0 = 1, s1 = 1, s2 = 1, s3 = 1;
#endif
    const vec3r n = psi_normal(psi, j, sx, sxy);
    const REAL nn = n.x * n.x + n.y * n.y + n.z * n.z + (REAL)1e-30;
#if WEIGHTED
    const REAL len = SQRT(nn);
#else
    const REAL len = 1;
#endif
    REAL g2 = 0;
    #pragma unroll
    for (int c = 0; c < NC; ++c) {
        const int jc = c * plane + j;
        const REAL uj = s0 * u[jc];
        const REAL vx = ONE_SIDED_SIGN(ex) * (s1 * u[jc + ex] - uj);
        const REAL vy = ONE_SIDED_SIGN(ey) * (s2 * u[jc + ey] - uj);
        const REAL vz = ONE_SIDED_SIGN(ez) * (s3 * u[jc + ez] - uj);
        const REAL s = (n.x * vx + n.y * vy + n.z * vz) / nn;
        w[c][0] = vx - s * n.x;
        w[c][1] = vy - s * n.y;
        w[c][2] = vz - s * n.z;
        g2 += w[c][0] * w[c][0] + w[c][1] * w[c][1] + w[c][2] * w[c][2];
    }
#if ALONG
    const REAL dx = dir[j], dy = dir[plane + j], dz = dir[2 * plane + j];
    #pragma unroll
    for (int c = 0; c < NC; ++c) {
        const REAL a = len * (dx * w[c][0] + dy * w[c][1] + dz * w[c][2]);
        w[c][0] = a * dx;
        w[c][1] = a * dy;
        w[c][2] = a * dz;
    }
#else
#if FLOW_P == 1
    const REAL gain = len * RSQRT(g2 + e2);
#else
    const REAL gain = len;
#endif
    #pragma unroll
    for (int c = 0; c < NC; ++c) {
        w[c][0] *= gain;
        w[c][1] *= gain;
        w[c][2] *= gain;
    }
#endif
    return g2;
}

__kernel void flow_step(__global const REAL* restrict u, __global REAL* restrict v,
                        __global const REAL* restrict psi, __global const REAL* restrict dir,
                        __global const REAL* restrict u0, const REAL r, const REAL dt,
                        __global const REAL* restrict lambda, const REAL e2, const int ex, const int ey,
                        const int ez, const int sx, const int sxy, RUN_ARGS)
{
    FOR_EACH_RUN_CELL(i) {
        REAL wc[NC][3], wx[NC][3], wy[NC][3], wz[NC][3];
        const REAL g2 = flow_flux(u, psi, dir, i, ex, ey, ez, sx, sxy, plane, e2, i, wc);
        flow_flux(u, psi, dir, i - ex, ex, ey, ez, sx, sxy, plane, e2, i, wx);
        flow_flux(u, psi, dir, i - ey, ex, ey, ez, sx, sxy, plane, e2, i, wy);
        flow_flux(u, psi, dir, i - ez, ex, ey, ez, sx, sxy, plane, e2, i, wz);
#if WEIGHTED
        const vec3r n = psi_normal(psi, i, sx, sxy);
        const REAL inv_len = RSQRT(n.x * n.x + n.y * n.y + n.z * n.z + (REAL)1e-30);
#else
        const REAL inv_len = 1;
#endif
        #pragma unroll
        for (int c = 0; c < NC; ++c) {
            const int ic = c * plane + i;
            const REAL div = ONE_SIDED_SIGN(ex) * (wc[c][0] - wx[c][0]) +
                             ONE_SIDED_SIGN(ey) * (wc[c][1] - wy[c][1]) +
                             ONE_SIDED_SIGN(ez) * (wc[c][2] - wz[c][2]);
            REAL rate = div * inv_len;
#if HARMONIC && FLOW_P == 2
            rate += u[ic] * g2;
#elif HARMONIC
            rate += u[ic] * SQRT(g2);
#endif
            REAL val = u[ic] + r * rate;
#if FIDELITY
            val -= dt * lambda[0] * (u[ic] - u0[ic]);
#endif
            v[ic] = val;
        }
    }
}

// Per-cell terms of the surface integrals that set TV's dynamic lambda (C.2) and measure the
// residual: with a smeared delta of half-width eps_cells (grid units),
//   num  = delta (v - v0) . P v / |P v|_e,  area = delta,  resid = delta (u - u0)^2.
__kernel void tv_lambda_terms(__global const REAL* restrict u, __global const REAL* restrict u0,
                              __global const REAL* restrict psi, const REAL inv_h,
                              const REAL eps_cells, const REAL e2, const int ex, const int ey,
                              const int ez, const int sx, const int sxy,
                              __global REAL* restrict num, __global REAL* restrict area,
                              __global REAL* restrict resid, LIST_ARGS)
{
    LIST_RANGE(k0, k1, chan);
    for (int k = k0; k < k1; ++k) {
        const int i = list[k];
        const REAL d = psi[i] * inv_h;
        const REAL delta = FABS(d) < eps_cells
            ? (1 + cos((REAL)M_PI * d / eps_cells)) / (2 * eps_cells) : (REAL)0;
        const vec3r n = psi_normal(psi, i, sx, sxy);
        const REAL nn = n.x * n.x + n.y * n.y + n.z * n.z + (REAL)1e-30;
        const REAL vx = ONE_SIDED_SIGN(ex) * (u[i + ex] - u[i]);
        const REAL vy = ONE_SIDED_SIGN(ey) * (u[i + ey] - u[i]);
        const REAL vz = ONE_SIDED_SIGN(ez) * (u[i + ez] - u[i]);
        const REAL s = (n.x * vx + n.y * vy + n.z * vz) / nn;
        const REAL px = vx - s * n.x, py = vy - s * n.y, pz = vz - s * n.z;
        const REAL ax = vx - ONE_SIDED_SIGN(ex) * (u0[i + ex] - u0[i]);
        const REAL ay = vy - ONE_SIDED_SIGN(ey) * (u0[i + ey] - u0[i]);
        const REAL az = vz - ONE_SIDED_SIGN(ez) * (u0[i + ez] - u0[i]);
        num[k] = delta * (ax * px + ay * py + az * pz) * RSQRT(px * px + py * py + pz * pz + e2);
        area[k] = delta;
        resid[k] = delta * SQR(u[i] - u0[i]);
    }
}

// Partial sums of a band-length array: work-item g adds entries [g*chunk, (g+1)*chunk).
// The host adds the few partials (band / chunk numbers).
__kernel void chunk_sum(__global const REAL* restrict a, const int n, const int chunk,
                        __global REAL* restrict partial)
{
    const int g = get_global_id(0);
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
// scale the plain formula settled at 1.2-1.6 sigma^2. Once the residual has passed half of
// sigma^2, each update multiplies f by residual / sigma^2, limited to [0.67, 1.5] per
// update and f to [0.1, 10]: f stops moving only where the residual is sigma^2 (on a
// sphere within 1-4% after t = 0.08, 40 updates). inv_sigma2 = 0 keeps f = 1: plain (C.2).
// One work-item: the partial sums are a few hundred numbers.
__kernel void tv_lambda_update(__global const REAL* restrict num, __global const REAL* restrict area,
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
            const REAL dx = ax > 0 ? u[ic] - u[ic - 1] : u[ic + 1] - u[ic];
            const REAL dy = ay > 0 ? u[ic] - u[ic - sx] : u[ic + sx] - u[ic];
            const REAL dz = az > 0 ? u[ic] - u[ic - sxy] : u[ic + sxy] - u[ic];
            v[ic] = u[ic] - r * (ax * dx + ay * dy + az * dz);
        }
    }
}

// ---- reinitialisation of psi to a signed distance ------------------------------------------
// phi_t + sgn(phi0) (|grad phi| - 1) = 0 with Godunov's upwind norm (Sussman, Smereka, Osher),
// and Russo and Smereka's subcell fix on cells next to the surface: there the update pulls
// phi towards D = phi0 / |grad phi0| (a distance estimate from phi0 itself), so the zero
// level set does not move. World units; r = dt / h.
INLINE REAL godunov_sq(const REAL back, const REAL fwd, const REAL s)
{
    return s > 0 ? FMAX(SQR(FMAX(back, (REAL)0)), SQR(FMIN(fwd, (REAL)0)))
                 : FMAX(SQR(FMIN(back, (REAL)0)), SQR(FMAX(fwd, (REAL)0)));
}

INLINE REAL subcell_slope(__global const REAL* restrict p, const int i, const int s)
{
    return FMAX(FMAX(FABS(p[i + s] - p[i - s]) * (REAL)0.5, FABS(p[i + s] - p[i])),
                FMAX(FABS(p[i] - p[i - s]), (REAL)1e-12));
}

__kernel void reinit_step(__global const REAL* restrict phi, __global REAL* restrict out,
                          __global const REAL* restrict phi0, const REAL r, const REAL inv_h,
                          const int sx, const int sxy, LIST_ARGS)
{
    LIST_RANGE(k0, k1, chan);
    for (int k = k0; k < k1; ++k) {
        const int i = list[k];
        const REAL p0 = phi0[i];
        const REAL s = p0 > 0 ? (REAL)1 : (p0 < 0 ? (REAL)-1 : (REAL)0);
        const bool near = p0 * phi0[i + 1] <= 0 || p0 * phi0[i - 1] <= 0 ||
                          p0 * phi0[i + sx] <= 0 || p0 * phi0[i - sx] <= 0 ||
                          p0 * phi0[i + sxy] <= 0 || p0 * phi0[i - sxy] <= 0;
        const REAL c = phi[i];
        if (near) {
            const REAL g = SQRT(SQR(subcell_slope(phi0, i, 1)) + SQR(subcell_slope(phi0, i, sx)) +
                                SQR(subcell_slope(phi0, i, sxy))) * inv_h;
            out[i] = c - r * (s * FABS(c) - p0 / g);
        } else {
            const REAL gx = godunov_sq(c - phi[i - 1], phi[i + 1] - c, s);
            const REAL gy = godunov_sq(c - phi[i - sx], phi[i + sx] - c, s);
            const REAL gz = godunov_sq(c - phi[i - sxy], phi[i + sxy] - c, s);
            out[i] = c - r * s * (SQRT(gx + gy + gz) * inv_h - 1) / inv_h;
        }
    }
}

// ---- principal curvature directions ---------------------------------------------------------
// Hessian of psi by central differences, restricted to the tangent plane spanned by an
// orthonormal pair (t1, t2) orthogonal to N; the 2x2 form's eigenvectors are the principal
// directions and its eigenvalues the principal curvatures (1/R for a sphere of radius R, psi
// negative inside). For a distance function the directions are constant along the normals,
// so every band cell gets its own values, no interpolation. Outputs per band entry k: the major direction (larger curvature) in
// dir[0..2][k], the minor in dir[3..5][k] and the curvatures in curv[0..1][k] (world units).
__kernel void principal_directions(__global const REAL* restrict psi, const REAL inv_h,
                                   __global REAL* restrict dir, __global REAL* restrict curv,
                                   const int sx, const int sxy, LIST_ARGS)
{
    LIST_RANGE(k0, k1, chan);
    for (int k = k0; k < k1; ++k) {
        const int i = list[k];
        const vec3r g = psi_normal(psi, i, sx, sxy);
        const REAL inv = RSQRT(g.x * g.x + g.y * g.y + g.z * g.z + (REAL)1e-30);
        const REAL nx = g.x * inv, ny = g.y * inv, nz = g.z * inv;
        const REAL c = psi[i];
        const REAL hxx = psi[i + 1] - 2 * c + psi[i - 1];
        const REAL hyy = psi[i + sx] - 2 * c + psi[i - sx];
        const REAL hzz = psi[i + sxy] - 2 * c + psi[i - sxy];
        const REAL hxy = (REAL)0.25 * (psi[i + 1 + sx] - psi[i - 1 + sx] - psi[i + 1 - sx] + psi[i - 1 - sx]);
        const REAL hxz = (REAL)0.25 * (psi[i + 1 + sxy] - psi[i - 1 + sxy] - psi[i + 1 - sxy] + psi[i - 1 - sxy]);
        const REAL hyz = (REAL)0.25 * (psi[i + sx + sxy] - psi[i - sx + sxy] - psi[i + sx - sxy] + psi[i - sx - sxy]);
        // t1 = N x e, e the axis least aligned with N; t2 = N x t1
        REAL ex = 0, ey = 0, ez = 0;
        if (FABS(nx) <= FABS(ny) && FABS(nx) <= FABS(nz)) ex = 1;
        else if (FABS(ny) <= FABS(nz)) ey = 1;
        else ez = 1;
        REAL ax = ny * ez - nz * ey, ay = nz * ex - nx * ez, az = nx * ey - ny * ex;
        const REAL ia = RSQRT(ax * ax + ay * ay + az * az);
        ax *= ia; ay *= ia; az *= ia;
        const REAL bx = ny * az - nz * ay, by = nz * ax - nx * az, bz = nx * ay - ny * ax;
        // H t for t = a and t = b
        const REAL hax = hxx * ax + hxy * ay + hxz * az, hay = hxy * ax + hyy * ay + hyz * az,
                   haz = hxz * ax + hyz * ay + hzz * az;
        const REAL hbx = hxx * bx + hxy * by + hxz * bz, hby = hxy * bx + hyy * by + hyz * bz,
                   hbz = hxz * bx + hyz * by + hzz * bz;
        const REAL p = ax * hax + ay * hay + az * haz;
        const REAL q = ax * hbx + ay * hby + az * hbz;
        const REAL r = bx * hbx + by * hby + bz * hbz;
        const REAL mean = (REAL)0.5 * (p + r);
        const REAL dev = SQRT(SQR((REAL)0.5 * (p - r)) + q * q);
        const REAL theta = (REAL)0.5 * atan2(2 * q, p - r);
        const REAL ct = cos(theta), st = sin(theta);
        dir[k] = ct * ax + st * bx;
        dir[nlist + k] = ct * ay + st * by;
        dir[2 * nlist + k] = ct * az + st * bz;
        dir[3 * nlist + k] = -st * ax + ct * bx;
        dir[4 * nlist + k] = -st * ay + ct * by;
        dir[5 * nlist + k] = -st * az + ct * bz;
        // curvature = tangential Hessian / |grad psi| in world units: second differences
        // are h^2 psi'' and |grad psi| = 1 / (inv h), so the factor is inv / h
        const REAL scale = inv * inv_h;
        // a distance function's level set at distance d = psi has curvatures k / (1 + d k):
        // undo that so every band cell carries the surface's own curvatures
        const REAL k1 = (mean + dev) * scale, k2 = (mean - dev) * scale;
        curv[k] = k1 / (1 - c * k1);
        curv[nlist + k] = k2 / (1 - c * k2);
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

// ---- the band's own roofline -----------------------------------------------------------------
// v = u + psi over band runs: the bytes a heat step must move (read u and psi, write v) with
// its access pattern and no arithmetic. benchmarks/surface_accuracy.py times it beside the
// steps: what the band's short runs allow, as against a plain copy of one long array.
__kernel void band_copy(__global const REAL* restrict u, __global REAL* restrict v,
                        __global const REAL* restrict psi, RUN_ARGS)
{
    FOR_EACH_RUN_CELL(i) { v[chan + i] = u[chan + i] + psi[i]; }
}

// ---- mesh -> distance: exact point-triangle distances refined over neighbouring cells ------

// Closest point to p on triangle (a, b, c), by the Voronoi regions of its vertices, edges and
// face (as in Ericson's Real-Time Collision Detection, section 5.1.5).
INLINE vec3r v3(const REAL x, const REAL y, const REAL z) { vec3r r; r.x = x; r.y = y; r.z = z; return r; }
INLINE vec3r v3sub(const vec3r a, const vec3r b) { return v3(a.x - b.x, a.y - b.y, a.z - b.z); }
INLINE REAL v3dot(const vec3r a, const vec3r b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
INLINE vec3r v3mad(const vec3r a, const REAL s, const vec3r d) { return v3(a.x + s * d.x, a.y + s * d.y, a.z + s * d.z); }

INLINE vec3r closest_on_triangle(const vec3r p, const vec3r a, const vec3r b, const vec3r c)
{
    const vec3r ab = v3sub(b, a), ac = v3sub(c, a), ap = v3sub(p, a);
    const REAL d1 = v3dot(ab, ap), d2 = v3dot(ac, ap);
    if (d1 <= 0 && d2 <= 0) return a;
    const vec3r bp = v3sub(p, b);
    const REAL d3 = v3dot(ab, bp), d4 = v3dot(ac, bp);
    if (d3 >= 0 && d4 <= d3) return b;
    const REAL vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) return v3mad(a, d1 / (d1 - d3), ab);
    const vec3r cp = v3sub(p, c);
    const REAL d5 = v3dot(ab, cp), d6 = v3dot(ac, cp);
    if (d6 >= 0 && d5 <= d6) return c;
    const REAL vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) return v3mad(a, d2 / (d2 - d6), ac);
    const REAL va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
        return v3mad(b, (d4 - d3) / ((d4 - d3) + (d5 - d6)), v3sub(c, b));
    const REAL denom = 1 / (va + vb + vc);
    return v3mad(v3mad(a, vb * denom, ab), vc * denom, ac);
}

// For each listed cell (flat index into an unpadded nz x ny x nx volume), try the current
// nearest triangle of each of its 27 neighbours (face_in, -1 for none) and keep the closest:
// then walk up to WALK steps across edge-adjacent triangles (nbr: 3 per face, -1 for none)
// while that gets closer. A few passes make every band cell's triangle the nearest one.
// tri: 9 coordinates per face relative to the grid origin, in cells.
#ifndef WALK
#define WALK 8
#endif
__kernel void mesh_refine(__global const int* restrict cells, const int ncells,
                          __global const int* restrict face_in, __global int* restrict face_out,
                          __global REAL* restrict dist, __global REAL* restrict cpt,
                          __global const REAL* restrict tri, __global const int* restrict nbr,
                          const int nx, const int ny, const int nz)
{
    const int k = get_global_id(0);
    if (k >= ncells) return;
    const int i = cells[k];
    const int z = i / (nx * ny), y = (i / nx) % ny, x = i % nx;
    const vec3r p = v3(x, y, z);
    REAL best = INFINITY;
    int best_face = face_in[i];
    vec3r best_cp = p;
    for (int dz = -1; dz <= 1; ++dz)
    for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx) {
        const int xx = clamp(x + dx, 0, nx - 1), yy = clamp(y + dy, 0, ny - 1), zz = clamp(z + dz, 0, nz - 1);
        const int f = face_in[(zz * ny + yy) * nx + xx];
        if (f < 0) continue;
        __global const REAL* t = tri + 9 * f;
        const vec3r q = closest_on_triangle(p, v3(t[0], t[1], t[2]), v3(t[3], t[4], t[5]),
                                            v3(t[6], t[7], t[8]));
        const vec3r d = v3sub(p, q);
        const REAL dd = v3dot(d, d);
        if (dd < best) { best = dd; best_face = f; best_cp = q; }
    }
    // walk across the edges of the mesh from the best triangle while that gets closer
    for (int step = 0; step < WALK && best_face >= 0; ++step) {
        const int from = best_face;
        for (int e = 0; e < 3; ++e) {
            const int f = nbr[3 * from + e];
            if (f < 0) continue;
            __global const REAL* t = tri + 9 * f;
            const vec3r q = closest_on_triangle(p, v3(t[0], t[1], t[2]), v3(t[3], t[4], t[5]),
                                                v3(t[6], t[7], t[8]));
            const vec3r d = v3sub(p, q);
            const REAL dd = v3dot(d, d);
            if (dd < best) { best = dd; best_face = f; best_cp = q; }
        }
        if (best_face == from) break;
    }
    face_out[i] = best_face;
    dist[k] = SQRT(best);
    cpt[3 * k] = best_cp.x;
    cpt[3 * k + 1] = best_cp.y;
    cpt[3 * k + 2] = best_cp.z;
}
