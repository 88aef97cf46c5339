// The narrow band in dense bricks (clpde/bricks.py): kernels of the surface flows
// (heat, TV, harmonic maps, diffusion along a field, Turk's reaction-diffusion, TV's dynamic
// lambda) and the closest-point re-extension, with surface/flux.h's per-cell arithmetic, the
// band lists' own.
//
// A brick holds BX x BY x BZ cells (BV in all), x fastest; a quantity is one buffer
// (channels, nbricks + 2, BV), `plane` its channel stride: bricks 1..nbricks are stored,
// brick 0 is a sentinel of zeros for every brick place not stored, the last one slack. No halo is stored: a kernel copies its brick and the faces of its neighbours (the
// 27-entry table nbr) into a tile, then runs the stencils on the tile with plain strides.
//
// Launch geometry (GROUP_PER_BRICK): on CPUs (0) one work-item walks whole bricks, from a
// private tile; on GPUs (1) one work-group of BV work-items takes a brick, one cell each,
// from a tile in local memory. The arithmetic is the same (and is surface/heat.cl's): the
// results agree to rounding.
#include "common.h"
#include "surface/surface.h"
#include "bricks/bricks.h"
// the flux functions read u from the brick's tile
#define U_SPACE TILE
#include "surface/flux.h"

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

#ifndef FIDELITY
#define FIDELITY 0
#endif

// A tile of n REALs: in local memory on GPUs (declared at the kernel's scope), private on CPUs.
#if GROUP_PER_BRICK
#define TILE_ARRAY(name, n) __local REAL name[n]
#else
#define TILE_ARRAY(name, n) REAL name[n]
#endif

// The signed one-sided offsets (ex, ey, ez) in a tile of halo 1 for directions sx, sy, sz (+1
// forward gradient, -1 backward), and psi's strides in its tiles of halo 2.
#define TILE_STEPS(sx, sy, sz)                                                              \
    const int ex = (sx), ey = (sy) * TILE_X(1), ez = (sz) * TILE_XY(1);                   \
    const int psx = TILE_X(2), psxy = TILE_XY(2)

// ---- the stepped values, in the apron layout ------------------------------------------------
// A step writes v in the apron layout: a cell within AX of the brick's low faces is also
// written into the aprons of the bricks before it (along x, y, z and their combinations: up
// to 7), one writer per apron cell. before[k], k = 1..7 (bit 0 x, bit 1 y, bit 2 z): the
// brick before this one in those directions (0: none stored); before[0] = b.
INLINE void bricks_before(__global const int* restrict nbr, const int b, int before[8])
{
    __global const int* nb = nbr + 27 * b;
    before[0] = b;
    before[1] = nb[12];
    before[2] = nb[10];
    before[3] = nb[9];
    before[4] = nb[4];
    before[5] = nb[3];
    before[6] = nb[1];
    before[7] = nb[0];
}

// Store the stepped value of cell (x, y, z) of brick b (channel vc); on GPUs each work-item
// copies its own value into the aprons it belongs to, on CPUs apron_copy does it after the
// brick (in the cell loop these stores kept it from being vectorised; docs/surface_storage.md).
INLINE void store_stepped(__global REAL* restrict vc, const int b, const int before[8],
                          const int x, const int y, const int z, const REAL val)
{
    vc[b * BVA + (z * BYA + y) * BXA + x] = val;
#if GROUP_PER_BRICK
    for (int k = 1; k < 8; ++k) {
        const int hx = k & 1, hy = (k >> 1) & 1, hz = k >> 2;
        if ((hx && x >= AX) || (hy && y >= AX) || (hz && z >= AX) || !before[k]) continue;
        vc[before[k] * BVA + ((z + hz * BZ) * BYA + y + hy * BY) * BXA + x + hx * BX] = val;
    }
#endif
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

// The brick's low faces, edges and corner into the aprons (CPUs; on GPUs store_stepped did).
INLINE void apron_copy(__global REAL* restrict vc, const int b, const int before[8])
{
#if !GROUP_PER_BRICK
    APRON_COPY(1, 0, 0); APRON_COPY(0, 1, 0); APRON_COPY(1, 1, 0); APRON_COPY(0, 0, 1);
    APRON_COPY(1, 0, 1); APRON_COPY(0, 1, 1); APRON_COPY(1, 1, 1);
#endif
}

// Whether row (y, z) of brick b holds a node (false outside the brick): the steps skip the
// other rows, whose values are never read (the re-extension reads nodes only).
INLINE bool node_row(__global const uchar* restrict rows, const int b, const int y, const int z)
{
    return y >= 0 && y < BY && z >= 0 && z < BZ && rows[b * BY * BZ + z * BY + y];
}

// ---- flux tables (CPUs) ------------------------------------------------------------------
// A cell's divergence takes the flux at the cell and at the cells one step back along each
// axis (i - ex, i - ey, i - ez), which are the fluxes of its neighbours: on CPUs a step
// computes the fluxes of a brick's cells and of the one layer of cells behind its low
// (sx, sy, sz > 0) or high faces, (BX + 1) (BY + 1) (BZ + 1) of them, once each into a table,
// instead of four per cell; the same functions on the same cells, so the same values. Flux
// rows no node row reads are skipped.
#define FX (BX + 1)
#define FXY (FX * (BY + 1))
#define FLUX_CELLS (FXY * (BZ + 1))

// The flux cells whose fluxes a node row reads, as loops setting (x, y, z), the cell, and k,
// its place among the flux cells. These loops read the kernel's sx, sy, sz, rows and b.
#define FOR_EACH_FLUX_CELL(x, y, z, k)                                                    \
    for (int fz = 0; fz <= BZ; ++fz)                                                      \
        for (int fy = 0, y = fy - (sy > 0), z = fz - (sz > 0); fy <= BY; ++fy, ++y)       \
            if (node_row(rows, b, y, z) || node_row(rows, b, y + sy, z) ||                \
                node_row(rows, b, y, z + sz))                                             \
                for (int fx = 0, x = -(sx > 0), k = (fz * (BY + 1) + fy) * FX; fx <= BX;   \
                     ++fx, ++x, ++k)

// The node cells of brick b (CPUs: rows without a node skipped whole; x innermost), with
// l their place in the brick, i in u's tile, q in psi's, k among the flux cells.
#define FOR_EACH_NODE_ROW_CELL(l, i, q, k)                                                \
    for (int z = 0; z < BZ; ++z)                                                          \
        for (int y = 0; y < BY; ++y)                                                      \
            if (rows[b * BY * BZ + z * BY + y])                                           \
                for (int x = 0, l = (z * BY + y) * BX, i = TILE_AT(1, 0, y, z),           \
                     q = TILE_AT(2, 0, y, z), k = f0 + (z * (BY + 1) + y) * FX; x < BX;   \
                     ++x, ++l, ++i, ++q, ++k)

// A flux table's divergence at flux cell k (channel block fc: x, y, z components FLUX_CELLS
// apart; fe: the steps one flux cell back).
#define TABLE_DIV(fc, k)                                                                  \
    (ONE_SIDED_SIGN(sx) * ((fc)[k] - (fc)[(k) - fe0]) +                                   \
     ONE_SIDED_SIGN(sy) * ((fc)[FLUX_CELLS + (k)] - (fc)[FLUX_CELLS + (k) - fe1]) +       \
     ONE_SIDED_SIGN(sz) * ((fc)[2 * FLUX_CELLS + (k)] - (fc)[2 * FLUX_CELLS + (k) - fe2]))

// The flux table's offsets: the flux cell of brick cell (0, 0, 0) and the steps back.
#define FLUX_TABLE_STEPS(sx, sy, sz)                                                      \
    const int f0 = ((sz > 0) * (BY + 1) + (sy > 0)) * FX + (sx > 0);                      \
    const int fe0 = (sx), fe1 = (sy) * FX, fe2 = (sz) * FXY

// 1 / |N| at psi tile cell q (WEIGHTED), else 1.
INLINE REAL inv_normal_length(__global const REAL* p, const int q, const int psx, const int psxy)
{
#if WEIGHTED
    const vec3r n = psi_normal(p, q, psx, psxy);
    return RSQRT(n.x * n.x + n.y * n.y + n.z * n.z + (REAL)1e-30);
#else
    return 1;
#endif
}

// ---- intrinsic heat flow (4.7) / (4.8), appendix E -----------------------------------------
// psi: the psi tiles (BrickBand.scatter_tiles with halo 2: per brick its cells and those
// within 2 of its faces). One explicit step v = u + r div(...) (r = dt / h^2) on the node
// rows of the bricks holding a NODE cell, one channel per get_global_id(1). sx, sy, sz: the
// one-sided directions (+1 forward gradient, -1 backward).
__kernel void bricks_heat_step(__global const REAL* restrict u, __global REAL* restrict v,
                              __global const REAL* restrict psi, const REAL r, const int sx,
                              const int sy, const int sz, __global const uchar* restrict rows,
                              BRICK_ARGS)
{
    const int chan = get_global_id(1) * plane;
    __global REAL* vc = v + get_global_id(1) * (nbricks + 2) * BVA;
    TILE_ARRAY(ut, TILE_CELLS(1));
    TILE_STEPS(sx, sy, sz);
#if !GROUP_PER_BRICK
    REAL f[3 * FLUX_CELLS];
    FLUX_TABLE_STEPS(sx, sy, sz);
#endif
    FOR_EACH_BRICK(b, BIT_NODE) {
        load_tile(ut, u + chan, nbr, b, 1);
        __global const REAL* pt = psi + b * TILE_CELLS(2);
        int before[8];
        bricks_before(nbr, b, before);
#if GROUP_PER_BRICK
        FOR_EACH_BRICK_CELL(l, x, y, z) {
            const int i = TILE_AT(1, x, y, z);
            store_stepped(vc, b, before, x, y, z,
                          ut[i] + r * heat_div(ut, i, ex, ey, ez, pt, TILE_AT(2, x, y, z), psx,
                                               psxy));
        }
#else
        FOR_EACH_FLUX_CELL(x, y, z, k) {
            const vec3r w = heat_flux(ut, TILE_AT(1, x, y, z), ex, ey, ez, pt, TILE_AT(2, x, y, z),
                                      psx, psxy);
            f[k] = w.x;
            f[FLUX_CELLS + k] = w.y;
            f[2 * FLUX_CELLS + k] = w.z;
        }
        FOR_EACH_NODE_ROW_CELL(l, i, q, k) {
            // heat_div, with the fluxes looked up
            store_stepped(vc, b, before, x, y, z,
                          ut[i] + r * (TABLE_DIV(f, k) * inv_normal_length(pt, q, psx, psxy)));
        }
        apron_copy(vc, b, before);
#endif
    }
}

// ---- TV, harmonic maps, diffusion along a field (surface/flows.cl's flow_step) -------------
// All NC channels per work-item (the flows couple them): u's tiles of halo 1, one per channel;
// psi and dir (ALONG, 3 channels) in stored tiles of halo 2, dir's channel stride that of
// the tiles; u0 (FIDELITY) in the plain brick layout. v as brick_heat_step writes it.
// On CPUs each flux is computed once per brick into flux tables, as brick_heat_step does, but
// for line fields, whose fluxes depend on the updated cell (their signs turn to its vector).
#define FLOW_CACHE (!GROUP_PER_BRICK && !LINE_FIELD)

// A flow's stepped value of channel c with fidelity (C.1), stored in the apron layout.
#define STORE_FLOW(c, val)                                                                \
    {                                                                                     \
        REAL out_ = (val);                                                                \
        if (FIDELITY)                                                                     \
            out_ -= dt * lambda[0] *                                                      \
                    (ut[(c) * TILE_CELLS(1) + i] - u0[(c) * plane + b * BV + l]);         \
        store_stepped(v + (c) * vplane, b, before, x, y, z, out_);                        \
    }

__kernel void bricks_flow_step(__global const REAL* restrict u, __global REAL* restrict v,
                              __global const REAL* restrict psi, __global const REAL* restrict dir,
                              __global const REAL* restrict u0, const REAL r, const REAL dt,
                              __global const REAL* restrict lambda, const REAL e2, const int sx,
                              const int sy, const int sz, __global const uchar* restrict rows,
                              BRICK_ARGS)
{
    TILE_ARRAY(ut, NC * TILE_CELLS(1));
    TILE_STEPS(sx, sy, sz);
    const int dplane = (nbricks + 2) * TILE_CELLS(2), vplane = (nbricks + 2) * BVA;
#if FLOW_CACHE
    // the fluxes of the flux cells ((channel, component) blocks) and |P v|^2 there
    REAL f[3 * NC * FLUX_CELLS], g2[FLUX_CELLS];
    FLUX_TABLE_STEPS(sx, sy, sz);
#endif
    FOR_EACH_BRICK(b, BIT_NODE) {
        for (int c = 0; c < NC; ++c) load_tile(ut + c * TILE_CELLS(1), u + c * plane, nbr, b, 1);
        __global const REAL* pt = psi + b * TILE_CELLS(2);
        __global const REAL* dirt = dir + b * TILE_CELLS(2);
        int before[8];
        bricks_before(nbr, b, before);
#if FLOW_CACHE
        FOR_EACH_FLUX_CELL(x, y, z, k) {
            const int j = TILE_AT(1, x, y, z);
            REAL w[NC][3];
            g2[k] = flow_flux(ut, TILE_CELLS(1), j, ex, ey, ez, pt, dirt, dplane,
                              TILE_AT(2, x, y, z), psx, psxy, e2, j, w);
            #pragma unroll
            for (int c = 0; c < NC; ++c) {
                f[3 * c * FLUX_CELLS + k] = w[c][0];
                f[(3 * c + 1) * FLUX_CELLS + k] = w[c][1];
                f[(3 * c + 2) * FLUX_CELLS + k] = w[c][2];
            }
        }
        FOR_EACH_NODE_ROW_CELL(l, i, q, k) {
            // flow_cell, with the fluxes looked up
            const REAL inv_len = inv_normal_length(pt, q, psx, psxy);
            #pragma unroll
            for (int c = 0; c < NC; ++c)
                STORE_FLOW(c, flow_update(ut[c * TILE_CELLS(1) + i],
                                          TABLE_DIV(f + 3 * c * FLUX_CELLS, k), inv_len, g2[k], r));
        }
#else
        FOR_EACH_BRICK_CELL(l, x, y, z) {
            if (!node_row(rows, b, y, z)) continue;
            const int i = TILE_AT(1, x, y, z);
            REAL val[NC];
            flow_cell(ut, TILE_CELLS(1), i, ex, ey, ez, pt, dirt, dplane, TILE_AT(2, x, y, z),
                      psx, psxy, e2, r, val);
            #pragma unroll
            for (int c = 0; c < NC; ++c) STORE_FLOW(c, val[c]);
        }
#endif
        for (int c = 0; c < NC; ++c) apron_copy(v + c * vplane, b, before);
    }
}

// The per-cell terms of TV's dynamic lambda (C.2) at the NODE cells (cell_bits, plain brick
// layout), into num, area and resid (plain brick layout; the other cells keep their zeros).
__kernel void bricks_lambda_terms(__global const REAL* restrict u, __global const REAL* restrict u0,
                                 __global const REAL* restrict psi, const REAL inv_h,
                                 const REAL eps_cells, const REAL e2, const int sx, const int sy,
                                 const int sz, __global const uchar* restrict cell_bits,
                                 __global REAL* restrict num, __global REAL* restrict area,
                                 __global REAL* restrict resid, BRICK_ARGS)
{
    TILE_ARRAY(ut, TILE_CELLS(1));
    TILE_ARRAY(u0t, TILE_CELLS(1));
    TILE_STEPS(sx, sy, sz);
    FOR_EACH_BRICK(b, BIT_NODE) {
        load_tile(ut, u, nbr, b, 1);
        load_tile(u0t, u0, nbr, b, 1);
        __global const REAL* pt = psi + b * TILE_CELLS(2);
        FOR_EACH_BRICK_CELL(l, x, y, z) {
            const int k = b * BV + l;
            if (!(cell_bits[k] & BIT_NODE)) continue;
            const lambda_terms t = lambda_terms_cell(ut, u0t, TILE_AT(1, x, y, z), ex, ey, ez, pt,
                                                     TILE_AT(2, x, y, z), psx, psxy, inv_h,
                                                     eps_cells, e2);
            num[k] = t.num;
            area[k] = t.area;
            resid[k] = t.resid;
        }
    }
}

// ---- Turk's reaction-diffusion (surface/heat.cl's turk_step) ---------------------------------
// The two chemicals' tiles of halo 1; dir (ALONG) as brick_flow_step's, beta in the plain
// brick layout. On CPUs both chemicals' fluxes are computed once per brick (flux tables).
__kernel void bricks_turk_step(__global const REAL* restrict u, __global REAL* restrict v,
                              __global const REAL* restrict psi, __global const REAL* restrict dir,
                              __global const REAL* restrict beta, const REAL dt, const REAL da,
                              const REAL db, const REAL s, const int sx, const int sy,
                              const int sz, __global const uchar* restrict rows, BRICK_ARGS)
{
    TILE_ARRAY(ut, 2 * TILE_CELLS(1));
    TILE_STEPS(sx, sy, sz);
    const int dplane = (nbricks + 2) * TILE_CELLS(2), vplane = (nbricks + 2) * BVA;
#if !GROUP_PER_BRICK
    REAL fa[3 * FLUX_CELLS], fb[3 * FLUX_CELLS];
    FLUX_TABLE_STEPS(sx, sy, sz);
#endif
    FOR_EACH_BRICK(b, BIT_NODE) {
        load_tile(ut, u, nbr, b, 1);
        load_tile(ut + TILE_CELLS(1), u + plane, nbr, b, 1);
        __global const REAL* pt = psi + b * TILE_CELLS(2);
        __global const REAL* dirt = dir + b * TILE_CELLS(2);
        int before[8];
        bricks_before(nbr, b, before);
#if GROUP_PER_BRICK
        FOR_EACH_BRICK_CELL(l, x, y, z) {
            if (!node_row(rows, b, y, z)) continue;
            const REAL2 ab = turk_cell(ut, TILE_CELLS(1), TILE_AT(1, x, y, z), ex, ey, ez, pt, dirt,
                                       dplane, TILE_AT(2, x, y, z), psx, psxy, beta[b * BV + l],
                                       dt, da, db, s);
#else
        FOR_EACH_FLUX_CELL(x, y, z, k) {
            const int j = TILE_AT(1, x, y, z), q = TILE_AT(2, x, y, z);
#if ALONG
            const vec3r wa = along_flux(ut, j, ex, ey, ez, pt, dirt, dplane, q, psx, psxy);
#else
            const vec3r wa = heat_flux(ut, j, ex, ey, ez, pt, q, psx, psxy);
#endif
            const vec3r wb = heat_flux(ut + TILE_CELLS(1), j, ex, ey, ez, pt, q, psx, psxy);
            fa[k] = wa.x;
            fa[FLUX_CELLS + k] = wa.y;
            fa[2 * FLUX_CELLS + k] = wa.z;
            fb[k] = wb.x;
            fb[FLUX_CELLS + k] = wb.y;
            fb[2 * FLUX_CELLS + k] = wb.z;
        }
        FOR_EACH_NODE_ROW_CELL(l, i, q, k) {
            // turk_cell, with the fluxes looked up
            const REAL2 ab = turk_update(ut[i], ut[TILE_CELLS(1) + i], TABLE_DIV(fa, k),
                                         TABLE_DIV(fb, k), beta[b * BV + l], dt, da, db, s);
#endif
            store_stepped(v, b, before, x, y, z, ab.x);
            store_stepped(v + vplane, b, before, x, y, z, ab.y);
        }
        apron_copy(v, b, before);
        apron_copy(v + vplane, b, before);
    }
}

// ---- the apron layout of a plain brick buffer -----------------------------------------------
// dst: src's bricks each lengthened by the first AX cells of the next bricks along x, y, z
// (their combinations too), as the steps write it: the re-extension's source before a flow's
// first step, made on the device from the plain layout (channel per get_global_id(1)), for
// the bricks with a band cell (no stencil starts in the others). Next brick places not
// stored read the sentinel's zeros (no stencil reaches them: every node's brick is stored).
__kernel void bricks_to_apron(__global const REAL* restrict src, __global REAL* restrict dst,
                             BRICK_ARGS)
{
    __global const REAL* s = src + get_global_id(1) * plane;
    __global REAL* d = dst + get_global_id(1) * (nbricks + 2) * BVA;
    FOR_EACH_BRICK(b, 0xff) {
        __global const int* nb = nbr + 27 * b;
#if GROUP_PER_BRICK
        for (int k = get_local_id(0); k < BVA; k += BV) {
#else
        for (int k = 0; k < BVA; ++k) {
#endif
            const int x = k % BXA, y = (k / BXA) % BYA, z = k / (BXA * BYA);
            const int hx = x >= BX, hy = y >= BY, hz = z >= BZ;
            const int from = nb[(hz + 1) * 9 + (hy + 1) * 3 + hx + 1];
            d[b * BVA + k] = s[from * BV + ((z - hz * BZ) * BY + y - hy * BY) * BX + x - hx * BX];
        }
    }
}

// ---- closest-point re-extension --------------------------------------------------------------
// dst(x) = src(cp(x)) for the listed cells (all NC channels), interpolated as surface/extend.cl's
// extend_cp (tricubic Lagrange, or trilinear) from stencils computed once per psi (psi is
// fixed): per entry k the brick-storage index of the target cell (`list`, plain layout),
// the stencil's first node (x0, y0, z0) as its brick and place there (BrickBand.node_code),
// and the closest point's offsets from floor(cp) (frac[k], frac[n + k], frac[2n + k]). src
// is in the apron layout, so the whole stencil lies in the node's brick: fixed strides, as
// on the dense grid. (Gathering across the neighbouring bricks instead, with rows picking
// their brick, ran slower (docs/surface_storage.md); computing the closest points here from a psi tile cost more
// than the whole list re-extension on dense storage.)
// (REAL4, LOAD4, node_weights and NODES: surface.h.)

__kernel void bricks_extend_cp(__global const REAL* restrict src, __global REAL* restrict dst,
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
#if LINE_FIELD
            // line field: every node's vector turned to the side of floor(cp)'s node
            const int ref = b0 + (NODES / 2 - 1) * (BXA * BYA + BXA + 1);
            const NODE_WEIGHTS wx = node_weights(tx), wy = node_weights(ty), wz = node_weights(tz);
            REAL acc = 0;
            for (int a = 0; a < NODES; ++a)
                for (int e = 0; e < NODES; ++e)
                    for (int d = 0; d < NODES; ++d) {
                        const int p = b0 + (a * BYA + e) * BXA + d;
                        acc += line_sign(src, ref, p, src_plane) * (wz[a] * wy[e] * wx[d]) *
                               u[p - b0];
                    }
            val[c] = acc;
#elif INTERP == 3
            // 16 rows of 4 nodes at fixed strides in the node's brick and its apron, summed
            // as 4-vectors (as surface/extend.cl's extend_cp)
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
