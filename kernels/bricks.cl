// The narrow band in dense bricks (clpde/surface/bricks.py): kernels of the surface flows.
//
// A brick holds BX x BY x BZ cells (BV in all), x fastest; a quantity is one buffer
// (channels, nbricks + 2, BV), `plane` its channel stride: bricks 1..nbricks are stored,
// brick 0 is a sentinel of zeros for every brick place not stored, the last one slack. No halo is stored: a kernel copies its brick and the faces of its neighbours (the
// 27-entry table nbr) into a tile, then runs the stencils on the tile with plain strides.
//
// Launch geometry (GROUP_PER_BRICK): on CPUs (0) one work-item walks whole bricks, from a
// private tile; on GPUs (1) one work-group of BV work-items takes a brick, one cell each,
// from a tile in local memory. The arithmetic is the same (and is surface_heat.cl's): the
// results agree to rounding.
#include "common.cl"
#include "surface.h"
#include "bricks.h"

// The re-extension's source (the stepped values) has each brick lengthened along x, y and z
// by an apron of AX cells, copies of the next bricks' first ones, so a tricubic stencil
// whose first node lies in a brick lies in that brick and its apron (BXA cells a row, BXA
// BYA a slab, BVA a brick).
#define AX 3
#define BXA (BX + AX)
#define BYA (BY + AX)
#define BZA (BZ + AX)
#define BVA (BXA * BYA * BZA)
#ifndef WEIGHTED
#define WEIGHTED 0
#endif
#ifndef NORMALIZE
#define NORMALIZE 0
#endif

// band bits of a cell (bricks.py: NODE, REACH, EXT)
#define BIT_NODE 1

// ---- intrinsic heat flow (4.7) / (4.8), appendix E, on a tile ------------------------------
// surface_heat.cl's heat_flux / heat_div with tile strides: ex, ey, ez are the signed one-sided
// offsets in the tile (+-1, +-tx, +-txy).
INLINE void tile_flux(TILE const REAL* u, __global const REAL* p, const int j, const int q,
                      const int ex, const int ey, const int ez, const int usx, const int usxy,
                      const int sx, const int sxy, REAL* w)
{
    // j: the cell in the u tile (one-sided offsets ex, ey, ez), q: in the psi tile (strides
    // sx, sxy)
    const REAL c = u[j];
    const REAL vx = ONE_SIDED_SIGN(ex) * (u[j + ex] - c);
    const REAL vy = ONE_SIDED_SIGN(ey) * (u[j + ey] - c);
    const REAL vz = ONE_SIDED_SIGN(ez) * (u[j + ez] - c);
    const REAL nx = (REAL)0.5 * (p[q + 1] - p[q - 1]);
    const REAL ny = (REAL)0.5 * (p[q + sx] - p[q - sx]);
    const REAL nz = (REAL)0.5 * (p[q + sxy] - p[q - sxy]);
    const REAL nn = nx * nx + ny * ny + nz * nz + (REAL)1e-30;
    const REAL s = (nx * vx + ny * vy + nz * vz) / nn;
#if WEIGHTED
    const REAL len = SQRT(nn);
#else
    const REAL len = 1;
#endif
    w[0] = len * (vx - s * nx);
    w[1] = len * (vy - s * ny);
    w[2] = len * (vz - s * nz);
}

// The divergence at cell i of the u tile (halo 1), q of the psi tile (halo 2): the fluxes
// one cell back read psi two cells away along an axis, u only one (faces and edges).
INLINE REAL tile_heat_div(TILE const REAL* u, __global const REAL* p, const int i, const int q,
                          const int dx, const int dy, const int dz)
{
    const int ex = dx, ey = dy * TILE_X(1), ez = dz * TILE_XY(1);
    const int px = dx, py = dy * TILE_X(2), pz = dz * TILE_XY(2);
    const int usx = TILE_X(1), usxy = TILE_XY(1), sx = TILE_X(2), sxy = TILE_XY(2);
    REAL wc[3], wx[3], wy[3], wz[3];
    tile_flux(u, p, i, q, ex, ey, ez, usx, usxy, sx, sxy, wc);
    tile_flux(u, p, i - ex, q - px, ex, ey, ez, usx, usxy, sx, sxy, wx);
    tile_flux(u, p, i - ey, q - py, ex, ey, ez, usx, usxy, sx, sxy, wy);
    tile_flux(u, p, i - ez, q - pz, ex, ey, ez, usx, usxy, sx, sxy, wz);
    REAL div = ONE_SIDED_SIGN(ex) * (wc[0] - wx[0]) + ONE_SIDED_SIGN(ey) * (wc[1] - wy[1]) +
               ONE_SIDED_SIGN(ez) * (wc[2] - wz[2]);
#if WEIGHTED
    const REAL nx = (REAL)0.5 * (p[q + 1] - p[q - 1]);
    const REAL ny = (REAL)0.5 * (p[q + sx] - p[q - sx]);
    const REAL nz = (REAL)0.5 * (p[q + sxy] - p[q - sxy]);
    div *= RSQRT(nx * nx + ny * ny + nz * nz + (REAL)1e-30);
#endif
    return div;
}

// Copy the low (HX, HY, HZ) part of brick b of vc into the apron of the brick before it
// (before[HX + 2 HY + 4 HZ]); compile-time bounds, so the rows are vector copies.
#define APRON_COPY(HX, HY, HZ)                                                            \
    if (before[(HX) + 2 * (HY) + 4 * (HZ)]) {                                             \
        __global REAL* to = vc + before[(HX) + 2 * (HY) + 4 * (HZ)] * BVA +               \
                            ((HZ) * BZ * BYA + (HY) * BY) * BXA + (HX) * BX;               \
        __global const REAL* from = vc + b * BVA;                                         \
        for (int z = 0; z < ((HZ) ? AX : BZ); ++z)                                        \
            for (int y = 0; y < ((HY) ? AX : BY); ++y)                                    \
                for (int x = 0; x < ((HX) ? AX : BX); ++x)                                \
                    to[(z * BYA + y) * BXA + x] = from[(z * BYA + y) * BXA + x];          \
    }

// The fluxes of a brick, each computed once (CPU path). A cell's divergence takes the flux at
// the cell and at the cells one step back along each axis (i - ex, i - ey, i - ez), which
// are the fluxes of its neighbours: per brick the fluxes of the brick's cells and of the one
// layer of cells behind its low (sx, sy, sz > 0) or high faces, (BX + 1) (BY + 1) (BZ + 1)
// of them, instead of four per cell (tile_heat_div). The same tile_flux on the same cells,
// so the same values; flux rows no updated row reads are skipped.
#define FX (BX + 1)
#define FXY (FX * (BY + 1))
#define FLUX_CELLS (FXY * (BZ + 1))

// Whether row (y, z) of the brick holds a node (false outside the brick).
INLINE bool node_row(__global const uchar* restrict rows, const int b, const int y, const int z)
{
    return y >= 0 && y < BY && z >= 0 && z < BZ && rows[b * BY * BZ + z * BY + y];
}

// The fluxes of the cells (x, y, z), x in [lo, lo + BX] (lo = -1 for a forward gradient,
// sx > 0, else 0; the same along y and z), into f: three components, FLUX_CELLS apart.
INLINE void brick_fluxes(REAL* f, TILE const REAL* u, __global const REAL* p,
                         __global const uchar* restrict rows, const int b, const int dx,
                         const int dy, const int dz)
{
    const int ex = dx, ey = dy * TILE_X(1), ez = dz * TILE_XY(1);
    const int usx = TILE_X(1), usxy = TILE_XY(1), sx = TILE_X(2), sxy = TILE_XY(2);
    const int lx = dx > 0 ? -1 : 0, ly = dy > 0 ? -1 : 0, lz = dz > 0 ? -1 : 0;
    for (int fz = 0; fz <= BZ; ++fz)
        for (int fy = 0; fy <= BY; ++fy) {
            const int y = fy + ly, z = fz + lz;
            // rows y + dy, z + dz read this flux row one step back; row y, z itself too
            if (!node_row(rows, b, y, z) && !node_row(rows, b, y + dy, z) &&
                !node_row(rows, b, y, z + dz)) continue;
            for (int fx = 0; fx <= BX; ++fx) {
                const int x = fx + lx;
                REAL w[3];
                tile_flux(u, p, TILE_AT(1, x, y, z), TILE_AT(2, x, y, z), ex, ey, ez, usx, usxy,
                          sx, sxy, w);
                const int k = (fz * (BY + 1) + fy) * FX + fx;
                f[k] = w[0];
                f[FLUX_CELLS + k] = w[1];
                f[2 * FLUX_CELLS + k] = w[2];
            }
        }
}

// psi: the psi tiles (BrickBand.scatter with halo 2: per brick its cells and those within 2
// of its faces, the tile layout). One explicit step v = u + r div(...) (r = dt / h^2) on every cell of the bricks holding a
// NODE cell (the other cells' values are never read: re-extension reads nodes only). sx, sy,
// sz: the one-sided directions (+1 forward gradient, -1 backward). v is in the apron
// layout: a cell within AX of the brick's low faces is also written into the aprons of the
// bricks before it (along x, y, z and their combinations: up to 7), one writer per apron
// cell.
__kernel void brick_heat_step(__global const REAL* restrict u, __global REAL* restrict v,
                              __global const REAL* restrict psi, const REAL r, const int sx,
                              const int sy, const int sz, __global const uchar* restrict rows,
                              BRICK_ARGS)
{
    const int chan = get_global_id(1) * plane;
    __global REAL* vc = v + get_global_id(1) * (nbricks + 2) * BVA;
#if GROUP_PER_BRICK
    __local REAL ut[TILE_CELLS(1)];
#else
    REAL ut[TILE_CELLS(1)];
    REAL f[3 * FLUX_CELLS];
    // the flux cell of brick cell (0, 0, 0), and the flux offsets one step back along x, y, z
    const int f0 = ((sz > 0) * (BY + 1) + (sy > 0)) * FX + (sx > 0);
    const int fex = sx, fey = sy * FX, fez = sz * FXY;
#endif
    FOR_EACH_BRICK(b, BIT_NODE) {
        load_tile(ut, u + chan, nbr, b, 1);
        // psi is fixed: its tiles of halo 2 are stored, one after the other (psi_tiles)
        __global const REAL* pt = psi + b * TILE_CELLS(2);
        // the bricks before this one: k = 1..7, bit 0 x, bit 1 y, bit 2 z (0: none stored)
        __global const int* nb = nbr + 27 * b;
        const int before[8] = {b, nb[12], nb[10], nb[9], nb[4], nb[3], nb[1], nb[0]};
#if GROUP_PER_BRICK
        FOR_EACH_BRICK_CELL(l, x, y, z) {
            const int i = TILE_AT(1, x, y, z);
            const REAL val = ut[i] + r * tile_heat_div(ut, pt, i, TILE_AT(2, x, y, z), sx, sy, sz);
#else
        brick_fluxes(f, ut, pt, rows, b, sx, sy, sz);
        // rows along x without a node are skipped whole (their values are never read)
        for (int z = 0; z < BZ; ++z)
            for (int y = 0; y < BY; ++y) {
                if (!rows[b * BY * BZ + z * BY + y]) continue;
                for (int x = 0; x < BX; ++x) {
            const int i = TILE_AT(1, x, y, z);
            const int k = f0 + (z * (BY + 1) + y) * FX + x;
            // tile_heat_div's sum, with the fluxes looked up
            REAL div = ONE_SIDED_SIGN(sx) * (f[k] - f[k - fex]) +
                       ONE_SIDED_SIGN(sy) * (f[FLUX_CELLS + k] - f[FLUX_CELLS + k - fey]) +
                       ONE_SIDED_SIGN(sz) * (f[2 * FLUX_CELLS + k] - f[2 * FLUX_CELLS + k - fez]);
#if WEIGHTED
            const int q = TILE_AT(2, x, y, z), psx = TILE_X(2), psxy = TILE_XY(2);
            const REAL nx = (REAL)0.5 * (pt[q + 1] - pt[q - 1]);
            const REAL ny = (REAL)0.5 * (pt[q + psx] - pt[q - psx]);
            const REAL nz = (REAL)0.5 * (pt[q + psxy] - pt[q - psxy]);
            div *= RSQRT(nx * nx + ny * ny + nz * nz + (REAL)1e-30);
#endif
            const REAL val = ut[i] + r * div;
#endif
            vc[b * BVA + (z * BYA + y) * BXA + x] = val;
#if GROUP_PER_BRICK
            // each work-item copies its own value into the aprons it belongs to
            for (int k = 1; k < 8; ++k) {
                const int hx = k & 1, hy = (k >> 1) & 1, hz = k >> 2;
                if ((hx && x >= AX) || (hy && y >= AX) || (hz && z >= AX) || !before[k]) continue;
                vc[before[k] * BVA + ((z + hz * BZ) * BYA + y + hy * BY) * BXA + x + hx * BX] = val;
            }
#endif
#if GROUP_PER_BRICK
        }
#else
                }
            }
#endif
#if !GROUP_PER_BRICK
        // then the brick's low faces, edges and corner go to the aprons (a separate pass:
        // in the cell loop these stores kept it from being vectorised, 3x slower)
        APRON_COPY(1, 0, 0); APRON_COPY(0, 1, 0); APRON_COPY(1, 1, 0); APRON_COPY(0, 0, 1);
        APRON_COPY(1, 0, 1); APRON_COPY(0, 1, 1); APRON_COPY(1, 1, 1);
#endif
    }
}

// ---- closest-point re-extension --------------------------------------------------------------
// dst(x) = src(cp(x)) for the listed cells (all NC channels), interpolated as surface_extend.cl's
// extend_cp (tricubic Lagrange, or trilinear) from stencils computed once per psi (psi is
// fixed): per entry k the brick-storage index of the target cell (`list`, plain layout),
// the stencil's first node (x0, y0, z0) as its brick and place there (BrickBand.node_code),
// and the closest point's offsets from floor(cp) (frac[k], frac[n + k], frac[2n + k]). src
// is in the apron layout, so the whole stencil lies in the node's brick: fixed strides, as
// on the dense grid. (Gathering across the neighbouring bricks instead, with rows picking
// their brick, ran 3-4x slower; computing the closest points here from a psi tile cost more
// than the whole list re-extension on dense storage.)
// (REAL4, LOAD4, node_weights and NODES: surface.h.)

__kernel void brick_extend_cp(__global const REAL* restrict src, __global REAL* restrict dst,
                              __global const int* restrict base,
                              __global const REAL* restrict frac, const int src_plane,
                              LIST_ARGS)
{
    LIST_RANGE(k0, k1, chan_unused);
    for (int k = k0; k < k1; ++k) {
        const int code = base[k];  // brick << 12 | z << 8 | y << 4 | x of the first node
        const int node = code >> 12, lz0 = (code >> 8) & 15, ly0 = (code >> 4) & 15;
        const int b0 = node * BVA + (lz0 * BYA + ly0) * BXA + (code & 15);
        const REAL tx = frac[k], ty = frac[nlist + k], tz = frac[2 * nlist + k];
        REAL val[NC];
        #pragma unroll
        for (int c = 0; c < NC; ++c) {
            __global const REAL* u = src + c * src_plane + b0;
#if INTERP == 3
            // 16 rows of 4 nodes at fixed strides in the node's brick and its apron, summed
            // as 4-vectors (as surface_extend.cl's extend_cp)
            const REAL4 wy = node_weights(ty), wz = node_weights(tz);
            REAL4 acc = 0;
            for (int a = 0; a < 4; ++a) {
                __global const REAL* slab = u + a * (BXA * BYA);
                acc += wz[a] * (wy.x * LOAD4(slab) + wy.y * LOAD4(slab + BXA) +
                                wy.z * LOAD4(slab + 2 * BXA) + wy.w * LOAD4(slab + 3 * BXA));
            }
            const REAL4 wx = node_weights(tx);
            val[c] = acc.x * wx.x + acc.y * wx.y + acc.z * wx.z + acc.w * wx.w;
#else
            REAL acc = 0;
            for (int a = 0; a < 2; ++a)
                for (int e = 0; e < 2; ++e) {
                    const int row = a * (BXA * BYA) + e * BXA;
                    acc += ((a ? tz : 1 - tz) * (e ? ty : 1 - ty)) * ((1 - tx) * u[row] + tx * u[row + 1]);
                }
            val[c] = acc;
#endif
        }
#if NORMALIZE
        REAL n2 = 0;
        for (int c = 0; c < NC; ++c) n2 += val[c] * val[c];
        const REAL sc = n2 > 0 ? RSQRT(n2) : (REAL)0;
        for (int c = 0; c < NC; ++c) val[c] *= sc;
#endif
        const int i = list[k];
        for (int c = 0; c < NC; ++c) dst[c * plane + i] = val[c];
    }
}

// ---- the bricks' own roofline ------------------------------------------------------------------
// v = u + psi over every cell of the bricks holding a NODE cell: the bytes a heat step must
// move, with no stencil and no tile (benchmarks/surface_accuracy.py).
__kernel void brick_copy(__global const REAL* restrict u, __global REAL* restrict v,
                         __global const REAL* restrict psi, BRICK_ARGS)
{
    const int chan = get_global_id(1) * plane;
    FOR_EACH_BRICK(b, BIT_NODE) {
        FOR_EACH_BRICK_CELL(l, x, y, z) {
            v[chan + b * BV + l] = u[chan + b * BV + l] + psi[b * BV + l];
        }
    }
}
