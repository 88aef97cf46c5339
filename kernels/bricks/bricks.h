// Dense bricks of a narrow band (clpde/bricks.py), shared by bricks.cl (the
// surface flows) and regions/bricks.cl (region tracking): the brick size, the launch
// geometry, the tiles a kernel copies a brick and its neighbours' faces into, and the loops
// over bricks and their cells. A brick holds BX x BY x BZ cells (BV in all), x fastest; a
// quantity is one buffer (channels, nbricks + 2, BV); brick 0 stands for every brick place
// not stored. Include after common.h.
#ifndef CLPDE_BRICKS_H
#define CLPDE_BRICKS_H

#ifndef BX
#define BX 8
#endif
#ifndef BY
#define BY 4
#endif
#ifndef BZ
#define BZ 4
#endif
#define BV (BX * BY * BZ)
#ifndef GROUP_PER_BRICK
#define GROUP_PER_BRICK 0
#endif

#if GROUP_PER_BRICK
#define TILE __local
#else
#define TILE __private
#endif

// Arguments every brick kernel takes last (BrickBand.launch).
#define BRICK_ARGS __global const int* restrict nbr,                                      \
                   __global const uchar* restrict brick_bits, const int nbricks,         \
                   const int plane, const int per_item

// Tile of halo H around a brick: (BX + 2H) x (BY + 2H) x (BZ + 2H) cells, x fastest.
#define TILE_X(H) (BX + 2 * (H))
#define TILE_XY(H) (TILE_X(H) * (BY + 2 * (H)))
#define TILE_CELLS(H) (TILE_XY(H) * (BZ + 2 * (H)))

// Copy brick b of src and the cells of its neighbours within H of its faces into t. H <= the
// brick's sides, so every tile cell lies in one of the 27 neighbours. On CPUs one work-item
// copies whole rows (three runs: left neighbour, own brick, right neighbour); on GPUs tile
// cell k goes to work-item k % BV.
#if GROUP_PER_BRICK
INLINE void load_tile(TILE REAL* t, __global const REAL* restrict src,
                      __global const int* restrict nbr, const int b, const int H)
{
    const int tx = BX + 2 * H, txy = tx * (BY + 2 * H), n = txy * (BZ + 2 * H);
    __global const int* nb = nbr + 27 * b;
    for (int k = get_local_id(0); k < n; k += BV) {
        const int z = k / txy - H, y = (k / tx) % (BY + 2 * H) - H, x = k % tx - H;
        const int dz = z < 0 ? -1 : (z >= BZ ? 1 : 0);
        const int dy = y < 0 ? -1 : (y >= BY ? 1 : 0);
        const int dx = x < 0 ? -1 : (x >= BX ? 1 : 0);
        const int brick = nb[(dz + 1) * 9 + (dy + 1) * 3 + dx + 1];
        t[k] = src[brick * BV + ((z - dz * BZ) * BY + (y - dy * BY)) * BX + x - dx * BX];
    }
    barrier(CLK_LOCAL_MEM_FENCE);
}
#else
INLINE void load_tile(TILE REAL* t, __global const REAL* restrict src,
                      __global const int* restrict nbr, const int b, const int H)
{
    __global const int* nb = nbr + 27 * b;
    for (int z = -H; z < BZ + H; ++z) {
        const int dz = z < 0 ? -1 : (z >= BZ ? 1 : 0);
        for (int y = -H; y < BY + H; ++y) {
            const int dy = y < 0 ? -1 : (y >= BY ? 1 : 0);
            const int side = (dz + 1) * 9 + (dy + 1) * 3;
            const int row = ((z - dz * BZ) * BY + y - dy * BY) * BX;
            TILE REAL* out = t + ((z + H) * (BY + 2 * H) + y + H) * (BX + 2 * H) + H;
            __global const REAL* left = src + nb[side] * BV + row + BX;
            __global const REAL* mid = src + nb[side + 1] * BV + row;
            __global const REAL* right = src + nb[side + 2] * BV + row - BX;
            for (int x = -H; x < 0; ++x) out[x] = left[x];
            for (int x = 0; x < BX; ++x) out[x] = mid[x];
            for (int x = BX; x < BX + H; ++x) out[x] = right[x];
        }
    }
}
#endif

// The tile index of cell (x, y, z) of the brick.
#define TILE_AT(H, x, y, z) ((((z) + (H)) * (BY + 2 * (H)) + (y) + (H)) * TILE_X(H) + (x) + (H))

// The cells a work-item updates: on CPUs all of the brick's, x innermost (the loop PoCL
// widens); on GPUs its own. Sets l (cell in the brick) and x, y, z (its coordinates).
#if GROUP_PER_BRICK
#define FOR_EACH_BRICK_CELL(l, x, y, z)                                                   \
    for (int l = get_local_id(0), x = l % BX, y = (l / BX) % BY, z = l / (BX * BY);       \
         l == get_local_id(0); ++l)
#else
#define FOR_EACH_BRICK_CELL(l, x, y, z)                                                   \
    for (int z = 0; z < BZ; ++z)                                                          \
        for (int y = 0; y < BY; ++y)                                                      \
            for (int x = 0, l = (z * BY + y) * BX; x < BX; ++x, ++l)
#endif

// The bricks a work-item takes (b), skipping those with no cell carrying `bits` (whole
// work-groups return together on GPUs, before any barrier). Open one block per brick.
#if GROUP_PER_BRICK
#define FOR_EACH_BRICK(b, bits)                                                           \
    const int b = get_group_id(0) + 1;                                                    \
    if (b > nbricks || !(brick_bits[b] & (bits))) return;
#else
#define FOR_EACH_BRICK(b, bits)                                                           \
    for (int b = 1 + get_global_id(0) * per_item, b_end_ = min(b + per_item, nbricks + 1); \
         b < b_end_; ++b)                                                                 \
        if (brick_bits[b] & (bits))
#endif

#endif
