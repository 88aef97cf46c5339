// Generalized winding number of a triangle mesh (Jacobson, Kavan, Sorkine-Hornung 2013):
// w(p) = sum over triangles of the signed solid angle the triangle subtends at p, / 4 pi.
// About 1 inside a closed, outward-oriented mesh, 0 outside, and smoothly near 1/2 across a
// hole, so |w| > 1/2 decides the side of a mesh with holes.
//
// The solid angle of triangle (a, b, c), vertices relative to p, is 2 atan2(N, D) with
// N = a.(b x c) and D = |a||b||c| + (a.b)|c| + (b.c)|a| + (c.a)|b| (Van Oosterom and
// Strackee 1983).
//
// Two-level far field (after Barill et al. 2018, "Fast winding numbers for soups and
// clouds"): the host sorts the triangles along a Morton curve into clusters of consecutive
// triangles; each cluster keeps its centre c, its area vector A = sum a_t n_t and the
// first moment M_ij = sum a_t n_t,i (x_t - c)_j (x_t: triangle centroid). Seen from a point
// far from the cluster (relative to its radius) its solid angle is the Taylor expansion of
// the integral of n.(y - p)/|y - p|^3 about y = c: with r = c - p,
//     A.r / |r|^3 + tr(M) / |r|^3 - 3 r.M r / |r|^5,
// whose error falls as (radius / |r|)^2 relative to the first term. The host decides near
// or far per tile of points (a box of them), so every point of a work-item loops over the
// same clusters and the innermost loop runs over points: it vectorises on CPUs.
//
// Coordinates are in grid cells relative to the grid origin, as mesh_refine's triangles.
#include "common.h"

// points per work-item (a chunk of one tile)
#ifndef CHUNK
#define CHUNK 64
#endif

#define PI_R ((REAL)3.14159265358979323846)

// atan2 without PoCL's out-of-line call: reduce to t = min/max in [0, 1], then to
// |t| <= tan(pi/8) through atan(t) = pi/4 + atan((t - 1)/(t + 1)); there atan(t)/t is a
// degree-4 polynomial in t^2 (least-squares fit on Chebyshev nodes, error 7e-9 rad, below
// float rounding). Selects only, so loops calling it vectorise.
INLINE REAL wn_atan2(const REAL y, const REAL x)
{
    const REAL ax = FABS(x), ay = FABS(y);
    const REAL hi = ax > ay ? ax : ay, lo = ax > ay ? ay : ax;
    const REAL t = lo / (hi > (REAL)0 ? hi : (REAL)1);
    const int upper = t > (REAL)0.41421356237309505;
    const REAL u = upper ? (t - (REAL)1) / (t + (REAL)1) : t;
    const REAL s = u * u;
    const REAL poly = (REAL)9.999999819e-01 + s * ((REAL)-3.333279694e-01 + s * ((REAL)1.997440479e-01 +
                      s * ((REAL)-1.385147843e-01 + s * (REAL)7.984962912e-02)));
    REAL r = u * poly + (upper ? PI_R / 4 : (REAL)0);
    r = ay > ax ? PI_R / 2 - r : r;
    r = x < 0 ? PI_R - r : r;
    return y < 0 ? -r : r;
}

// Solid angle of triangle (a, b, c) seen from the origin.
INLINE REAL solid_angle(const REAL ax, const REAL ay, const REAL az, const REAL bx, const REAL by,
                        const REAL bz, const REAL cx, const REAL cy, const REAL cz)
{
    const REAL la = SQRT(ax * ax + ay * ay + az * az);
    const REAL lb = SQRT(bx * bx + by * by + bz * bz);
    const REAL lc = SQRT(cx * cx + cy * cy + cz * cz);
    const REAL det = ax * (by * cz - bz * cy) + ay * (bz * cx - bx * cz) + az * (bx * cy - by * cx);
    const REAL ab = ax * bx + ay * by + az * bz;
    const REAL bc = bx * cx + by * cy + bz * cz;
    const REAL ca = cx * ax + cy * ay + cz * az;
    const REAL den = la * lb * lc + ab * lc + bc * la + ca * lb;
    return (REAL)2 * wn_atan2(det, den);
}

// w at points pts (3 * npts, x y z interleaved), written to w[k]. Work-item g takes points
// [chunk_start[g], chunk_end[g]) (at most CHUNK, all of tile chunk_tile[g]). Tile t sums the
// clusters near_list[near_off[t] .. near_off[t + 1]) exactly, triangle by triangle, and the
// clusters far_list[far_off[t] .. far_off[t + 1]) through their expansions. Cluster k owns
// triangles [cl_start[k], cl_start[k + 1]) of tri (9 numbers a triangle) and has 15
// numbers in clu: c (3), A (3), M (9, row-major).
__kernel void winding_number(__global const REAL* restrict pts,
                             __global const int* restrict chunk_start,
                             __global const int* restrict chunk_end,
                             __global const int* restrict chunk_tile, const int nchunks,
                             __global const int* restrict near_off,
                             __global const int* restrict near_list,
                             __global const int* restrict far_off,
                             __global const int* restrict far_list,
                             __global const int* restrict cl_start,
                             __global const REAL* restrict clu,
                             __global const REAL* restrict tri, __global REAL* restrict w)
{
    const int g = get_global_id(0);
    if (g >= nchunks) return;
    const int k0 = chunk_start[g];
    const int n = min(chunk_end[g] - k0, CHUNK);
    const int tile = chunk_tile[g];
    REAL px[CHUNK], py[CHUNK], pz[CHUNK], acc[CHUNK];
    for (int k = 0; k < n; ++k) {
        px[k] = pts[3 * (k0 + k)];
        py[k] = pts[3 * (k0 + k) + 1];
        pz[k] = pts[3 * (k0 + k) + 2];
        acc[k] = 0;
    }
    for (int e = near_off[tile]; e < near_off[tile + 1]; ++e) {
        const int cl = near_list[e];
        for (int f = cl_start[cl]; f < cl_start[cl + 1]; ++f) {
            __global const REAL* t = tri + 9 * f;
            const REAL x0 = t[0], y0 = t[1], z0 = t[2], x1 = t[3], y1 = t[4], z1 = t[5];
            const REAL x2 = t[6], y2 = t[7], z2 = t[8];
            for (int k = 0; k < n; ++k)
                acc[k] += solid_angle(x0 - px[k], y0 - py[k], z0 - pz[k], x1 - px[k], y1 - py[k],
                                      z1 - pz[k], x2 - px[k], y2 - py[k], z2 - pz[k]);
        }
    }
    for (int e = far_off[tile]; e < far_off[tile + 1]; ++e) {
        __global const REAL* c = clu + 15 * far_list[e];
        const REAL cx = c[0], cy = c[1], cz = c[2], ax = c[3], ay = c[4], az = c[5];
        const REAL m00 = c[6], m01 = c[7], m02 = c[8], m10 = c[9], m11 = c[10], m12 = c[11];
        const REAL m20 = c[12], m21 = c[13], m22 = c[14];
        const REAL trace = m00 + m11 + m22;
        for (int k = 0; k < n; ++k) {
            const REAL rx = cx - px[k], ry = cy - py[k], rz = cz - pz[k];
            const REAL inv = RSQRT(rx * rx + ry * ry + rz * rz);
            const REAL inv2 = inv * inv, inv3 = inv2 * inv;
            const REAL rmr = rx * (m00 * rx + m01 * ry + m02 * rz) + ry * (m10 * rx + m11 * ry + m12 * rz) +
                             rz * (m20 * rx + m21 * ry + m22 * rz);
            acc[k] += inv3 * (ax * rx + ay * ry + az * rz + trace - (REAL)3 * rmr * inv2);
        }
    }
    for (int k = 0; k < n; ++k) w[k0 + k] = acc[k] * ((REAL)0.25 / PI_R);
}
