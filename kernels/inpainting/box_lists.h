// Kernels over index lists of a box around a hole (poisson.cl, navier_stokes.cl).
//
// Fields are plain (channels, ny, nx) arrays with no ghost layer; a list holds flat indices
// y * nx + x of one plane. Work distribution: item g of a launch takes list entries
// k = g*chunk + j*stride, j = 0 .. per-1 (on CPUs a contiguous run: chunk = per,
// stride = 1; on GPUs a strided sweep: chunk = 1, stride = number of items), in channel
// get_global_id(1); reductions write one partial per item and channel
// (partial[c * ng + g]), added up by whoever needs the total: no atomics, and the result
// does not depend on the scheduling.
#ifndef BOX_LISTS_CL
#define BOX_LISTS_CL
#include "common.h"

#define ITEM_ARGS __global const int* restrict list, const int n, const int chunk, \
                  const int stride, const int per, const int ng
#define FOR_ITEMS(k)                                                                   \
    const int g_ = get_global_id(0);                                                  \
    const int c_ = get_global_id(1);                                                  \
    const int chan = c_ * nx * ny;                                                    \
    if (g_ >= ng) return;                                                             \
    int j_ = 0;                                                                       \
    for (int k = g_ * chunk; j_ < per && k < n; ++j_, k += stride)

// Graph Laplacian at flat index i (y * nx + x) of one channel plane starting at `chan`.
INLINE REAL graph_laplacian(__global const REAL* u, const int chan, const int i,
                            const int nx, const int ny)
{
    const int y = i / nx, x = i - y * nx;
    const REAL c = u[chan + i];
    REAL s = 0;
    if (x > 0) s += u[chan + i - 1] - c;
    if (x < nx - 1) s += u[chan + i + 1] - c;
    if (y > 0) s += u[chan + i - nx] - c;
    if (y < ny - 1) s += u[chan + i + nx] - c;
    return s;
}

#endif
