// The narrow band's construction, once per psi (clpde/surface/band.py; the band's mask and
// runs are common/grid3d.cl's): the closest points of its cells and the interpolation
// stencils of those points, the interpolation nodes and the cells a step reads around
// them. No defines: the interpolation order is an argument (these run once per psi), so one
// program serves every surface. Layout and conventions: surface.h.
#include "common.h"
#include "surface/surface.h"

// Closest points x - psi grad(psi) / |grad(psi)| of the band cells, in padded index units
// (grad by central differences; psi in grid units = world units / spacing).
__kernel void band_closest_points(__global const REAL* restrict psi, const REAL inv_h,
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

// The first interpolation node along one axis for position p (index units): floor(p) - 1 of
// 4 nodes (interp 3, tricubic) or floor(p) of 2 (trilinear), clamped into [0, n - nodes] so
// a read never leaves the volume (surface/extend.cl's axis_weights).
INLINE int first_node(const REAL p, const int n, const int interp)
{
    return interp == 3 ? clamp((int)floor(p) - 1, 0, n - 4) : clamp((int)floor(p), 0, n - 2);
}

// The interpolation stencil of each closest point, computed once (psi is fixed): the flat
// padded index of its first node (x0, y0, z0) in base[k] and its position relative to
// floor(p) in frac[k], frac[nlist + k], frac[2 nlist + k]. The same nodes and weights as
// surface/extend.cl's interpolate(); the re-extension then needs no floor, clamp or index
// arithmetic.
__kernel void band_cp_stencils(__global const REAL* restrict cpx, __global const REAL* restrict cpy,
                          __global const REAL* restrict cpz, const int sx, const int sxy,
                          const int pnx, const int pny, const int pnz, const int interp,
                          __global int* restrict base, __global REAL* restrict frac, LIST_ARGS)
{
    LIST_RANGE(k0, k1, chan);
    for (int k = k0; k < k1; ++k) {
        const int x0 = first_node(cpx[k], pnx, interp);
        const int y0 = first_node(cpy[k], pny, interp);
        const int z0 = first_node(cpz[k], pnz, interp);
        base[k] = z0 * sxy + y0 * sx + x0;
        frac[k] = cpx[k] - floor(cpx[k]);
        frac[nlist + k] = cpy[k] - floor(cpy[k]);
        frac[2 * nlist + k] = cpz[k] - floor(cpz[k]);
    }
}

// The cells a step must update: the interpolation nodes of the band's closest points
// (base from cp_stencils; `nodes` per axis, 4 or 2). Every other band cell's new value comes
// from re-extension alone. Concurrent work-items may mark the same node: they all write 1.
__kernel void band_mark_nodes(__global const int* restrict base, __global uchar* restrict mask,
                         const int sx, const int sxy, const int nodes, LIST_ARGS)
{
    LIST_RANGE(k0, k1, chan);
    for (int k = k0; k < k1; ++k)
        for (int a = 0; a < nodes; ++a)
            for (int b = 0; b < nodes; ++b)
                for (int e = 0; e < nodes; ++e) mask[base[k] + a * sxy + b * sx + e] = 1;
}

// The cells the steps read around the listed ones: the cell, its 6 face and 12 edge
// neighbours (appendix E's one-sided stencils, over all eight side choices). These need
// fresh re-extended values after every step.
__kernel void band_mark_stencil(__global uchar* restrict mask, const int sx, const int sxy,
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
