// A 3D grid's narrow band, once per level set (clpde/grid3d.py, which surfaces and regions
// share): the band's mask and its runs along x. The ground floor's kernels: they include
// only common/ headers.
#include "common.h"

// mask[i] = 1 where |psi| < width on interior cells of the padded volume. Work-item (y, z)
// of the interior walks one row.
__kernel void grid3d_band_mask(__global const REAL* restrict psi, __global uchar* restrict mask,
                        const REAL width, const int nx, const int ny, const int nz,
                        const int sx, const int sxy, const int G)
{
    const int y = get_global_id(0), z = get_global_id(1);
    if (y >= ny || z >= nz) return;
    const int row = (z + G) * sxy + (y + G) * sx + G;
    for (int x = 0; x < nx; ++x) mask[row + x] = FABS(psi[row + x]) < width;
}

// Band runs: maximal stretches of consecutive cells along x in a band list. flags[k] = 1
// where entry k starts a run; the host compacts the flags into run offsets (the positions
// of the run starts in the list).
__kernel void grid3d_band_run_starts(__global const int* restrict list, const int n,
                              __global uchar* restrict flags)
{
    const int k = get_global_id(0);
    if (k >= n) return;
    flags[k] = k == 0 || list[k - 1] != list[k] - 1;
}

// Cell ranges [start, end) of the runs, each lengthened to a multiple of `pad` cells where
// its row's interior and the next run leave room: a vectorised loop then ends without a
// scalar remainder (about as slow per cell as a whole vector). The extra cells' stepped
// values are never read (re-extension reads only the band's nodes).
__kernel void grid3d_band_run_bounds(__global const int* restrict list,
                              __global const int* restrict offsets, const int nruns,
                              const int n, const int pad, const int nx, const int sx,
                              const int G, __global int* restrict start,
                              __global int* restrict end)
{
    const int r = get_global_id(0);
    if (r >= nruns) return;
    const int first = list[offsets[r]];
    const int count = (r + 1 < nruns ? offsets[r + 1] : n) - offsets[r];
    const int row_end = first - first % sx + G + nx;
    int last = min(first + (count + pad - 1) / pad * pad, row_end);
    if (r + 1 < nruns) last = min(last, list[offsets[r + 1]]);
    start[r] = first;
    end[r] = max(last, first + count);
}

// (RUN_ARGS and FOR_EACH_RUN_CELL, the loops over these runs, are in common.h.)
