// Reductions over the interior of a padded field in two passes: one partial per interior
// row and channel on the device (work-item (0, y, c), a loop along the row), then either
// the host or one work-item per channel adds a channel's row partials. Include after
// common.h.
#ifndef CLPDE_REDUCE_H
#define CLPDE_REDUCE_H

// First in a row-sum kernel's body: lets the row's sums be reordered, or their fixed order
// keeps PoCL's loop vectoriser from widening the loop (about 3x slower). Maxima and minima
// use MAX_SEL / MIN_SEL, plain selects (fmax/fmin/fabs keep those loops scalar on PoCL).
#ifdef CLPDE_POCL
#define REASSOCIATE_SUMS _Pragma("clang fp reassociate(on)")
#else
#define REASSOCIATE_SUMS
#endif
#define MAX_SEL(p, q) ((q) > (p) ? (q) : (p))
#define MIN_SEL(p, q) ((q) < (p) ? (q) : (p))

// The interior row y of channel get_global_id(2) that work-item (0, y, c) reduces, and the
// padded index `row` of its first cell (GRID_ARGS names); items past the last row return.
#define ROW_OF_ITEM(y, row)                                                           \
    const int y = get_global_id(1);                                                   \
    if (y >= ny) return;                                                              \
    const int row = get_global_id(2) * plane + (y + G) * sx + G

// The second pass on the device: the sum of `n` partials starting at `partial`, in order
// (row partials here; also box_lists.h's per-item partials and surface/flows.cl's chunk sums).
inline REAL sum_rows(__global const REAL* restrict partial, const int n)
{
    REAL acc = 0;
    for (int y = 0; y < n; ++y) acc += partial[y];
    return acc;
}

#endif
