// Kernels only the benchmarks use (benchmarks/surface_accuracy.py).
#include "common.cl"

// ---- the band's own roofline -----------------------------------------------------------------
// v = u + psi over band runs: the bytes a heat step must move (read u and psi, write v) with
// its access pattern and no arithmetic. benchmarks/surface_accuracy.py times it beside the
// steps: what the band's short runs allow, as against a plain copy of one long array.
__kernel void band_copy(__global const REAL* restrict u, __global REAL* restrict v,
                        __global const REAL* restrict psi, RUN_ARGS)
{
    FOR_EACH_RUN_CELL(i) { v[chan + i] = u[chan + i] + psi[i]; }
}
