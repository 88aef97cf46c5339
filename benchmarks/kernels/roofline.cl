// Kernels only the benchmarks use (surface_accuracy.py, brick_roofline.py): the bytes a heat
// step must move, with its access pattern and no arithmetic, in both band storages. They are
// no part of the library: the benchmarks build this file by its path, with the runtime's
// include path (kernels/, kernels/common/).
#include "common.h"
#include "bricks/bricks.h"

#define BIT_NODE 1 // a node cell, as in surface/bricks.cl

// ---- the band's own roofline -----------------------------------------------------------------
// v = u + psi over band runs: the bytes a heat step must move (read u and psi, write v) with
// its access pattern and no arithmetic. surface_accuracy.py and brick_roofline.py time it
// beside the steps: what the band's short runs allow, as against a plain copy of one long array.
__kernel void band_copy(__global const REAL* restrict u, __global REAL* restrict v,
                        __global const REAL* restrict psi, RUN_ARGS)
{
    FOR_EACH_RUN_CELL(i) { v[chan + i] = u[chan + i] + psi[i]; }
}

// ---- the bricks' own roofline ------------------------------------------------------------------
// v = u + psi over every cell of the bricks holding a NODE cell: the bytes a heat step must
// move, with no stencil and no tile (brick_roofline.py; built with the bricks' defines).
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
