// Shared definitions for every clpde kernel.
//
// Fields are stored with a ghost layer of G cells on each side, channel planes one after the
// other: layout (channels, ny + 2G, nx + 2G), x fastest. Stencil kernels update interior
// cells only and never test for borders; separate thin kernels (fields.cl) fill the ghosts.
//
// REAL (float or double) is set by the host with -DREAL=...

#ifdef REAL_IS_DOUBLE
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
#endif

#ifndef REAL
#define REAL float
#endif

// Every grid kernel takes these arguments, in this order, after its buffers:
// interior size, row stride, plane stride (one channel), ghost width, cells per work-item.
#define GRID_ARGS const int nx, const int ny, const int sx, const int plane, const int G, \
                  const int xrun

// Loop over the interior cells this work-item owns. Work-item (gx, y, c) walks cells
// [gx*xrun, gx*xrun + xrun) of row y in channel c: on CPUs xrun = nx (one row per item,
// which vectorises), on GPUs xrun = 1 (one cell per item). `i` is the padded linear index.
#define FOR_EACH_CELL(i)                                                              \
    const int row_y_ = get_global_id(1);                                              \
    if (row_y_ >= ny) return;                                                         \
    const int x0_ = get_global_id(0) * xrun;                                          \
    const int x1_ = min(x0_ + xrun, nx);                                              \
    const int row0_ = get_global_id(2) * plane + (row_y_ + G) * sx + G;               \
    for (int i = row0_ + x0_; i < row0_ + x1_; ++i)

// Neumann ghosts written by the step itself, saving the two ghost-fill launches a step
// would otherwise need (on PoCL a launch costs about as much as a 512^2 heat step). Each
// ghost is the mirror image of exactly one interior cell across the border face (the
// layout Field.fill_ghosts makes), so the work-item that wrote that cell also writes its
// mirror images: race-free with any launch geometry. Call after the FOR_EACH_CELL loop:
//     FOR_EACH_CELL(i) { v[i] = ...; }
//     MIRROR_GHOSTS(v);
inline void mirror_cols(__global REAL* v, const int src, const int dst, const int x0,
                        const int x1, const int nx, const int G)
{
    for (int x = x0; x < min(x1, G); ++x) v[dst - 1 - x] = v[src + x];
    for (int x = max(x0, nx - G); x < x1; ++x) v[dst + 2 * nx - 1 - x] = v[src + x];
}

inline void mirror_ghosts(__global REAL* v, const int row0, const int x0, const int x1,
                          const int y, const int nx, const int ny, const int sx, const int G)
{
    mirror_cols(v, row0, row0, x0, x1, nx, G);
    // Rows within G of the top (bottom) border also land in the ghost rows above (below),
    // together with the column ghosts just written.
    for (int pass = 0; pass < 2; ++pass) {
        const int mirrored = pass == 0 ? -1 - y : 2 * ny - 1 - y;
        if (pass == 0 ? y >= G : y < ny - G) continue;
        const int dst = row0 + (mirrored - y) * sx;
        for (int x = x0; x < x1; ++x) v[dst + x] = v[row0 + x];
        mirror_cols(v, row0, dst, x0, x1, nx, G);
    }
}
#define MIRROR_GHOSTS(v) mirror_ghosts(v, row0_, x0_, x1_, row_y_, nx, ny, sx, G)

// The same over a compacted list of padded plane indices: work-item (g, c) takes entries
// [k0, k1) of `list` in channel c, whose plane starts at `chan`. Use as
//     LIST_RANGE(k0, k1, chan);
//     for (int k = k0; k < k1; ++k) { const int i = chan + list[k]; ... }
#define LIST_ARGS __global const int* restrict list, const int nlist, const int plane, \
                  const int run
#define LIST_RANGE(k0, k1, chan)                                                      \
    const int k0 = get_global_id(0) * run;                                            \
    const int k1 = min(k0 + run, nlist);                                              \
    const int chan = get_global_id(1) * plane

// Kernels over the runs of a 3D band (stretches of consecutive band cells along x, built by
// surface/band.cl's band_run_* kernels, clpde.grid3d.BandRuns) take these arguments after
// their own: the runs' cell ranges, their number, the channel stride and runs per work-item.
// On CPUs a work-item walks whole runs, whose cells are consecutive in memory, so the cell
// loop vectorises with contiguous loads (a list's gathers keep it scalar); on GPUs every
// cell is a run of its own. `chan` is the work-item's channel offset, `i` the padded index
// of a cell:
//     FOR_EACH_RUN_CELL(i) { v[chan + i] = ...; }
#define RUN_ARGS __global const int* restrict run_start, __global const int* restrict run_end, \
                 const int nruns, const int plane, const int runs_per_item
#define FOR_EACH_RUN_CELL(i)                                                          \
    const int r0_ = get_global_id(0) * runs_per_item;                                 \
    const int r1_ = min(r0_ + runs_per_item, nruns);                                  \
    const int chan = get_global_id(1) * plane;                                        \
    for (int run_ = r0_; run_ < r1_; ++run_)                                          \
        for (int i = run_start[run_], end_ = run_end[run_]; i < end_; ++i)

#define SQR(a) ((a) * (a))

// PoCL leaves larger inline helpers as calls inside loops, which keeps those loops scalar:
// helpers called from a cell loop are declared INLINE.
#define INLINE inline __attribute__((always_inline))

// PoCL compiles OpenCL's sqrt/rsqrt to library calls that its loop vectoriser cannot
// widen (docs/planar.md has the measured cost); the compiler builtin becomes the vector
// instruction.
// The host defines CLPDE_POCL on PoCL devices.
#if defined(CLPDE_POCL) && defined(REAL_IS_DOUBLE)
#define SQRT(x) __builtin_sqrt(x)
#elif defined(CLPDE_POCL)
#define SQRT(x) __builtin_sqrtf(x)
#else
#define SQRT(x) sqrt(x)
#endif
#define RSQRT(x) ((REAL)1 / SQRT(x))

// fmin, fmax, fabs and copysign are out-of-line calls on PoCL too, and a loop calling them
// stays scalar; plain selects vectorise. (NaN handling differs from fmin/fmax: none is
// expected.)
#if defined(CLPDE_POCL)
#define FABS(a) ((a) < 0 ? -(a) : (a))
#define FMIN(a, b) ((a) < (b) ? (a) : (b))
#define FMAX(a, b) ((a) > (b) ? (a) : (b))
#define COPYSIGN(m, s) ((s) < 0 ? -(m) : (m))
#else
#define FABS(a) fabs(a)
#define FMIN(a, b) fmin(a, b)
#define FMAX(a, b) fmax(a, b)
#define COPYSIGN(m, s) copysign(m, s)
#endif

// Likewise PoCL's exp is an out-of-line call (Perona-Malik's exponential edge-stopping ran
// far slower than the heat step; docs/planar.md). On PoCL, float EXP is computed inline instead: x = k ln2
// + r with |r| <= ln2/2 (k rounded by the 1.5 * 2^23 trick, ln2 split in two for an exact
// k ln2), e^r by its degree-6 Taylor polynomial, 2^k written into the exponent bits. Within
// 3 ulp of exp (relative error < 3e-7) for x in [-87, 88]; beyond, 0 below and e^88 above
// (0 rather than a tiny normal: products with it would be denormals, which x86 computes
// many times slower). Plain arithmetic and selects of plain values only (a select of the
// result itself became a branch), so loops calling it vectorise.
inline float clpde_expf(const float x)
{
    const float xc = x < -87.0f ? -87.0f : (x > 88.0f ? 88.0f : x);
    const float k = (xc * 1.44269504f + 12582912.0f) - 12582912.0f;
    const float r = (xc - k * 0.693145751953125f) - k * 1.428606765330187e-6f;
    const float p = 1.0f + r * (1.0f + r * (0.5f + r * (1.6666667e-1f + r * (4.1666668e-2f +
                    r * (8.3333338e-3f + r * 1.3888889e-3f)))));
    const int scale_bits = x < -87.0f ? 0 : ((int)k + 127) << 23;  // 2^k, or 0.0f
    return p * as_float(scale_bits);
}
#if defined(CLPDE_POCL) && !defined(REAL_IS_DOUBLE)
#define EXP(x) clpde_expf(x)
#else
#define EXP(x) exp(x)
#endif
