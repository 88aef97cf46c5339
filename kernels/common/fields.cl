// Ghost filling, index-list compaction and row-wise reductions for padded fields.
#include "common.h"
#include "reduce.h"

// Ghost columns left and right of every interior row. Neumann (mode 0) mirrors the field
// about the border face, so the normal difference across it is zero; Dirichlet (mode 1)
// sets the ghosts to `value`. Work-item (y, c).
__kernel void fields_fill_ghost_cols(__global REAL* u, const int mode, const REAL value,
                              GRID_ARGS)
{
    const int y = get_global_id(0);
    if (y >= ny) return;
    const int row = get_global_id(1) * plane + (y + G) * sx;
    for (int k = 0; k < G; ++k) {
        u[row + G - 1 - k] = mode ? value : u[row + G + min(k, nx - 1)];
        u[row + G + nx + k] = mode ? value : u[row + G + nx - 1 - min(k, nx - 1)];
    }
}

// Ghost rows above and below, over the whole padded width (corners included); run after
// fill_ghost_cols so corners mirror the already-filled column ghosts. Work-item (x, c).
__kernel void fields_fill_ghost_rows(__global REAL* u, const int mode, const REAL value,
                              GRID_ARGS)
{
    const int x = get_global_id(0);
    if (x >= sx) return;
    const int base = get_global_id(1) * plane + x;
    for (int k = 0; k < G; ++k) {
        u[base + (G - 1 - k) * sx] = mode ? value : u[base + (G + min(k, ny - 1)) * sx];
        u[base + (G + ny + k) * sx] = mode ? value : u[base + (G + ny - 1 - min(k, ny - 1)) * sx];
    }
}

// Copy the interior of `src` into `dst` (same geometry).
__kernel void fields_copy_interior(__global const REAL* restrict src, __global REAL* restrict dst,
                            GRID_ARGS)
{
    FOR_EACH_CELL(i) dst[i] = src[i];
}

// ---- compaction of a mask into a list of flat indices, in three passes ------------------
// The mask is a flat uchar array of n entries cut into chunks of `chunk`; each work-item
// counts one chunk, one work-item turns counts into offsets, then each chunk writes its own
// indices in order. Deterministic, and needs no atomics. The launches are rounded up to
// whole work-groups (Runtime.items): the items past the last chunk return at once.
#define NCHUNKS(n, chunk) max(1, ((n) + (chunk) - 1) / (chunk))

__kernel void fields_count_chunks(__global const uchar* restrict mask, const int n, const int chunk,
                           __global int* restrict counts)
{
    const int c = get_global_id(0);
    if (c >= NCHUNKS(n, chunk)) return;
    const int end = min((c + 1) * chunk, n);
    int total = 0;
    for (int i = c * chunk; i < end; ++i) total += mask[i] != 0;
    counts[c] = total;
}

__kernel void fields_exclusive_scan_serial(__global int* counts, const int nchunks,
                                    __global int* restrict total)
{
    int running = 0;
    for (int c = 0; c < nchunks; ++c) {
        const int here = counts[c];
        counts[c] = running;
        running += here;
    }
    total[0] = running;
}

__kernel void fields_write_chunks(__global const uchar* restrict mask, const int n, const int chunk,
                           __global const int* restrict offsets, __global int* restrict list)
{
    const int c = get_global_id(0);
    if (c >= NCHUNKS(n, chunk)) return;
    const int end = min((c + 1) * chunk, n);
    int out = offsets[c];
    int i = c * chunk;
    // 8 bytes at a time while whole words remain (chunk is a multiple of 8, so the words are
    // aligned): band masks are mostly zeros, and a zero word is skipped with one test
    // instead of eight (the same list, in the same order)
    for (; i + 8 <= end; i += 8) {
        if (*(__global const ulong*)(mask + i) == 0) continue;
        for (int j = i; j < i + 8; ++j)
            if (mask[j]) list[out++] = j;
    }
    for (; i < end; ++i)
        if (mask[i]) list[out++] = i;
}

// ---- reductions: one partial per interior row, combined on the host at check time ------
// op 0: sum a, 1: sum a^2, 2: max |a - b|, 3: sum (a - b)^2, 4: max |a|, 5: min a, 6: max a
__kernel void fields_row_reduce(__global const REAL* restrict a, __global const REAL* restrict b,
                         const int op, __global REAL* restrict partial, GRID_ARGS)
{
    REASSOCIATE_SUMS  // maxima and minima below: MAX_SEL / MIN_SEL (reduce.h)
    ROW_OF_ITEM(y, row);
    REAL acc = (op == 5) ? INFINITY : ((op == 6) ? -INFINITY : 0);
    // One loop per operation: a switch inside the loop would keep it scalar.
    __global const REAL* ra = a + row;
    __global const REAL* rb = b + row;
    if (op == 0)      for (int x = 0; x < nx; ++x) acc += ra[x];
    else if (op == 1) for (int x = 0; x < nx; ++x) acc += SQR(ra[x]);
    else if (op == 2) {  // max |a - b| = max(max(a - b), -min(a - b)): two plain reductions
        REAL lo = 0;
        for (int x = 0; x < nx; ++x) {
            acc = MAX_SEL(acc, ra[x] - rb[x]);
            lo = MIN_SEL(lo, ra[x] - rb[x]);
        }
        acc = MAX_SEL(acc, -lo);
    }
    else if (op == 3) for (int x = 0; x < nx; ++x) acc += SQR(ra[x] - rb[x]);
    else if (op == 4) {
        REAL lo = 0;
        for (int x = 0; x < nx; ++x) {
            acc = MAX_SEL(acc, ra[x]);
            lo = MIN_SEL(lo, ra[x]);
        }
        acc = MAX_SEL(acc, -lo);
    }
    else if (op == 5) for (int x = 0; x < nx; ++x) acc = MIN_SEL(acc, ra[x]);
    else              for (int x = 0; x < nx; ++x) acc = MAX_SEL(acc, ra[x]);
    partial[get_global_id(2) * ny + y] = acc;
}

// Copy the listed cells of `src` into `dst` (every channel); other cells keep their value.
__kernel void fields_copy_listed(__global const REAL* restrict src, __global REAL* restrict dst,
                          LIST_ARGS)
{
    LIST_RANGE(k0, k1, chan);
    for (int k = k0; k < k1; ++k) {
        const int i = chan + list[k];
        dst[i] = src[i];
    }
}
