// Region tracking on deforming level-set surfaces (thesis section 2.2), in 3D.
//
// One padded volume holds every level set, channel after channel: channel 0 is Phi (the
// surface S is Phi = 0), channels 1.. are the auxiliary functions Phi-hat, one per tracked
// region (the region's boundary is Phi = Phi-hat = 0). Layout (channels, nz + 2G, ny + 2G,
// nx + 2G), x fastest; `sx` is the row stride, `sxy` the slab stride, `plane` (LIST_ARGS)
// the channel stride. All values are in grid units (distances in cells, spacing 1); the
// host converts world speeds. Kernels visit a compacted band list and never test for
// borders: the host keeps the band clear of the volume's edge.
//
// Sign convention: u_t = V |grad u| (godunov.h's upwind norms); Phi is negative inside, so
// V > 0 moves the surface inwards. The host passes V = -beta / h for an outward normal
// speed beta.
#include "common.h"
#include "godunov.h"
#include "reinit.h"
#include "extend.h"
#include "regions/regions.h"

__kernel void regions_speed(__global const REAL* restrict phi, __global const REAL* restrict aux,
                           __global REAL* restrict speed, const REAL scale, const REAL vmax,
                           const int sx, const int sxy, RUN_ARGS)
{
    FOR_EACH_RUN_CELL(i) speed[i] = region_speed_at(phi, aux[i], i, scale, vmax, sx, sxy);
}

// ---- one explicit step of the coupled flows ------------------------------------------------
// Channel 0: Phi <- Phi + dt V |grad Phi|, upwind and slope-limited.
// Channel c > 0: Phi-hat <- Phi-hat + dt V (N_Phi . N_Phi-hat) |grad Phi-hat|: the surface's
// velocity projected on Phi-hat's normal, used on the whole band (the thesis' extension),
// with central-difference normals; eps2 keeps them finite where a function is flat.
__kernel void regions_step(__global const REAL* restrict ls, __global const REAL* restrict speed,
                          __global REAL* restrict out, const REAL dt, const REAL eps2,
                          const REAL lo, const REAL hi, const int sx, const int sxy, RUN_ARGS)
{
    FOR_EACH_RUN_CELL(i) {
        const int j = chan + i;
        CENTRAL_GRAD(ls, i, fx, fy, fz);
        CENTRAL_GRAD(ls, j, ux, uy, uz);
        const REAL proj = (fx * ux + fy * uy + fz * uz) *
            RSQRT((fx * fx + fy * fy + fz * fz + eps2) * (ux * ux + uy * uy + uz * uz + eps2));
        // a select, not a branch on the channel, so the loop vectorises (Phi's own is 1)
        const REAL v = speed[i] * band_cutoff(ls[i], lo, hi) * (chan != 0 ? proj : (REAL)1);
        out[j] = ls[j] + dt * v * upwind_norm_3d(ls, j, sx, sxy, v);
    }
}

// One Euler stage of every level set with the speed computed in place, one work-item walking
// whole runs with every channel (launched with one channel): the separate sweeps of
// region_speed, region_step and heun_average read and wrote the speed and a stage buffer
// besides. region_euler: out = ls + dt L(ls); region_heun (Heun's second stage, averaging
// in place): out = (out + ls + dt L(ls)) / 2, where out holds the step's start (read and
// written only at the cell itself, so race-free). Two kernels, not a flag: a select between
// the two stores kept the loop scalar. stats[n * second + g] = max |V| over work-item g's
// cells inside the band (n items), for the host's next stable time step without a sweep of
// its own. Cells where |Phi| >= hi keep their values (band_cutoff is 0 there).
INLINE void region_stage(__global const REAL* restrict ls, __global const REAL* restrict aux,
                         __global REAL* restrict out, __global REAL* restrict stats,
                         const REAL dt, const REAL eps2, const REAL lo, const REAL hi,
                         const REAL scale, const REAL vmax, const int sx, const int sxy,
                         const int second, RUN_ARGS)
{
    // max |V| on the bit patterns: for non-negative floats their order is the integers'
    // order, and an integer maximum keeps the loop vectorisable (a floating-point one,
    // without fast-math, kept it scalar)
    REAL_BITS fastest = 0;
    FOR_EACH_RUN_CELL(i) {
        const REAL speed = region_speed_at(ls, aux[i], i, scale, vmax, sx, sxy);
        // only cells inside the band count (|Phi| < hi): the host may lengthen runs past it
        const REAL_BITS bits = FABS(ls[i]) < hi ? AS_BITS(FABS(speed)) : 0;
        fastest = bits > fastest ? bits : fastest;
        const REAL v0 = speed * band_cutoff(ls[i], lo, hi);
        CENTRAL_GRAD(ls, i, fx, fy, fz);
        const REAL f2 = fx * fx + fy * fy + fz * fz + eps2;
#pragma unroll
        for (int c = 0; c < NC; ++c) {
            const int j = c * plane + i;
            const REAL next = region_next(ls, c, j, v0, fx, fy, fz, f2, eps2, dt, sx, sxy);
            if (second)
                out[j] = (REAL)0.5 * (out[j] + next);
            else
                out[j] = next;
        }
    }
    stats[get_global_size(0) * second + get_global_id(0)] = AS_REAL(fastest);
}

#define REGION_STAGE_ARGS                                                                  \
    __global const REAL* restrict ls, __global const REAL* restrict aux,                   \
        __global REAL* restrict out, __global REAL* restrict stats, const REAL dt,         \
        const REAL eps2, const REAL lo, const REAL hi, const REAL scale, const REAL vmax,  \
        const int sx, const int sxy, RUN_ARGS
#define REGION_STAGE_CALL(second)                                                          \
    region_stage(ls, aux, out, stats, dt, eps2, lo, hi, scale, vmax, sx, sxy, second,     \
                 run_start, run_end, nruns, plane, runs_per_item)
__kernel void regions_euler(REGION_STAGE_ARGS) { REGION_STAGE_CALL(0); }
__kernel void regions_heun(REGION_STAGE_ARGS) { REGION_STAGE_CALL(1); }

// Rigid motion with velocity (ux, uy, uz) (cells per unit time), every channel:
// u <- u - dt U . grad u with slope-limited upwind differences per axis. For Phi-hat this is
// beta-hat |grad Phi-hat| with beta-hat = U . N_Phi-hat: the projection of the surface's full
// velocity (not only its normal part) on Phi-hat's normal.
__kernel void regions_advect_step(__global const REAL* restrict ls, __global REAL* restrict out,
                          const REAL dt, const REAL ux, const REAL uy, const REAL uz,
                          const REAL lo, const REAL hi, const int sx, const int sxy, RUN_ARGS)
{
    FOR_EACH_RUN_CELL(i) {
        const int j = chan + i;
        out[j] = advect_next(ls, j, band_cutoff(ls[i], lo, hi), dt, ux, uy, uz, sx, sxy);
    }
}

// ---- reinitialisation, every channel -------------------------------------------------------
// u_t + S(u0) (|grad u| - 1) = 0 with the slope-limited Godunov norm and Russo and Smereka's
// subcell fix at the cells where u0 changes sign towards one of their 6 neighbours (reinit.h's
// reinit_update_3d), so the zero level set stays where it is. Their |grad u0| leans on the
// central estimate (SUBCELL_STEEP = 1/2 of the steepest one-sided slope at most): on a signed
// distance the central one is 1 up to O(h^2 / R^2), so repeated reinitialisations (every few
// steps) leave the zero level set in place; Russo-Smereka's max with the one-sided slopes
// (1 + h / 2R on curved surfaces) moved a sphere's radius by 0.4 cells in 40 calls. Half the
// steepest slope still guards against flat central estimates at kinks. Cells whose slope is
// already within SUBCELL_TOL of 1 are kept as they are: the relaxation's O(h^2) bias,
// repeated every few steps, otherwise grows.
// (SUBCELL_TOL and SUBCELL_STEEP: regions.h, which regions/bricks.cl shares.)
#define REINIT3D_UPDATE(u, u0, i, dt)                                                      \
    reinit_update_3d(u, u0, i, sx, sxy, dt, (REAL)SUBCELL_STEEP, (REAL)SUBCELL_TOL)

// Heun's first stage: out = u + dt L(u).
__kernel void regions_reinit3d_step(__global const REAL* restrict u, __global const REAL* restrict u0,
                            __global REAL* restrict out, const REAL dt, const int sx,
                            const int sxy, RUN_ARGS)
{
    FOR_EACH_RUN_CELL(cell) {
        const int i = chan + cell;
        out[i] = REINIT3D_UPDATE(u, u0, i, dt);
    }
}

// Heun's second stage and average in one sweep: acc <- (acc + stage1 + dt L(stage1)) / 2,
// where stage1 = acc + dt L(acc) (reinit3d_step). acc is read and written only at the cell
// itself, so the update in place is race-free; fusing saved the averaging sweep and its
// buffer (one read of three volumes per iteration instead of two sweeps).
__kernel void regions_reinit3d_heun(__global REAL* restrict acc, __global const REAL* restrict stage1,
                            __global const REAL* restrict u0, const REAL dt, const int sx,
                            const int sxy, RUN_ARGS)
{
    FOR_EACH_RUN_CELL(cell) {
        const int i = chan + cell;
        acc[i] = (REAL)0.5 * (acc[i] + REINIT3D_UPDATE(stage1, u0, i, dt));
    }
}

// The same two stages from the targets of reinit3d_targets (reinit.h's subcell_target_3d,
// computed once per reinitialisation into `target`, every channel): bit for bit the same
// results as reinit3d_step and reinit3d_heun, with a third less work per sweep.
// `inband` (one byte per cell, nonzero on the band) lets the runs be lengthened to whole
// vectors like the step's: a cell outside the band gets the target -INFINITY, so both
// stages keep its value (reinit3d_heun_pre's average of two equal values is exact), and
// its stale neighbours are never used (at 256^3 a sweep took about 2/3 of the time).
__kernel void regions_reinit3d_targets(__global const REAL* restrict u0,
                               __global const uchar* restrict inband,
                               __global REAL* restrict target, const int sx, const int sxy,
                               RUN_ARGS)
{
    FOR_EACH_RUN_CELL(cell) {
        const int i = chan + cell;
        const REAL t = subcell_target_3d(u0, i, sx, sxy, (REAL)SUBCELL_STEEP, (REAL)SUBCELL_TOL);
        target[i] = inband[cell] ? t : (REAL)-INFINITY;
    }
}

__kernel void regions_reinit3d_step_pre(__global const REAL* restrict u, __global const REAL* restrict u0,
                                __global const REAL* restrict target, __global REAL* restrict out,
                                const REAL dt, const int sx, const int sxy, RUN_ARGS)
{
    FOR_EACH_RUN_CELL(cell) {
        const int i = chan + cell;
        out[i] = reinit_update_target(u, u0, target, i, sx, sxy, dt);
    }
}

__kernel void regions_reinit3d_heun_pre(__global REAL* restrict acc, __global const REAL* restrict stage1,
                                __global const REAL* restrict u0,
                                __global const REAL* restrict target, const REAL dt,
                                const int sx, const int sxy, RUN_ARGS)
{
    FOR_EACH_RUN_CELL(cell) {
        const int i = chan + cell;
        acc[i] = (REAL)0.5 * (acc[i] + reinit_update_target(stage1, u0, target, i, sx, sxy, dt));
    }
}

// ---- band safety ---------------------------------------------------------------------------
// flag[0] = 1 when a band cell lies within `margin` cells of the interior's border (the host
// then stops: the surface grew out of its volume).
__kernel void regions_band_near_border(__global int* restrict flag, const int nx, const int ny,
                               const int nz, const int G, const int margin, const int sx,
                               const int sxy, LIST_ARGS)
{
    LIST_RANGE(k0, k1, chan);
    int hit = 0;
    for (int k = k0; k < k1; ++k) {
        const int i = list[k];
        const int z = i / sxy - G, y = (i % sxy) / sx - G, x = i % sx - G;
        hit |= (x < margin) | (y < margin) | (z < margin) | (x >= nx - margin) |
               (y >= ny - margin) | (z >= nz - margin);
    }
    if (hit) flag[0] = 1;  // every writer stores the same value
}

// out[g] = max |v| over the band cells of work-item g (the host takes the maximum of these
// few values: the largest speed, for the next stable time step).
__kernel void regions_band_max_abs(__global const REAL* restrict v, __global REAL* restrict out,
                           LIST_ARGS)
{
    LIST_RANGE(k0, k1, chan);
    REAL m = 0;
    for (int k = k0; k < k1; ++k) m = FMAX(m, FABS(v[chan + list[k]]));
    out[get_global_id(0)] = m;
}

// Heun's (TVD Runge-Kutta 2) last stage, every channel: out = (u + stage2) / 2, where
// stage2 is two Euler steps from u. Plain Euler with the slope-limited differences slowly
// sharpens convex level sets (a translated sphere grew; docs/regions.md); Heun does not.
__kernel void regions_heun_average(__global const REAL* restrict u, __global const REAL* restrict stage2,
                           __global REAL* restrict out, RUN_ARGS)
{
    FOR_EACH_RUN_CELL(i) {
        const int j = chan + i;
        out[j] = (REAL)0.5 * (u[j] + stage2[j]);
    }
}

// dst = src on the band's cells, every channel. The host keeps its work buffers equal to
// the level sets outside the band (every write lands in the band), so syncing the band
// replaces copies of whole volumes (at 256^3 a volume copy cost as much as 2 Heun steps).
__kernel void regions_copy_runs(__global const REAL* restrict src, __global REAL* restrict dst, RUN_ARGS)
{
    FOR_EACH_RUN_CELL(i) {
        const int j = chan + i;
        dst[j] = src[j];
    }
}

// mask[i] = 1 where |Phi| < width on the interior cells (Phi: channel 0). Work-item (y, z)
// of the interior walks one row. (The same test as surface.cl's band_mask, kept here so
// this file builds on its own.)
__kernel void regions_band_mask(__global const REAL* restrict phi, __global uchar* restrict mask,
                               const REAL width, const int nx, const int ny, const int nz,
                               const int sx, const int sxy, const int G)
{
    const int y = get_global_id(0), z = get_global_id(1);
    if (y >= ny || z >= nz) return;
    const int row = (z + G) * sxy + (y + G) * sx + G;
    for (int x = 0; x < nx; ++x) mask[row + x] = FABS(phi[row + x]) < width;
}

// dst = 1 where src is nonzero within `reach` cells along one axis (offset `stride`):
// three passes (x, y, z) dilate a band mask by a cube. The reinitialisation band is the
// step band dilated this way, not a wider |Phi| test: a cell that was outside every band
// holds a stale value, possibly far too large, and a value test would keep it out (and
// frozen) while the surface sweeps past it. reach <= G, so reads stay in the buffer (ghost
// entries of the masks are 0).
__kernel void regions_dilate_mask(__global const uchar* restrict src, __global uchar* restrict dst,
                          const int stride, const int reach, const int nx, const int ny,
                          const int nz, const int sx, const int sxy, const int G)
{
    const int y = get_global_id(0), z = get_global_id(1);
    if (y >= ny || z >= nz) return;
    const int row = (z + G) * sxy + (y + G) * sx + G;
    // one pass along the row per offset: the loops over x vectorise (src holds 0 or 1)
    for (int x = 0; x < nx; ++x) dst[row + x] = src[row + x - reach * stride];
    for (int d = 1 - reach; d <= reach; ++d)
        for (int x = 0; x < nx; ++x) dst[row + x] |= src[row + x + d * stride];
}

// Extension of the Phi-hat along the surface's normals (channels 1.., launched with one
// channel fewer): u_t + sign(Phi) N_Phi . grad u = 0, first-order upwind, weighted by
// 1 - band_cutoff(Phi, lo, hi), so it leaves the cells with |Phi| < lo alone (the host
// passes lo = 0.8, hi = 1.5 cells: the cells that fix Phi-hat on the surface are kept).
// Cells that enter the band as the surface moves hold stale Phi-hat values (from the start,
// or from when they last left the band); the reinitialisation keeps every sign, so a stale
// zero would stay and meet the surface when it arrives (an expanding sphere's cap grew that
// way). Extension replaces them by values carried out from the surface, and keeps Phi-hat
// meeting the surface at right angles (a tilted Phi-hat, bent by the band's faded edges,
// let a cap's boundary drift with the surface's motion; docs/regions.md).
// Cells where `inband` is 0 (the runs' whole-vector padding) keep their values.
__kernel void regions_extend_outer(__global const REAL* restrict ls,
                           __global const uchar* restrict inband, __global REAL* restrict out,
                           const REAL dt, const REAL lo, const REAL hi, const int sx,
                           const int sxy, RUN_ARGS)
{
    FOR_EACH_RUN_CELL(i) {
        const int j = chan + plane + i;
        REAL ax, ay, az;
        const REAL w = extend_velocity(ls, i, lo, hi, sx, sxy, &ax, &ay, &az);
        const REAL c = ls[j];
        const REAL du = upwind_transport(ls, j, sx, sxy, ax, ay, az);
        out[j] = inband[i] ? c - dt * w * du : c;
    }
}
