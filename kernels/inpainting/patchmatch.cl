// Patch-based (exemplar) inpainting: PatchMatch nearest-neighbour fields and patch votes.
//
// Everything works on one box around a hole, stored without ghosts: an image of NCH planes
// (colour channels, then texture features) of W x H pixels, x fastest. A pixel is a
// "target" when its PATCH x PATCH patch overlaps the hole; a pixel is a legal "source" when
// its whole patch lies inside the box and in the known part (the host builds that mask, so
// a source never reads a hole pixel and the vote can write the hole in place).
//
// The nearest-neighbour field (NNF) holds, per pixel, the source centre (x, y) as an int2.
// One PatchMatch pass, for each target in parallel, reads the previous field and writes the
// next (ping-pong): it rescores its current source (first pass after a vote), tries the sources
// its four neighbours at distance `jump` point to, shifted back by that distance (jump
// flooding: the host runs jumps 4, 2, 1, so good offsets cross a patch in one pass), then a
// random search around its best with radius halving from `radius` to 1 (none when radius is
// 0: the host searches in the first pass of an iteration only). The random numbers
// come from a hash of (seed, pass, pixel, trial): results depend only on the seed.
//
// Patch distance: the mean over the patch pixels inside the box of
//     sum_c w_c (I_c(p + o) - I_c(s + o))^2,
// w_c = 1 for colour, the feature weight for feature planes, the guide weight for guides. With `masked` set, only
// patch pixels whose `use` flag is set count (the onion-peel start at the coarsest level,
// where the hole has no values yet); otherwise every in-box pixel counts, and the sum stops
// early once it exceeds the best distance so far.

#include "common.h"

#ifndef PATCH
#define PATCH 7
#endif
#define PR (PATCH / 2)
#ifndef NCH_MAX
#define NCH_MAX 8
#endif

inline uint hash_u32(uint x)
{
    // A 32-bit integer mix (lowbias32): cheap, with good avalanche.
    x ^= x >> 16;
    x *= 0x7feb352dU;
    x ^= x >> 15;
    x *= 0x846ca68bU;
    x ^= x >> 16;
    return x;
}

inline REAL patch_distance(const __global REAL* img, const __global uchar* use, const int masked,
                           const int W, const int H, const int nch, const __global REAL* chw,
                           const int px, const int py, const int sx, const int sy,
                           const REAL bound)
{
    const int plane = W * H;
    const int ox0 = max(-PR, -px), ox1 = min(PR, W - 1 - px);
    const int oy0 = max(-PR, -py), oy1 = min(PR, H - 1 - py);
    REAL sum = 0;
    if (!masked) {
        const REAL limit = bound * (REAL)((ox1 - ox0 + 1) * (oy1 - oy0 + 1));
        // A row that lies wholly inside takes a loop of constant bounds (unrolled once
        // compiled); the sums are taken in the same order, so the distance is the same.
        const int full = ox0 == -PR && ox1 == PR;
        for (int oy = oy0; oy <= oy1; ++oy) {
            const int tp = (py + oy) * W + px;
            const int sp = (sy + oy) * W + sx;
            for (int c = 0; c < nch; ++c) {
                const __global REAL* a = img + c * plane + tp;
                const __global REAL* b = img + c * plane + sp;
                REAL row = 0;
                if (full) {
                    for (int ox = -PR; ox <= PR; ++ox) {
                        const REAL d = a[ox] - b[ox];
                        row += d * d;
                    }
                } else {
                    for (int ox = ox0; ox <= ox1; ++ox) {
                        const REAL d = a[ox] - b[ox];
                        row += d * d;
                    }
                }
                sum += chw[c] * row;
            }
            if (sum > limit) return INFINITY;
        }
        return sum / (REAL)((ox1 - ox0 + 1) * (oy1 - oy0 + 1));
    }
    // Only the `use` pixels count (the onion peel). A product instead of a branch per pixel
    // keeps the loop vectorisable, and the sum can still stop early: the mean over the n <=
    // full used pixels is at least sum / full, so sum > bound * full means a worse patch.
    const REAL limit = bound * (REAL)((ox1 - ox0 + 1) * (oy1 - oy0 + 1));
    int n = 0;
    for (int oy = oy0; oy <= oy1; ++oy) {
        const int tp = (py + oy) * W + px;
        const int sp = (sy + oy) * W + sx;
        for (int ox = ox0; ox <= ox1; ++ox) n += use[tp + ox];
        for (int c = 0; c < nch; ++c) {
            const __global REAL* a = img + c * plane + tp;
            const __global REAL* b = img + c * plane + sp;
            REAL row = 0;
            for (int ox = ox0; ox <= ox1; ++ox) {
                const REAL d = a[ox] - b[ox];
                row += (REAL)use[tp + ox] * d * d;
            }
            sum += chw[c] * row;
        }
        if (sum > limit) return INFINITY;
    }
    return n ? sum / (REAL)n : INFINITY;
}

// Distance of each target's current source (after a vote changed the image).
__kernel void patchmatch_score(const __global REAL* img, const __global uchar* use, const int masked,
                       const __global int2* nnf, __global REAL* dist,
                       const __global int* targets, const int ntargets,
                       const int W, const int H, const int nch, const __global REAL* chw)
{
    const int k = get_global_id(0);
    if (k >= ntargets) return;
    const int t = targets[k];
    const int2 s = nnf[t];
    dist[t] = patch_distance(img, use, masked, W, H, nch, chw, t % W, t / W, s.x, s.y, INFINITY);
}

__kernel void patchmatch_pass(const __global REAL* img, const __global uchar* use, const int masked,
                      const __global uchar* valid,
                      const __global int2* nnf_in, __global int2* nnf_out, __global REAL* dist,
                      const __global int* targets, const int ntargets,
                      const int W, const int H, const int nch, const __global REAL* chw,
                      const int jump, const int radius, const uint seed, const uint pass,
                      const int rescore)
{
    const int k = get_global_id(0);
    if (k >= ntargets) return;
    const int t = targets[k];
    const int px = t % W, py = t / W;
    int2 best = nnf_in[t];
    // The first pass after a vote rescores the current source; later ones trust dist.
    REAL bd = rescore ? patch_distance(img, use, masked, W, H, nch, chw, px, py, best.x, best.y,
                                       INFINITY)
                      : dist[t];

    const int dx[4] = {-1, 1, 0, 0};
    const int dy[4] = {0, 0, -1, 1};
    for (int d = 0; d < 4; ++d) {
        const int qx = px + dx[d] * jump, qy = py + dy[d] * jump;
        if (qx < 0 || qx >= W || qy < 0 || qy >= H) continue;
        const int2 q = nnf_in[qy * W + qx];
        const int sx = q.x - dx[d] * jump, sy = q.y - dy[d] * jump;
        if (sx < 0 || sx >= W || sy < 0 || sy >= H || !valid[sy * W + sx]) continue;
        if (sx == best.x && sy == best.y) continue;
        const REAL dd = patch_distance(img, use, masked, W, H, nch, chw, px, py, sx, sy, bd);
        if (dd < bd) { bd = dd; best = (int2)(sx, sy); }
    }

    uint state = hash_u32(seed ^ hash_u32(pass * 0x9e3779b9U ^ hash_u32((uint)t)));
    for (int r = radius; r >= 1; r >>= 1) {
        state = hash_u32(state);
        const int rx = (int)(state % (uint)(2 * r + 1)) - r;
        state = hash_u32(state);
        const int ry = (int)(state % (uint)(2 * r + 1)) - r;
        const int sx = clamp(best.x + rx, PR, W - 1 - PR);
        const int sy = clamp(best.y + ry, PR, H - 1 - PR);
        if (!valid[sy * W + sx] || (sx == best.x && sy == best.y)) continue;
        const REAL dd = patch_distance(img, use, masked, W, H, nch, chw, px, py, sx, sy, bd);
        if (dd < bd) { bd = dd; best = (int2)(sx, sy); }
    }
    nnf_out[t] = best;
    dist[t] = bd;
}

// New values of the hole pixels from the patches that cover them. Each covering target q
// (every pixel within PR of a hole pixel is a target) proposes the value its source patch
// has at the same offset, with weight exp(-dist(q) / (2 sigma2) - pen(q)); pen(q) is the
// target's depth into the hole times log(gamma) (Wexler et al.'s confidence gamma^-depth: a
// patch centred near the known border is more trustworthy than one deep in the hole).
// `best_only` takes the single proposal of the largest weight instead (sharper, for the last
// vote). Sources lie in the known part, so the hole can be written in place. Only the first
// `nout` planes are written: planes after them are guides, known everywhere, that only enter
// the distance.
__kernel void patchmatch_vote(__global REAL* img, const __global int2* nnf, const __global REAL* dist,
                      const __global REAL* pen,
                      const __global int* holes, const int nholes, const int W, const int H,
                      const int nch, const int nout, const REAL sigma2, const int best_only)
{
    const int k = get_global_id(0);
    if (k >= nholes) return;
    const int p = holes[k];
    const int px = p % W, py = p / W;
    const int plane = W * H;
    const int ox0 = max(-PR, px - (W - 1)), ox1 = min(PR, px);
    const int oy0 = max(-PR, py - (H - 1)), oy1 = min(PR, py);
    const REAL inv = 1 / (2 * sigma2);
    // First the proposal of the largest weight: the weights are taken relative to it, so
    // that they cannot all underflow, and best_only needs nothing more.
    REAL emin = INFINITY;
    int smin = -1;
    for (int oy = oy0; oy <= oy1; ++oy)
        for (int ox = ox0; ox <= ox1; ++ox) {
            const int q = (py - oy) * W + px - ox;
            const REAL eq = dist[q] * inv + pen[q];
            if (eq < emin) {
                emin = eq;
                const int2 s = nnf[q];
                smin = (s.y + oy) * W + s.x + ox;
            }
        }
    if (smin < 0) return;
    if (best_only) {
        for (int c = 0; c < nout; ++c) img[c * plane + p] = img[c * plane + smin];
        return;
    }
    REAL acc[NCH_MAX];
    for (int c = 0; c < nout; ++c) acc[c] = 0;
    REAL wsum = 0;
    for (int oy = oy0; oy <= oy1; ++oy)
        for (int ox = ox0; ox <= ox1; ++ox) {
            const int q = (py - oy) * W + px - ox;
            const REAL dq = dist[q];
            if (!isfinite(dq)) continue;
            const int2 s = nnf[q];
            const int sp = (s.y + oy) * W + s.x + ox;
            const REAL w = exp(-(dq * inv + pen[q] - emin));
            wsum += w;
            for (int c = 0; c < nout; ++c) acc[c] += w * img[c * plane + sp];
        }
    for (int c = 0; c < nout; ++c) img[c * plane + p] = acc[c] / wsum;
}

// Onion-peel start: each pixel of the current layer takes the centre value of its source.
__kernel void patchmatch_copy_centre(__global REAL* img, const __global int2* nnf,
                             const __global REAL* dist, const __global int* pixels,
                             const int npixels, const int W, const int H, const int nout)
{
    const int k = get_global_id(0);
    if (k >= npixels) return;
    const int p = pixels[k];
    if (!isfinite(dist[p])) return;
    const int2 s = nnf[p];
    const int plane = W * H;
    for (int c = 0; c < nout; ++c) img[c * plane + p] = img[c * plane + s.y * W + s.x];
}

// One half-sweep of iterated conditional modes over the offsets (the coherence step before
// the last vote): each target of the given parity ((x + y) % 2) takes, among its own source
// and the sources its eight neighbours' offsets give it, the one of least
//     dist * factor^-agree,
// agree the number of the eight neighbours with that offset. A pixel thus follows its
// neighbours when their offset is within a small factor as good as its own: copied regions
// grow and their seams become fewer (counting four neighbours only, a line one pixel wide
// that agrees along itself never moves). Targets of one parity are updated in place from
// the other's field and their own; a diagonal neighbour has the same parity, so its value
// is read from the field before this half-sweep (a copy, nnf_in), and the result is the
// same on every run.
__kernel void patchmatch_coherence(const __global REAL* img, const __global uchar* valid,
                           const __global int2* nnf_in, __global int2* nnf,
                           __global REAL* dist, const __global int* targets,
                           const int ntargets, const int W, const int H, const int nch,
                           const __global REAL* chw, const int parity, const REAL factor)
{
    const int k = get_global_id(0);
    if (k >= ntargets) return;
    const int t = targets[k];
    const int px = t % W, py = t / W;
    if (((px + py) & 1) != parity) return;
    int2 off[8];
    int has[8];
    int n = 0;
    for (int oy = -1; oy <= 1; ++oy)
        for (int ox = -1; ox <= 1; ++ox) {
            if (!ox && !oy) continue;
            const int qx = px + ox, qy = py + oy;
            has[n] = qx >= 0 && qx < W && qy >= 0 && qy < H;
            off[n] = has[n] ? nnf_in[qy * W + qx] - (int2)(qx, qy) : (int2)(0, 0);
            ++n;
        }
    int2 best = nnf_in[t];
    const int2 own = best - (int2)(px, py);
    REAL bd = dist[t];
    int agree = 0;
    for (int d = 0; d < 8; ++d) agree += has[d] && off[d].x == own.x && off[d].y == own.y;
    REAL be = bd / pown(factor, agree);
    for (int d = 0; d < 8; ++d) {
        if (!has[d] || (off[d].x == own.x && off[d].y == own.y)) continue;
        int seen = 0, c = 0;
        for (int e = 0; e < 8; ++e) {
            const int same = has[e] && off[e].x == off[d].x && off[e].y == off[d].y;
            seen |= same && e < d;
            c += same;
        }
        if (seen) continue;  // this offset was tried already
        const int sx = px + off[d].x, sy = py + off[d].y;
        if (sx < 0 || sx >= W || sy < 0 || sy >= H || !valid[sy * W + sx]) continue;
        const REAL scale = pown(factor, c);
        const REAL dd = patch_distance(img, valid, 0, W, H, nch, chw, px, py, sx, sy,
                                       be * scale);
        if (dd / scale < be) { be = dd / scale; bd = dd; best = (int2)(sx, sy); }
    }
    nnf[t] = best;
    dist[t] = bd;
}

// Candidate offsets shared by every target (the lags at which a periodic pattern repeats,
// choose.lattice_offsets): each target tries its pixel plus each offset and takes it when
// its colours (weights `chw_colour`: the texture features are 0 there) match at least as
// well as the current source's (ties go to the lattice, in the order of the list); then
// its distance is rescored with the full weights. A flat patch of a periodic pattern
// matches many phases equally well; the lattice's phase is the one whose neighbours beyond
// the patch are right too, whatever the seed's random search found. Colours only, because
// the features of known pixels next to the hole are means over fewer pixels and do not
// repeat with the pattern. `masked`: only the `use` pixels count, as in pm_pass.
__kernel void patchmatch_offsets(const __global REAL* img, const __global uchar* use, const int masked,
                         const __global uchar* valid, __global int2* nnf, __global REAL* dist,
                         const __global int* targets, const int ntargets,
                         const int W, const int H, const int nch, const __global REAL* chw,
                         const __global REAL* chw_colour,
                         const __global int2* offsets, const int noffsets)
{
    const int k = get_global_id(0);
    if (k >= ntargets) return;
    const int t = targets[k];
    const int px = t % W, py = t / W;
    int2 best = nnf[t];
    REAL bd = patch_distance(img, use, masked, W, H, nch, chw_colour, px, py, best.x, best.y,
                             INFINITY);
    int moved = 0;
    for (int i = 0; i < noffsets; ++i) {
        const int sx = px + offsets[i].x, sy = py + offsets[i].y;
        if (sx < 0 || sx >= W || sy < 0 || sy >= H || !valid[sy * W + sx]) continue;
        const REAL dd = patch_distance(img, use, masked, W, H, nch, chw_colour, px, py, sx, sy,
                                       bd);
        if (dd <= bd) { bd = dd; best = (int2)(sx, sy); moved = 1; }
    }
    if (!moved) return;
    nnf[t] = best;
    dist[t] = patch_distance(img, use, masked, W, H, nch, chw, px, py, best.x, best.y, INFINITY);
}
