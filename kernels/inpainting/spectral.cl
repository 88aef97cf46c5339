// Frequency-selective inpainting: each block of the damage is modelled as a sparse sum of
// 2-D Fourier basis functions, fitted greedily to the known pixels of an extended block
// around it, and the block's missing pixels are taken from the model.
//
// One work-group of SPECTRAL_GROUP items fits one block, every channel in turn: group g takes
// blocks[first + g], 7 ints (row, column, B, L, copy, picks, minor picks: those of the
// channels after the first): its B x B pixels from (row, column),
// its extended window L x L (L even, L - B even, L <= SPECTRAL_MAXL), in copy `copy` of the
// image (img: copies x nc planes of ny x nx; wave_of: one plane per copy; the copies are the
// fills on differently offset block grids, averaged afterwards). The blocks of one launch (a
// wave) are independent: no block's window holds pixels that another block of the wave
// writes, so they are written in place into `img`.
//
// Window: the block's B x B pixels in the middle, (L - B) / 2 on each side. A pixel's weight
// is w = s rho^d, d its distance to the window's centre, s = 1 for a known pixel, delta for a
// hole pixel that an earlier wave filled (wave_of[p] < wave), 0 for the rest and outside the
// image. wave_of[p] is -1 for known pixels.
//
// Model: a weighted least-squares plane (detrend = 1: a ramp is not periodic, and a sum of
// Fourier functions would need many terms for it) plus a sum of pairs
// c_k phi_k + conj(c_k) phi_-k, phi_k(x) = exp(2 pi i k.x / L). With the weighted residual's
// transform R(k) = sum_x w (f - g) exp(-2 pi i k.x / L) and the weight's transform W(k), the
// best real pair (k, -k) alone has the coefficient
//     c = (R(k) W(0) - W(2k) conj(R(k))) / (W(0)^2 - |W(2k)|^2)
// and lowers the weighted squared error by 2 Re(conj(c) R(k)); for a self-conjugate k
// (2k = 0 mod L), c = R(k) / W(0) (real) and the reduction R(k)^2 / W(0). Each iteration takes
// the candidate k with the largest reduction times the prior (1 - |k| / |k|max)^alpha, adds
// gamma c (gamma < 1 makes up for the basis functions not being orthogonal under the weights,
// so that later picks can correct earlier ones), and updates R in the frequency domain:
// R(l) -= gamma (c W(l - k) + conj(c) W(l + k)).
// Candidates: the half plane kx in [0, L/2] (R(-l) = conj(R(l)) for a real residual) with
// |k| <= cutoff L / 2; R is only read there, so it is only kept there. W (the whole plane),
// the candidates and their scores' factors depend on the weights alone: once per block.
// The loop stops after the block's most picks (the channels after the first: its minor picks),
// once a pick's reduction falls below `stop` times the first one's, once the weighted squared
// residual E is at most floor2 W(0) (its weighted mean square at most floor^2: the rest is
// finer than the data), or once the best pick's reduction is below `stall` times E (the model
// has stalled: no pair explains much of what is left, which looks like noise). E starts as
// sum w (f - plane)^2 and a step gamma c lowers it by gamma (2 - gamma) times the pick's
// reduction. Each item scores its own candidates as it updates them, so a pick costs one pass
// over the candidates and two barriers.
//
// Work-group shape (the host's work_shape): on GPUs SPECTRAL_GROUP = 64 items share a block's
// candidates, one at a time (SPECTRAL_VW = 1). On CPUs (SPECTRAL_GROUP = 1, SPECTRAL_VW = 8)
// one item walks them in vectors of 8: PoCL runs a work-group's items one after the other,
// and its compiler left the scalar loops unvectorised. There the candidates lie in columns
// (one kx, ky from 0 to L - 1) of whole vectors (spare slots, half_x -1, are updated but
// never scored), W is stored by columns, each continued periodically past L, so that a
// vector's W(l - k) and W(l + k) are 8 consecutive values, and the transforms take 8
// frequencies at a time from twiddle tables. (Columns, not rows: a column of L candidates
// fills whole vectors where L is a multiple of 8, a row's L / 2 + 1 never does; a thin
// fill's 20 px windows hold 264 slots, not 320, its 16 px windows 144, not 256.) Each sum
// runs in the same order as the scalar code's: with as many items, vectors give the scalar
// fill bit for bit (the item count orders the plane's partial sums, a difference of
// rounding).
//
// Local memory: X = (w (f - plane), w | W re, W im, columns WS apart); T = (row transforms, or
// the picks' coefficients | qa, qb, qc, R re, R im on the candidates' slots). With one
// candidate at a time X and T are 31 KB in float, 62 KB in double: more than the 32 KB that
// OpenCL promises (and NVIDIA's 48 KB per kernel). With SPECTRAL_SPILL=1 (chosen by the host
// where the device's local memory is too small) they live in `scratch`, SPECTRAL_SCRATCH REALs
// per work-group of global memory, and the barriers fence global memory too; the arithmetic is
// the same.
#include "common.h"

#define SPECTRAL_MAXL 32    // largest window
#define SPECTRAL_MAXK 512   // most picks per block
#ifndef SPECTRAL_GROUP
#define SPECTRAL_GROUP 64
#endif
// candidates per vector in the picks' update: 8 on CPUs, 1 (one at a time) on GPUs
#ifndef SPECTRAL_VW
#define SPECTRAL_VW 1
#endif
#if SPECTRAL_VW == 8
#define CAT_(a, b) a##b
#define CAT(a, b) CAT_(a, b)
#define REALV CAT(REAL, 8)
#elif SPECTRAL_VW != 1
#error "SPECTRAL_VW must be 1 or 8"
#endif
#define SPECTRAL_MAXH (SPECTRAL_MAXL * (SPECTRAL_MAXL / 2 + 1))  // the half plane's size
// the candidates' slots: the half plane's columns (kx from 0 to L / 2), each rounded up to
// whole vectors
#define SPECTRAL_SLOTS \
    ((SPECTRAL_MAXL / 2 + 1) * ((SPECTRAL_MAXL + SPECTRAL_VW - 1) / SPECTRAL_VW * SPECTRAL_VW))
// W's column stride (W is stored by columns: W(ky, kx) at kx W_STRIDE + ky): with vectors,
// each column goes on past L (W periodic), so that a vector's W(l - k) and W(l + k) are
// SPECTRAL_VW consecutive values
#define W_STRIDE(L) (SPECTRAL_VW > 1 ? 2 * (L) + SPECTRAL_VW : (L))
#define SPECTRAL_XN \
    (2 * SPECTRAL_MAXL * SPECTRAL_MAXL + 2 * SPECTRAL_MAXL * W_STRIDE(SPECTRAL_MAXL))
// T's first part: R's rows on the half plane (with vectors, each rounded up to whole
// vectors), then the picks' coefficients
#define SPECTRAL_T0 \
    (SPECTRAL_VW > 1 ? 2 * SPECTRAL_MAXL * ((SPECTRAL_MAXL / 2 + 8) / 8 * 8) : 2 * SPECTRAL_MAXH)
#define SPECTRAL_TN (SPECTRAL_T0 + 5 * SPECTRAL_SLOTS)
#define SPECTRAL_SCRATCH (SPECTRAL_XN + SPECTRAL_TN)

#ifndef SPECTRAL_SPILL
#define SPECTRAL_SPILL 0
#endif
#if SPECTRAL_SPILL
#define SPACE __global
#define FENCE (CLK_LOCAL_MEM_FENCE | CLK_GLOBAL_MEM_FENCE)
#else
#define SPACE __local
#define FENCE CLK_LOCAL_MEM_FENCE
#endif

#if SPECTRAL_VW > 1
// the lanes' slot indices (the comparisons of two REALVs give this type)
#ifdef REAL_IS_DOUBLE
#define IDXV long8
#else
#define IDXV int8
#endif
#define LANES ((IDXV)(0, 1, 2, 3, 4, 5, 6, 7))
// LOAD8: 8 consecutive REALs at p as a vector, in plain element accesses. PoCL's CPU
// compiler left vload8 (and select and fmax on vectors) as calls into its library, each
// vector spilled to the stack around the call: the kernel took 3.4x its time now. Element
// accesses at consecutive addresses become one unaligned vector load.
#define LOAD8(p) \
    ((REALV)((p)[0], (p)[1], (p)[2], (p)[3], (p)[4], (p)[5], (p)[6], (p)[7]))
// STORE8 stays vstore8: with element stores into local memory, Intel's CPU runtime gave a
// fill that differs from the same kernel's spilled variant (float64: 6e-8 on 4 of 1320
// values, tests/portability/test_limits.py; the spilled one, as before, matched vstore8's);
// the cause was not found. On PoCL element stores were about 1.2x faster per fill.
#define STORE8(v, p) vstore8((v), 0, (p))
// a vector of 8 candidates' residual transform (rr, ri) stored at j0, their scores folded
// into a lane-wise running argmax: top, each lane's largest score, and at, the first slot
// (in the lane) that holds it (a larger score replaces it, an equal one does not). The first
// pass and every update after a pick score alike. A spare slot's score is NaN (its qa),
// which never wins: NaN is greater than nothing.
#define STORE_AND_SCORE(rr, ri, j0, top, at)                                              \
    do {                                                                                  \
        STORE8((rr), rre + (j0));                                                         \
        STORE8((ri), rim + (j0));                                                         \
        const REALV score_ = (LOAD8(qa + (j0)) * (rr) + LOAD8(qb + (j0)) * (ri)) * (rr)   \
                             + LOAD8(qc + (j0)) * (ri) * (ri);                            \
        const IDXV better_ = score_ > (top);                                              \
        (top) = better_ ? score_ : (top);                                                 \
        (at) = better_ ? (IDXV)(j0) + LANES : (at);                                       \
    } while (0)

// (bs, bi): the largest of an item's scores, from its lanes' running argmax (top, at), and
// the first slot that holds it; (-1, 0) where none exceeds -1. The same choice as a running
// argmax over the slots in order (a larger score, or an equal one earlier, wins): each
// lane's first slot of its largest score, then the first of the lanes that reach the
// maximum. (Storing the scores and a pass of its own to find the slot cost a fifth of a
// thin fill's time on PoCL.)
inline void first_best(const REALV top, const IDXV at, REAL* bs, int* bi)
{
    // (ternaries: no NaN reaches top, and PoCL calls its library for fmax and min)
#define HI(a, b) ((a) > (b) ? (a) : (b))
#define LO(a, b) ((a) < (b) ? (a) : (b))
    const REAL m = HI(HI(HI(top.s0, top.s1), HI(top.s2, top.s3)),
                      HI(HI(top.s4, top.s5), HI(top.s6, top.s7)));
    *bs = -1;
    *bi = 0;
    if (!(m > -1)) return;
    const IDXV far = (IDXV)(0x7fffffff);
    const IDXV cand = top == m ? at : far;
    *bs = m;
    *bi = (int)LO(LO(LO(cand.s0, cand.s1), LO(cand.s2, cand.s3)),
                  LO(LO(cand.s4, cand.s5), LO(cand.s6, cand.s7)));
#undef HI
#undef LO
}
#endif

// x^alpha, by multiplication where alpha is a whole number up to 8: pow (and pown) cost as
// much as the rest of a block's set-up on PoCL's CPU device
inline REAL power(const REAL x, const REAL alpha)
{
    if (alpha >= 0 && alpha <= 8 && alpha == (REAL)(int)alpha) {
        REAL p = 1;
        for (int i = 0; i < (int)alpha; ++i) p *= x;
        return p;
    }
    return pow(x, alpha);
}

// x / L, and x mod L in *rest, for 0 <= x < 2 L^2 (L <= SPECTRAL_MAXL) without a division
// (a window's pixels and the model's terms take one each; PoCL's integer division costs
// tens of cycles): the quotient from the float reciprocal inv_l is off by at most one,
// which the two corrections mend (checked for every such x and L)
inline int div_l(const int x, const int L, const float inv_l, int* rest)
{
    int q = (int)((float)x * inv_l), r = x - q * L;
    if (r < 0) {
        r += L;
        --q;
    }
    if (r >= L) {
        r -= L;
        ++q;
    }
    *rest = r;
    return q;
}

__kernel __attribute__((reqd_work_group_size(SPECTRAL_GROUP, 1, 1)))
void spectral_blocks(__global REAL* img, __global const int* wave_of,
                     __global const int* blocks, const int first, const int wave,
                     const int nx, const int ny, const int nc, const REAL rho,
                     const REAL delta, const REAL gamma, const REAL alpha,
                     const REAL stop, const REAL floor2, const REAL stall, const int detrend,
                     const REAL cutoff, __global REAL* scratch)
{
#if SPECTRAL_SPILL
    __global REAL* const X = scratch + (size_t)get_group_id(0) * SPECTRAL_SCRATCH;
    __global REAL* const T = X + SPECTRAL_XN;
#else
    __local REAL X[SPECTRAL_XN];
    __local REAL T[SPECTRAL_TN];
#endif
    __local REAL tw[2 * SPECTRAL_MAXL];  // cos, sin of 2 pi j / L
    __local REAL uv[SPECTRAL_MAXL];      // the plane's coordinate (j - centre) / L
#if SPECTRAL_VW > 1
    __local REAL twc[SPECTRAL_MAXL * SPECTRAL_MAXL], tws[SPECTRAL_MAXL * SPECTRAL_MAXL];
#endif
    __local REAL best[SPECTRAL_GROUP];
    __local int best_at[SPECTRAL_GROUP];
    __local REAL pick_c[2];
    __local int pick_k[2];
    __local short half_y[SPECTRAL_SLOTS], half_x[SPECTRAL_SLOTS];
    __local int picks[SPECTRAL_MAXK];  // ky 64 + kx of each pick (self-conjugate: -1 - that)
    __local REAL sums[9 * SPECTRAL_GROUP];
    __local REAL fit[3];

    const int lid = get_local_id(0);
    const int blk = first + get_group_id(0);
    const int by = blocks[7 * blk], bx = blocks[7 * blk + 1];
    const int B = blocks[7 * blk + 2], L = blocks[7 * blk + 3];
    const int copy = blocks[7 * blk + 4], iterations = blocks[7 * blk + 5];
    const int minor_iterations = blocks[7 * blk + 6];
    __global const int* state = wave_of + (size_t)copy * nx * ny;
    const int LL = L * L;
    const int H = L / 2 + 1;
    const int b = (L - B) / 2;
    const int oy = by - b, ox = bx - b;
    const REAL two_pi_l = (REAL)6.283185307179586 / (REAL)L;
    const REAL centre = (REAL)0.5 * (REAL)(L - 1);
    const REAL log_rho = log(rho);
    const float inv_l = 1.0f / (float)L;
    SPACE REAL* const rows = T;                 // row transforms; then the picks' coefficients
    SPACE REAL* const coef_r = T;
    SPACE REAL* const coef_i = T + SPECTRAL_MAXK;
    SPACE REAL* const qa = T + SPECTRAL_T0;
    SPACE REAL* const qb = qa + SPECTRAL_SLOTS;
    SPACE REAL* const qc = qb + SPECTRAL_SLOTS;
    SPACE REAL* const rre = qc + SPECTRAL_SLOTS;
    SPACE REAL* const rim = rre + SPECTRAL_SLOTS;
    const int WS = W_STRIDE(L);
    SPACE REAL* const wre = X + 2 * LL;  // W, columns WS apart
    SPACE REAL* const wim = wre + L * WS;

    for (int j = lid; j < L; j += SPECTRAL_GROUP) {
        REAL c;
        const REAL s = sincos(two_pi_l * (REAL)j, &c);
        tw[j] = c;
        tw[SPECTRAL_MAXL + j] = s;
        uv[j] = ((REAL)j - centre) / (REAL)L;
    }
#if SPECTRAL_VW > 1
    // the rows' transforms in vectors of 8 frequencies: the twiddles as tables,
    // twc[n CS + k] = cos(2 pi k n / L) (and tws, sin), rows rounded up to whole vectors
    const int CS = (L + 7) / 8 * 8, HS = (H + 7) / 8 * 8;
    barrier(FENCE);
    for (int n = lid; n < L; n += SPECTRAL_GROUP)  // k n mod L by steps of n: no division
        for (int k = 0, t = 0; k < CS; ++k, t = t + n < L ? t + n : t + n - L) {
            twc[n * CS + k] = tw[t];
            tws[n * CS + k] = tw[SPECTRAL_MAXL + t];
        }
#endif
    // rho^d, d the distance to the window's centre, on a quarter of the window (d is
    // symmetric about the centre: the same values for a quarter of the exponentials), in T
    // until W's transform
    const int Q = L / 2;
    for (int i = lid; i < Q * Q; i += SPECTRAL_GROUP) {
        const int a = i / Q, c = i - a * Q;
        const REAL dy = (REAL)(Q + a) - centre, dx = (REAL)(Q + c) - centre;
        T[i] = exp(log_rho * sqrt(dx * dx + dy * dy));
    }
    barrier(FENCE);
    // the weights, X[LL, 2 LL)
    for (int i = lid; i < LL; i += SPECTRAL_GROUP) {
        int n;
        const int m = div_l(i, L, inv_l, &n);
        const int y = oy + m, x = ox + n;
        REAL w = 0;
        if (y >= 0 && y < ny && x >= 0 && x < nx) {
            const int s = state[y * nx + x];
            w = s < 0 ? (REAL)1 : (s < wave ? delta : (REAL)0);
            if (w > 0) {
                const int a = m < Q ? Q - 1 - m : m - Q, c = n < Q ? Q - 1 - n : n - Q;
                w *= T[a * Q + c];
            }
        }
        X[LL + i] = w;
    }
    barrier(FENCE);
    // W: rows (whole plane) into T, then columns into wre, wim
#if SPECTRAL_VW > 1
    // in vectors of 8 frequencies (rows CS apart in T): the same sums, in the same order
    for (int i = lid; i < L * (CS / 8); i += SPECTRAL_GROUP) {
        const int m = i / (CS / 8), k0 = 8 * (i - m * (CS / 8));
        REALV wr = 0, wi = 0;
        for (int n = 0; n < L; ++n) {
            const REAL w = X[LL + m * L + n];
            wr += w * LOAD8(twc + n * CS + k0);
            wi -= w * LOAD8(tws + n * CS + k0);
        }
        STORE8(wr, T + m * CS + k0);
        STORE8(wi, T + L * CS + m * CS + k0);
    }
    barrier(FENCE);
    for (int i = lid; i < L * (CS / 8); i += SPECTRAL_GROUP) {
        const int kx = i / (CS / 8), k0 = 8 * (i - kx * (CS / 8));  // 8 ky from k0
        REALV wr = 0, wi = 0;
        for (int m = 0; m < L; ++m) {
            const REAL a = T[m * CS + kx], b = T[L * CS + m * CS + kx];
            const REALV c = LOAD8(twc + m * CS + k0), s = LOAD8(tws + m * CS + k0);
            wr += a * c + b * s;
            wi += b * c - a * s;
        }
        // lanes past L land in the columns' continuation, written after the next barrier
        STORE8(wr, wre + kx * WS + k0);
        STORE8(wi, wim + kx * WS + k0);
    }
#else
    for (int i = lid; i < LL; i += SPECTRAL_GROUP) {
        const int m = i / L, k = i - m * L;
        REAL wr = 0, wi = 0;
        for (int n = 0, t = 0; n < L; ++n, t = t + k < L ? t + k : t + k - L) {
            const REAL w = X[LL + m * L + n];
            wr += w * tw[t];
            wi -= w * tw[SPECTRAL_MAXL + t];
        }
        T[i] = wr;
        T[LL + i] = wi;
    }
    barrier(FENCE);
    for (int i = lid; i < LL; i += SPECTRAL_GROUP) {
        const int ky = i / L, kx = i - ky * L;
        REAL wr = 0, wi = 0;
        for (int m = 0, t = 0; m < L; ++m, t = t + ky < L ? t + ky : t + ky - L) {
            const REAL c = tw[t], s = tw[SPECTRAL_MAXL + t];
            const int q = m * L + kx;
            wr += T[q] * c + T[LL + q] * s;
            wi += T[LL + q] * c - T[q] * s;
        }
        wre[kx * WS + ky] = wr;
        wim[kx * WS + ky] = wi;
    }
#endif
    // the candidates (|k| <= limit), column by column: kx from 0 to L / 2, ky from 0 to
    // L - 1. With vectors each column is rounded up to whole vectors, and its slots past L or
    // out of the disc are spare (half_x -1, never scored); without, they are left out.
    if (lid == 0) {
        const REAL limit = cutoff * (REAL)0.5 * (REAL)L;
        const int CL = (L + SPECTRAL_VW - 1) / SPECTRAL_VW * SPECTRAL_VW;
        int count_h = 0;
        for (int kx = 0; kx < H && (REAL)(kx * kx) <= limit * limit; ++kx) {
            for (int ky = 0; ky < CL; ++ky) {
                const int fy = ky <= L / 2 ? ky : ky - L;
                const bool in = ky < L && (REAL)(fy * fy + kx * kx) <= limit * limit;
                if (SPECTRAL_VW == 1 && !in) continue;
                half_y[count_h] = (short)ky;
                half_x[count_h] = (short)(in ? kx : -1);
                ++count_h;
            }
        }
        pick_k[0] = count_h;
    }
    barrier(FENCE);
#if SPECTRAL_VW > 1
    // W's columns continued past L, periodically (read by the picks' update only)
    for (int y = lid; y < L; y += SPECTRAL_GROUP)
        for (int x = L; x < WS; ++x) {  // (x - L: itself an original or continued value)
            wre[y * WS + x] = wre[y * WS + x - L];
            wim[y * WS + x] = wim[y * WS + x - L];
        }
#endif
    const int NC = pick_k[0];
    const REAL W0 = wre[0];
    // each candidate's score is qa R_re^2 + qb R_re R_im + qc R_im^2: the pair's error
    // reduction times the prior
    const REAL inv_kmax = (REAL)1 / ((REAL)0.5 * (REAL)L * sqrt((REAL)2));
    for (int j = lid; j < NC; j += SPECTRAL_GROUP) {
        const int ky = half_y[j], kx = half_x[j];
        const REAL fy = (REAL)(ky <= L / 2 ? ky : ky - L);
        const REAL nu = fmin(sqrt(fy * fy + (REAL)(kx * kx)) * inv_kmax, (REAL)1);
        const REAL prior = alpha == 0 ? (REAL)1 : power((REAL)1 - nu, alpha);
        const int k2y = 2 * ky < L ? 2 * ky : 2 * ky - L, k2x = 2 * kx < L ? 2 * kx : 2 * kx - L;
        if (kx < 0) {  // a vector's spare slot: its score NaN, never the best
            qa[j] = (REAL)NAN;
            qb[j] = qc[j] = 0;
        } else if (!(W0 > 0)) {
            qa[j] = qb[j] = qc[j] = 0;
        } else if (k2y == 0 && k2x == 0) {  // self-conjugate: one real coefficient
            qa[j] = prior / W0;
            qb[j] = qc[j] = 0;
        } else {
            const REAL vr = wre[k2x * WS + k2y], vi = wim[k2x * WS + k2y];
            const REAL den = fmax(W0 * W0 - (vr * vr + vi * vi), (REAL)1e-3 * W0 * W0);
            const REAL pd = prior / den;
            qa[j] = 2 * (W0 - vr) * pd;
            qb[j] = -4 * vi * pd;
            qc[j] = 2 * (W0 + vr) * pd;
        }
    }

    for (int ch = 0; ch < nc; ++ch) {
        __global REAL* plane = img + ((size_t)copy * nc + ch) * nx * ny;
        // the plane through the window: weighted least squares, u and v the centred
        // coordinates over L
        REAL acc[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};  // w, wu, wv, wuu, wuv, wvv, wf, wfu, wfv
        for (int i = lid; i < LL; i += SPECTRAL_GROUP) {
            const REAL w = X[LL + i];
            int n;
            const int m = div_l(i, L, inv_l, &n);
            const REAL f = w > 0 ? plane[(oy + m) * nx + ox + n] : (REAL)0;
            const REAL u = uv[m], v = uv[n];
            const REAL wf = w * f;
            acc[0] += w; acc[1] += w * u; acc[2] += w * v;
            acc[3] += w * u * u; acc[4] += w * u * v; acc[5] += w * v * v;
            acc[6] += wf; acc[7] += wf * u; acc[8] += wf * v;
            X[i] = f;
        }
        for (int q = 0; q < 9; ++q) sums[q * SPECTRAL_GROUP + lid] = acc[q];
        barrier(FENCE);  // also: the last channel's picks are no longer read
        if (lid == 0) {
            REAL t[9];
            for (int q = 0; q < 9; ++q) {
                REAL a = 0;
                for (int j = 0; j < SPECTRAL_GROUP; ++j) a += sums[q * SPECTRAL_GROUP + j];
                t[q] = a;
            }
            // normal equations for (c0, cu, cv); a small ridge on the slopes keeps windows
            // whose known pixels lie on a line solvable
            const REAL ridge = (REAL)1e-3 * t[0];
            const REAL a00 = t[0], a01 = t[1], a02 = t[2];
            const REAL a11 = t[3] + ridge, a12 = t[4], a22 = t[5] + ridge;
            const REAL c0 = a11 * a22 - a12 * a12, c1 = a02 * a12 - a01 * a22;
            const REAL c2 = a01 * a12 - a02 * a11;
            const REAL det = a00 * c0 + a01 * c1 + a02 * c2;
            if (detrend && t[0] > 0 && det > 0) {
                const REAL b0 = t[6], b1 = t[7], b2 = t[8];
                const REAL d11 = a00 * a22 - a02 * a02, d12 = a01 * a02 - a00 * a12;
                const REAL d22 = a00 * a11 - a01 * a01;
                fit[0] = (c0 * b0 + c1 * b1 + c2 * b2) / det;
                fit[1] = (c1 * b0 + d11 * b1 + d12 * b2) / det;
                fit[2] = (c2 * b0 + d12 * b1 + d22 * b2) / det;
            } else {
                fit[0] = fit[1] = fit[2] = 0;
            }
        }
        barrier(FENCE);
        REAL e = 0;  // the weighted squared residual w (f - plane)^2 over the window
        for (int i = lid; i < LL; i += SPECTRAL_GROUP) {
            int n;
            const int m = div_l(i, L, inv_l, &n);
            const REAL u = uv[m], v = uv[n];
            const REAL r = X[i] - (fit[0] + fit[1] * u + fit[2] * v);
            const REAL wr = X[LL + i] * r;
            X[i] = wr;
            e += wr * r;
        }
        sums[lid] = e;  // lid 0 read the plane's sums before the barrier above
        barrier(FENCE);
        // R: rows on the half plane into rows, then the candidates' columns
        // each item keeps its candidates' best score (item lid owns j = lid mod GROUP, or with
        // vectors the vectors lid mod GROUP, in the transform, in every pick's update and in
        // the scores, so they need no barrier)
        REAL bs = -1;
        int bi = 0;
#if SPECTRAL_VW > 1
        // in vectors of 8 frequencies (rows HS apart): the same sums, in the same order
        for (int i = lid; i < L * (HS / 8); i += SPECTRAL_GROUP) {
            const int m = i / (HS / 8), k0 = 8 * (i - m * (HS / 8));
            REALV ar = 0, ai = 0;
            for (int n = 0; n < L; ++n) {
                const REAL a = X[m * L + n];
                ar += a * LOAD8(twc + n * CS + k0);
                ai -= a * LOAD8(tws + n * CS + k0);
            }
            STORE8(ar, rows + m * HS + k0);
            STORE8(ai, rows + L * HS + m * HS + k0);
        }
        barrier(FENCE);
        REALV top = -1;
        IDXV at = 0;
        for (int v = lid; v < NC / 8; v += SPECTRAL_GROUP) {
            const int kx = v / (CS / 8), ky = 8 * v - kx * CS, j0 = 8 * v;  // 8 ky from ky
            REALV rr = 0, ri = 0;
            for (int m = 0; m < L; ++m) {
                const REAL ar = rows[m * HS + kx], ai = rows[L * HS + m * HS + kx];
                const REALV c = LOAD8(twc + m * CS + ky), s = LOAD8(tws + m * CS + ky);
                rr += ar * c + ai * s;
                ri += ai * c - ar * s;
            }
            STORE_AND_SCORE(rr, ri, j0, top, at);
        }
        first_best(top, at, &bs, &bi);
#else
        for (int i = lid; i < L * H; i += SPECTRAL_GROUP) {
            const int m = i / H, k = i - m * H;
            REAL ar = 0, ai = 0;
            for (int n = 0, t = 0; n < L; ++n, t = t + k < L ? t + k : t + k - L) {
                const REAL a = X[m * L + n];
                ar += a * tw[t];
                ai -= a * tw[SPECTRAL_MAXL + t];
            }
            rows[i] = ar;
            rows[L * H + i] = ai;
        }
        barrier(FENCE);
        for (int j = lid; j < NC; j += SPECTRAL_GROUP) {
            const int ky = half_y[j], kx = half_x[j];
            REAL rr = 0, ri = 0;
            for (int m = 0, t = 0; m < L; ++m, t = t + ky < L ? t + ky : t + ky - L) {
                const REAL c = tw[t], s = tw[SPECTRAL_MAXL + t];
                const REAL ar = rows[m * H + kx], ai = rows[L * H + m * H + kx];
                rr += ar * c + ai * s;
                ri += ai * c - ar * s;
            }
            rre[j] = rr;
            rim[j] = ri;
            const REAL score = (qa[j] * rr + qb[j] * ri) * rr + qc[j] * ri * ri;
            if (score > bs) {
                bs = score;
                bi = j;
            }
        }
#endif

        REAL first_gain = 0, energy = 0;  // item 0's: energy is the weighted squared error
        int count = 0;
        if (W0 > 0) {
            const int most = ch == 0 ? iterations : minor_iterations;
            for (int it = 0; it < most; ++it) {
                best[lid] = bs;
                best_at[lid] = bi;
                barrier(FENCE);
                if (lid == 0) {
                    if (it == 0)
                        for (int q = 0; q < SPECTRAL_GROUP; ++q) energy += sums[q];
                    REAL top = best[0];
                    int j = best_at[0];
                    for (int q = 1; q < SPECTRAL_GROUP; ++q)
                        if (best[q] > top || (best[q] == top && best_at[q] < j)) {
                            top = best[q];
                            j = best_at[q];
                        }
                    const int ky = half_y[j], kx = half_x[j];
                    const REAL rr = rre[j], ri = rim[j];
                    const int k2y = 2 * ky < L ? 2 * ky : 2 * ky - L;
                    const int k2x = 2 * kx < L ? 2 * kx : 2 * kx - L;
                    const bool self = k2y == 0 && k2x == 0;
                    REAL cr, ci = 0, gain;
                    if (self) {
                        cr = rr / W0;
                        gain = rr * cr;
                    } else {
                        const REAL vr = wre[k2x * WS + k2y], vi = wim[k2x * WS + k2y];
                        const REAL den = fmax(W0 * W0 - (vr * vr + vi * vi),
                                              (REAL)1e-3 * W0 * W0);
                        cr = (rr * W0 - (vr * rr + vi * ri)) / den;
                        ci = (ri * W0 - (vi * rr - vr * ri)) / den;
                        gain = 2 * (cr * rr + ci * ri);
                    }
                    if (it == 0) first_gain = gain;
                    // the residual already small (the weighted mean of its square at most
                    // floor2), or a pick that would gain too little (against the first pick's,
                    // or against the residual left: the model has stalled, a pick would fit
                    // the window's noise), ends the block's channel
                    if (!(gain > 0) || gain < stop * first_gain
                        || (floor2 > 0 && energy <= floor2 * W0)
                        || gain < stall * energy) {
                        pick_k[0] = -1;
                    } else {
                        pick_k[0] = ky * L + kx;
                        pick_k[1] = self;
                        pick_c[0] = gamma * cr;
                        pick_c[1] = gamma * ci;
                        picks[it] = self ? -1 - (ky * 64 + kx) : ky * 64 + kx;
                        coef_r[it] = gamma * cr;
                        coef_i[it] = gamma * ci;
                        // a step gamma along the best pair lowers the error by
                        // gamma (2 - gamma) times the full step's gain
                        energy -= gamma * (2 - gamma) * gain;
                    }
                }
                barrier(FENCE);
                const int k = pick_k[0];
                if (k < 0) break;
                count = it + 1;
                const int ky = k / L, kx = k - ky * L;
                const REAL cr = pick_c[0], ci = pick_c[1];
                const int self = pick_k[1];
#if SPECTRAL_VW > 1
                // CPUs: vectors of 8 candidates of one column (item lid takes vectors lid,
                // lid + GROUP, ...), whose W(l - k) and W(l + k) are 8 consecutive values of
                // W's continued columns, and the scores' argmax in a pass of its own (a running
                // argmax kept the compiler from vectorising the loop). The same arithmetic.
                REALV top = -1;
                IDXV at = 0;
                // column by column (CS / 8 vectors each), so that the column's offsets into
                // W are found once; the item's vectors of a column, v = lid mod GROUP
                for (int lx = 0, v0 = 0; v0 < NC / 8; ++lx, v0 += CS / 8) {
                    const int dx = lx - kx < 0 ? lx - kx + L : lx - kx;
                    const int sx = lx + kx >= L ? lx + kx - L : lx + kx;
                    const int dm0 = dx * WS - ky + L;  // + ly: lanes (ly - ky + i) mod L
                    const int dp0 = sx * WS + ky;      // + ly: lanes ly + ky + i
                    const int mine = (lid + SPECTRAL_GROUP - v0 % SPECTRAL_GROUP) % SPECTRAL_GROUP;
                    for (int v = v0 + mine; v < v0 + CS / 8; v += SPECTRAL_GROUP) {
                        const int j0 = 8 * v, ly = j0 - 8 * v0;
                        const REALV ar = LOAD8(wre + dm0 + ly), ai = LOAD8(wim + dm0 + ly);
                        REALV ur = cr * ar - ci * ai, ui = cr * ai + ci * ar;
                        if (!self) {
                            const REALV pr = LOAD8(wre + dp0 + ly);
                            const REALV pi = LOAD8(wim + dp0 + ly);
                            ur += cr * pr + ci * pi;
                            ui += cr * pi - ci * pr;
                        }
                        const REALV rr = LOAD8(rre + j0) - ur, ri = LOAD8(rim + j0) - ui;
                        STORE_AND_SCORE(rr, ri, j0, top, at);
                    }
                }
                first_best(top, at, &bs, &bi);
#else
                bs = -1;
                bi = 0;
                for (int j = lid; j < NC; j += SPECTRAL_GROUP) {
                    const int ly = half_y[j], lx = half_x[j];
                    int dy = ly - ky, dx = lx - kx;
                    dy += dy < 0 ? L : 0;
                    dx += dx < 0 ? L : 0;
                    const int dm = dx * WS + dy;
                    const REAL ar = wre[dm], ai = wim[dm];
                    REAL ur = cr * ar - ci * ai, ui = cr * ai + ci * ar;  // c W(l - k)
                    if (!self) {
                        int sy = ly + ky, sx = lx + kx;
                        sy -= sy >= L ? L : 0;
                        sx -= sx >= L ? L : 0;
                        const int dp = sx * WS + sy;
                        const REAL pr = wre[dp], pi = wim[dp];
                        ur += cr * pr + ci * pi;  // conj(c) W(l + k)
                        ui += cr * pi - ci * pr;
                    }
                    const REAL rr = rre[j] - ur, ri = rim[j] - ui;
                    rre[j] = rr;
                    rim[j] = ri;
                    // the next pick's score, as the update leaves R
                    const REAL score = (qa[j] * rr + qb[j] * ri) * rr + qc[j] * ri * ri;
                    if (score > bs) {
                        bs = score;
                        bi = j;
                    }
                }
#endif
                // no barrier: best[] is next written after lid 0 has read it (the barrier
                // above), and each item reads back only its own candidates
            }
        }
        barrier(FENCE);  // the model's picks, as lid 0 wrote them
        // the block's pixels that this wave fills, from the model
        for (int i = lid; i < B * B; i += SPECTRAL_GROUP) {
            const int u = i / B, v = i - u * B;
            const int y = by + u, x = bx + v;
            if (y < 0 || x < 0 || y >= ny || x >= nx) continue;
            const int p = y * nx + x;
            if (state[p] != wave) continue;
            const int m = b + u, n = b + v;
            REAL g = fit[0] + fit[1] * uv[m] + fit[2] * uv[n];
            for (int t = 0; t < count; ++t) {
                const int code = picks[t];
                const int k = code < 0 ? -1 - code : code;
                const int ky = k >> 6, kx = k & 63;
                int e;
                div_l(ky * m + kx * n, L, inv_l, &e);
                const REAL cr = coef_r[t], ci = coef_i[t];
                g += code < 0 ? cr * tw[e] : 2 * (cr * tw[e] - ci * tw[SPECTRAL_MAXL + e]);
            }
            plane[p] = g;
        }
    }
}
