// Region tracking (regions.cl) on the narrow band in dense bricks (clpde/regions/bricks.py).
//
// Every level set (channel 0 Phi, channels 1.. the Phi-hats) is one brick buffer
// (NC, nbricks + 2, BV) of bricks.h, `plane` its channel stride. Brick 0 stands for every
// brick place not stored and holds FAR (a positive distance beyond every band), so a tile
// cell there counts as outside the band; the upkeep keeps every brick a band cell's stencils
// reach (see brick_upkeep_flags), so no update reads it. A kernel copies a brick of every
// channel and its neighbours' faces into a private tile (load_tile) and runs regions.h's,
// godunov.h's, reinit.h's and extend.h's functions on it with the tile's strides: the same
// arithmetic as regions.cl's kernels. One work-item walks whole bricks (the CPU geometry of
// bricks.h, also used on GPUs here).
//
// `mask` (one byte per brick cell, BrickBand's layout) holds the band bits written by
// brick_band_mask: BIT_STEP, the step band (interior cells with |Phi| < width, as
// regions.cl's region_band_mask), and BIT_REINIT, the reinitialisation band (the step band
// dilated by RING cells, a cube, as dilate_mask does). brick_bits is their union per brick:
// the kernels skip bricks without the bit they update, so the work follows the band.
#define LS_SPACE __private
#define GROUP_PER_BRICK 0
#include "common.h"
#include "godunov.h"
#include "reinit.h"
#include "extend.h"
#include "regions/regions.h"
#include "bricks/bricks.h"

#define BIT_STEP 1
#define BIT_REINIT 2
#ifndef RING
#define RING 3  // the reinitialisation band's ring (RegionTracker's reinit_ring)
#endif
// The cells a band cell's updates reach: its reinitialisation ring and two more, the
// slope-limited stencils' half-width.
#define REACH (RING + 2)

// Tiles of every channel around brick b: channel c at t + c * TILE_CELLS(H).
INLINE void load_tiles(TILE REAL* t, __global const REAL* restrict src,
                       __global const int* restrict nbr, const int b, const int H,
                       const int plane)
{
    for (int c = 0; c < NC; ++c) load_tile(t + c * TILE_CELLS(H), src + c * plane, nbr, b, H);
}

// The rows along x of brick b holding a step-band cell (the stages skip the others: a third
// or more of a brick's rows for a band 10 cells thick).
#define FOR_EACH_BAND_ROW(b, y, z, bit)                                                   \
    for (int z = 0; z < BZ; ++z)                                                          \
        for (int y = 0; y < BY; ++y)                                                      \
            if (row_bits(mask, b, y, z) & (bit))
#define FOR_EACH_STEP_ROW(b, y, z) FOR_EACH_BAND_ROW(b, y, z, BIT_STEP)
// ... and of the reinitialisation band (the tracker keeps cur and nxt equal outside it)
#define FOR_EACH_REINIT_ROW(b, y, z) FOR_EACH_BAND_ROW(b, y, z, BIT_REINIT)
#define ROW_CELLS(x, l, y, z) for (int x = 0, l = ((z) * BY + (y)) * BX; x < BX; ++x, ++l)

INLINE uchar row_bits(__global const uchar* restrict mask, const int b, const int y, const int z)
{
    uchar any = 0;
    for (int x = 0; x < BX; ++x) any |= mask[b * BV + (z * BY + y) * BX + x];
    return any;
}

// ---- one Euler stage of every level set (regions.cl's region_euler / region_heun) ----------
// Cells outside the step band keep their values: region_euler copies them (so out equals ls
// there, as the lists' synced work buffers do), region_heun averages two equal values. Rows
// without a step-band cell are skipped: the tracker keeps nxt equal to cur outside the step
// band (region_bricks.py), which is what both stages would write there.
// stats: as regions.cl's, per work-item max |V| over the step band's cells with |Phi| < hi.
INLINE void brick_stage(__global const REAL* restrict ls, __global const REAL* restrict aux,
                        __global REAL* restrict out, __global REAL* restrict stats,
                        __global const uchar* restrict mask, const REAL dt, const REAL eps2,
                        const REAL lo, const REAL hi, const REAL scale, const REAL vmax,
                        const int second, BRICK_ARGS)
{
    const int sx = TILE_X(2), sxy = TILE_XY(2), tp = TILE_CELLS(2);
    REAL t[NC * TILE_CELLS(2)];
    REAL_BITS fastest = 0;
    FOR_EACH_BRICK(b, BIT_STEP) {
        load_tiles(t, ls, nbr, b, 2, plane);
        FOR_EACH_STEP_ROW(b, y, z) ROW_CELLS(x, l, y, z) {
            const int i = TILE_AT(2, x, y, z), k = b * BV + l;
            const int step = mask[k] & BIT_STEP;
            const REAL speed = region_speed_at(t, aux[k], i, scale, vmax, sx, sxy);
            const REAL_BITS bits = (step && FABS(t[i]) < hi) ? AS_BITS(FABS(speed)) : 0;
            fastest = bits > fastest ? bits : fastest;
            const REAL v0 = speed * band_cutoff(t[i], lo, hi);
            CENTRAL_GRAD(t, i, fx, fy, fz);
            const REAL f2 = fx * fx + fy * fy + fz * fz + eps2;
#pragma unroll
            for (int c = 0; c < NC; ++c) {
                const int j = c * tp + i;
                const REAL next = region_next(t, c, j, v0, fx, fy, fz, f2, eps2, dt, sx, sxy);
                const REAL val = step ? next : t[j];
                __global REAL* o = out + c * plane + k;
                *o = second ? (REAL)0.5 * (*o + val) : val;
            }
        }
    }
    stats[get_global_size(0) * second + get_global_id(0)] = AS_REAL(fastest);
}

#define BRICK_STAGE_ARGS                                                                   \
    __global const REAL* restrict ls, __global const REAL* restrict aux,                   \
        __global REAL* restrict out, __global REAL* restrict stats,                        \
        __global const uchar* restrict mask, const REAL dt, const REAL eps2, const REAL lo, \
        const REAL hi, const REAL scale, const REAL vmax, BRICK_ARGS
#define BRICK_STAGE_CALL(second)                                                           \
    brick_stage(ls, aux, out, stats, mask, dt, eps2, lo, hi, scale, vmax, second, nbr,     \
                brick_bits, nbricks, plane, per_item)
__kernel void bricks_euler(BRICK_STAGE_ARGS) { BRICK_STAGE_CALL(0); }
__kernel void bricks_heun(BRICK_STAGE_ARGS) { BRICK_STAGE_CALL(1); }

// Rigid motion (regions.cl's advect_step) as a Heun stage: second = 0 writes out = ls +
// dt L(ls), second = 1 averages out = (out + ls + dt L(ls)) / 2 (the lists' heun_average
// of the second stage, the same values).
__kernel void bricks_advect(__global const REAL* restrict ls, __global REAL* restrict out,
                                  __global const uchar* restrict mask, const REAL dt,
                                  const REAL ux, const REAL uy, const REAL uz, const REAL lo,
                                  const REAL hi, const int second, BRICK_ARGS)
{
    const int sx = TILE_X(2), sxy = TILE_XY(2), tp = TILE_CELLS(2);
    REAL t[NC * TILE_CELLS(2)];
    FOR_EACH_BRICK(b, BIT_STEP) {
        load_tiles(t, ls, nbr, b, 2, plane);
        FOR_EACH_STEP_ROW(b, y, z) ROW_CELLS(x, l, y, z) {
            const int i = TILE_AT(2, x, y, z), k = b * BV + l;
            const int step = mask[k] & BIT_STEP;
            const REAL cut = band_cutoff(t[i], lo, hi);
#pragma unroll
            for (int c = 0; c < NC; ++c) {
                const int j = c * tp + i;
                const REAL val = step ? advect_next(t, j, cut, dt, ux, uy, uz, sx, sxy) : t[j];
                __global REAL* o = out + c * plane + k;
                *o = second ? (REAL)0.5 * (*o + val) : val;
            }
        }
    }
}

// ---- reinitialisation (regions.cl's extend_outer, reinit3d_targets, _step_pre, _heun_pre) --
// The extension of the Phi-hat along Phi's normals; Phi itself is copied (so out equals ls
// on every brick written, and the host swaps the two).
__kernel void bricks_extend(__global const REAL* restrict ls,
                                  __global const uchar* restrict mask,
                                  __global REAL* restrict out, const REAL dt, const REAL lo,
                                  const REAL hi, BRICK_ARGS)
{
    const int sx = TILE_X(1), sxy = TILE_XY(1), tp = TILE_CELLS(1);
    REAL t[NC * TILE_CELLS(1)];
    FOR_EACH_BRICK(b, BIT_REINIT) {
        load_tiles(t, ls, nbr, b, 1, plane);
        FOR_EACH_REINIT_ROW(b, y, z) ROW_CELLS(x, l, y, z) {
            const int i = TILE_AT(1, x, y, z), k = b * BV + l;
            const int inband = mask[k] & BIT_REINIT;
            REAL ax, ay, az;
            const REAL w = extend_velocity(t, i, lo, hi, sx, sxy, &ax, &ay, &az);
            out[k] = t[i];
#pragma unroll
            for (int c = 1; c < NC; ++c) {
                const int j = c * tp + i;
                const REAL v = t[j];
                const REAL du = upwind_transport(t, j, sx, sxy, ax, ay, az);
                out[c * plane + k] = inband ? v - dt * w * du : v;
            }
        }
    }
}

// The subcell fix's targets (reinit.h's subcell_target_3d), -INFINITY outside the band.
__kernel void bricks_targets(__global const REAL* restrict u0,
                                   __global const uchar* restrict mask,
                                   __global REAL* restrict target, BRICK_ARGS)
{
    const int sx = TILE_X(1), sxy = TILE_XY(1), tp = TILE_CELLS(1);
    REAL t[NC * TILE_CELLS(1)];
    FOR_EACH_BRICK(b, BIT_REINIT) {
        load_tiles(t, u0, nbr, b, 1, plane);
        FOR_EACH_REINIT_ROW(b, y, z) ROW_CELLS(x, l, y, z) {
            const int i = TILE_AT(1, x, y, z), k = b * BV + l;
            const int inband = mask[k] & BIT_REINIT;
#pragma unroll
            for (int c = 0; c < NC; ++c) {
                const REAL g = subcell_target_3d(t, c * tp + i, sx, sxy, (REAL)SUBCELL_STEEP,
                                                 (REAL)SUBCELL_TOL);
                target[c * plane + k] = inband ? g : (REAL)-INFINITY;
            }
        }
    }
}

// A stage of the reinitialisation's Heun step: out = u + dt L(u) (the first), or averaged
// in place, out <- (out + u + dt L(u)) / 2 (the second, u the first stage's result).
__kernel void bricks_reinit_stage(__global const REAL* restrict u,
                                        __global const REAL* restrict u0,
                                        __global const REAL* restrict target,
                                        __global REAL* restrict out,
                                        __global const uchar* restrict mask, const REAL dt,
                                        const int second, BRICK_ARGS)
{
    const int sx = TILE_X(2), sxy = TILE_XY(2), tp = TILE_CELLS(2);
    REAL t[NC * TILE_CELLS(2)];
    FOR_EACH_BRICK(b, BIT_REINIT) {
        load_tiles(t, u, nbr, b, 2, plane);
        FOR_EACH_REINIT_ROW(b, y, z) ROW_CELLS(x, l, y, z) {
            const int i = TILE_AT(2, x, y, z), k = b * BV + l;
#pragma unroll
            for (int c = 0; c < NC; ++c) {
                const int ck = c * plane + k;
                const REAL next = reinit_update_at(t, c * tp + i, sx, sxy, u0[ck], target[ck], dt);
                out[ck] = second ? (REAL)0.5 * (out[ck] + next) : next;
            }
        }
    }
}

// ---- the bands and their upkeep ----------------------------------------------------------------
// Whether cell (x, y, z) of brick b (coords: per brick its brick coordinates, 3 ints, row b)
// is an interior cell of the grid (nx, ny, nz) with ghost width G.
INLINE int interior(__global const int* restrict coords, const int b, const int x, const int y,
                    const int z, const int nx, const int ny, const int nz, const int G)
{
    const int gx = coords[3 * b] * BX + x - G, gy = coords[3 * b + 1] * BY + y - G;
    const int gz = coords[3 * b + 2] * BZ + z - G;
    return gx >= 0 && gy >= 0 && gz >= 0 && gx < nx && gy < ny && gz < nz;
}

// The band bits of every cell (mask), their union per brick (bits), and flag[0] = 1 when a
// cell of the reinitialisation band lies within one cell of the interior's border (regions.cl's
// band_near_border with margin 1). Per brick: Phi's tile of halo RING, the step band on it as
// one bit word per tile row along x (bit RING + x for cell x), then its dilation by RING
// cells along x (shifts), y and z (ORs of rows) in turn: a cube, as dilate_mask's passes.
#define MY (BY + 2 * RING)
#define MZ (BZ + 2 * RING)
__kernel void bricks_band_mask(__global const REAL* restrict phi,
                                     __global uchar* restrict mask, __global uchar* restrict bits,
                                     __global const int* restrict coords,
                                     __global int* restrict flag, const REAL width,
                                     const int nx, const int ny, const int nz, const int G,
                                     __global const int* restrict nbr, const int nbricks,
                                     const int per_item)
{
    REAL t[TILE_CELLS(RING)];
    uint rows[MZ * MY];  // the step band on the tile
    uint wide[MZ * MY];  // dilated along x (bit x for brick cell x)
    uint tall[MZ * BY];  // and along y
    int hit = 0;
    for (int b = 1 + get_global_id(0) * per_item, b_end = min(b + per_item, nbricks + 1);
         b < b_end; ++b) {
        load_tile(t, phi, nbr, b, RING);
        const int x0 = coords[3 * b] * BX - G - RING, y0 = coords[3 * b + 1] * BY - G - RING;
        const int z0 = coords[3 * b + 2] * BZ - G - RING;
        uint inner = 0;  // the tile's columns inside the interior along x
        for (int x = 0; x < BX + 2 * RING; ++x)
            inner |= (uint)(x0 + x >= 0 && x0 + x < nx) << x;
        for (int z = 0; z < MZ; ++z)
            for (int y = 0; y < MY; ++y) {
                const int k = (z * MY + y) * TILE_X(RING);
                uint row = 0;
                for (int x = 0; x < BX + 2 * RING; ++x) row |= (uint)(FABS(t[k + x]) < width) << x;
                const int in = y0 + y >= 0 && y0 + y < ny && z0 + z >= 0 && z0 + z < nz;
                rows[z * MY + y] = in ? row & inner : 0;
                uint w = 0;
                for (int d = 0; d <= 2 * RING; ++d) w |= rows[z * MY + y] >> d;
                wide[z * MY + y] = w;
            }
        for (int z = 0; z < MZ; ++z)
            for (int y = 0; y < BY; ++y) {
                uint w = 0;
                for (int d = 0; d <= 2 * RING; ++d) w |= wide[z * MY + y + d];
                tall[z * BY + y] = w;
            }
        uchar any = 0;
        for (int z = 0; z < BZ; ++z)
            for (int y = 0; y < BY; ++y) {
                uint w = 0;
                for (int d = 0; d <= 2 * RING; ++d) w |= tall[(z + d) * BY + y];
                const uint step = rows[(z + RING) * MY + y + RING] >> RING;
                for (int x = 0, l = (z * BY + y) * BX; x < BX; ++x, ++l) {
                    const uchar cell = ((step >> x) & 1) * BIT_STEP | ((w >> x) & 1) * BIT_REINIT;
                    mask[b * BV + l] = cell;
                    any |= cell;
                }
                if (w & ((1u << BX) - 1)) {
                    // the row's first and last reinitialisation cells, and the row itself
                    const int gy = y0 + RING + y, gz = z0 + RING + z;
                    const int first = 31 - clz(w & -w), last = 31 - clz(w & ((1u << BX) - 1));
                    hit |= (gy < 1) | (gz < 1) | (gy >= ny - 1) | (gz >= nz - 1) |
                           (x0 + RING + first < 1) | (x0 + RING + last >= nx - 1);
                }
            }
        bits[b] = any;
    }
    if (hit) flag[0] = 1;  // every writer stores the same value
}

// The upkeep's flag word of every brick (flags[b - 1]): bit k (k = (dz + 1) 9 + (dy + 1) 3 +
// dx + 1, the neighbour table's order) is set when brick b + (dx, dy, dz) holds a cell within
// REACH cells (a cube) of a step-band cell of brick b (|Phi| < width, interior), so bit 13
// says the brick holds one; bit 27 is the brick's sign (its middle cell's Phi < 0), kept
// for the bricks the host drops. The host stores exactly the bricks some brick flags: every
// cell of the next reinitialisation band (the step band dilated by RING) and the stencils
// of its cells (2 more) then lie in stored bricks. Needs REACH <= every brick side.
INLINE int axis_code(const int x, const int side)
{
    return 2 | (x < REACH) | ((x >= side - REACH) << 2);  // bit 0: -1, bit 1: 0, bit 2: +1
}

__kernel void bricks_flags(__global const REAL* restrict phi, __global int* restrict flags,
                                 __global const int* restrict coords, const REAL width,
                                 const int nx, const int ny, const int nz, const int G,
                                 const int nbricks, const int per_item)
{
    for (int b = 1 + get_global_id(0) * per_item, b_end = min(b + per_item, nbricks + 1);
         b < b_end; ++b) {
        int word = phi[b * BV + ((BZ / 2) * BY + BY / 2) * BX + BX / 2] < 0 ? 1 << 27 : 0;
        for (int z = 0; z < BZ; ++z)
            for (int y = 0; y < BY; ++y) {
                int rx = 0;
                for (int x = 0; x < BX; ++x) {
                    const int band = FABS(phi[b * BV + (z * BY + y) * BX + x]) < width &&
                                     interior(coords, b, x, y, z, nx, ny, nz, G);
                    rx |= band ? axis_code(x, BX) : 0;
                }
                if (!rx) continue;
                const int ry = axis_code(y, BY), rz = axis_code(z, BZ);
                for (int kz = 0; kz < 3; ++kz)
                    for (int ky = 0; ky < 3; ++ky)
                        for (int kx = 0; kx < 3; ++kx)
                            if ((rz >> kz) & (ry >> ky) & (rx >> kx) & 1)
                                word |= 1 << (kz * 9 + ky * 3 + kx);
            }
        flags[b - 1] = word;
    }
}

// The new storage from the old: new brick b (1..nbricks) copies old brick src[b] when
// dir[b] < 0 (kept); else it is new, next to old brick src[b] in direction dir[b] (the
// neighbour table's order), and every cell takes the values of the nearest cell of that
// brick's facing side, Phi replaced by `far` with its sign (beyond the step band: the
// reinitialisations that follow bring the cells they reach to distances). Work-item 0
// also fills the sentinel brick 0 of every channel with FAR.
__kernel void bricks_remap(__global const REAL* restrict old, __global REAL* restrict out,
                                 __global const int* restrict src, __global const int* restrict dir,
                                 const REAL far, const REAL sentinel, const int old_plane,
                                 const int plane, const int nbricks, const int per_item)
{
    if (get_global_id(0) == 0)
        for (int c = 0; c < NC; ++c)
            for (int l = 0; l < BV; ++l) out[c * plane + l] = sentinel;
    for (int b = 1 + get_global_id(0) * per_item, b_end = min(b + per_item, nbricks + 1);
         b < b_end; ++b) {
        const int s = src[b], d = dir[b];
        if (d < 0) {
            for (int c = 0; c < NC; ++c)
                for (int l = 0; l < BV; ++l) out[c * plane + b * BV + l] = old[c * old_plane + s * BV + l];
            continue;
        }
        const int ddx = d % 3 - 1, ddy = (d / 3) % 3 - 1, ddz = d / 9 - 1;
        FOR_EACH_BRICK_CELL(l, x, y, z) {
            const int fx = ddx > 0 ? BX - 1 : (ddx < 0 ? 0 : x);
            const int fy = ddy > 0 ? BY - 1 : (ddy < 0 ? 0 : y);
            const int fz = ddz > 0 ? BZ - 1 : (ddz < 0 ? 0 : z);
            const int from = s * BV + (fz * BY + fy) * BX + fx;
            out[b * BV + l] = COPYSIGN(far, old[from]);
            for (int c = 1; c < NC; ++c) out[c * plane + b * BV + l] = old[c * old_plane + from];
        }
    }
}
