// Frequency-selective inpainting: each block of the damage is modelled as a sparse sum of
// 2-D Fourier basis functions, fitted greedily to the known pixels of an extended block
// around it, and the block's missing pixels are taken from the model.
//
// One work-group of SPECTRAL_GROUP items fits one (block, channel): group (g, c) takes block
// blocks[first + g] of channel c; a block is 5 ints (row, column, B, L, copy), its B x B pixels
// from (row, column), its extended window L x L (L even, L - B even, L <= SPECTRAL_MAXL), in
// copy `copy` of the image (img: copies x nc planes; wave_of: one plane per copy; copies are
// the fills on differently offset block grids, averaged afterwards). The blocks of one launch (a wave) are independent: no
// block's extended window holds pixels that another block of the wave writes, so they are
// written in place into `img`.
//
// Extended block: L x L pixels, the block's B x B pixels in the middle, (L - B) / 2 on each
// side. A pixel's weight is w = s * rho^d, d its distance to the window's centre, s = 1 for
// a known pixel, delta for a hole pixel that an earlier wave filled (wave_of[p] < wave), 0
// for the rest (and outside the image). wave_of[p] is -1 for known pixels.
//
// Model: g = a weighted least-squares plane (detrend=1; a ramp is not periodic, a sum of
// Fourier functions would need many terms for it) + sum of c_k phi_k + conj(c_k) phi_-k, phi_k(x) = exp(2 pi i k.x / L). With the
// weighted residual's transform R(k) = sum_x w (f - g) exp(-2 pi i k.x / L) and the weight's
// transform W(k), the best real pair (k, -k) alone has the coefficient
//     c = (R(k) W(0) - W(2k) conj(R(k))) / (W(0)^2 - |W(2k)|^2)
// and lowers the weighted squared error by 2 Re(conj(c) R(k)); for a self-conjugate k
// (2k = 0 mod L) c = R(k) / W(0) (real) and the reduction R(k)^2 / W(0). Each iteration
// takes the k with the largest reduction times the frequency prior (1 - |k| / |k|max)^alpha,
// adds gamma c (gamma < 1 makes up for the basis functions not being orthogonal under the
// weights, so that later picks can correct earlier ones), and updates R in the frequency
// domain: R(l) -= gamma (c W(l - k) + conj(c) W(l + k)). R is kept on the half plane
// kx in [0, L/2] only (R(-l) = conj(R(l)) for a real residual); W on the whole plane.
// The scores' factors, R on the half plane and the picks live in T once the transforms are
// done (2 MAXK + 5 MAXH <= 4 MAXL^2). The loop stops after `iterations` picks or once a pick's reduction falls below `stop`
// times the first one's.
#include "common.cl"

#define SPECTRAL_MAXL 32    // largest extended block (local memory: 8 L^2 reals)
#define SPECTRAL_MAXK 512   // most picks per block
#define SPECTRAL_GROUP 64
#define SPECTRAL_MAXH (SPECTRAL_MAXL * (SPECTRAL_MAXL / 2 + 1))  // the half plane's size

INLINE int spectral_wrap(const int v, const int L) { const int r = v % L; return r < 0 ? r + L : r; }

__kernel __attribute__((reqd_work_group_size(SPECTRAL_GROUP, 1, 1)))
void spectral_blocks(__global REAL* img, __global const int* wave_of,
                     __global const int* blocks, const int first, const int wave,
                     const int nx, const int ny, const int nc, const REAL rho,
                     const REAL delta, const REAL gamma, const REAL alpha,
                     const int iterations, const REAL stop, const int detrend)
{
    __local REAL X[4 * SPECTRAL_MAXL * SPECTRAL_MAXL];  // w f and w, then R and W
    __local REAL T[4 * SPECTRAL_MAXL * SPECTRAL_MAXL];  // the rows' transforms, then the picks
    __local REAL tw[2 * SPECTRAL_MAXL];                 // cos, sin of 2 pi j / L
    __local REAL best[SPECTRAL_GROUP];
    __local int best_at[SPECTRAL_GROUP];
    __local REAL pick_c[2];
    __local int pick_k[2];
    __local short half_y[SPECTRAL_MAXH], half_x[SPECTRAL_MAXH];
    __local int picks[SPECTRAL_MAXK];
    __local REAL sums[9 * SPECTRAL_GROUP];
    __local REAL fit[3];

    const int lid = get_local_id(0);
    const int blk = first + get_group_id(0);
    const int by = blocks[5 * blk], bx = blocks[5 * blk + 1];
    const int B = blocks[5 * blk + 2], L = blocks[5 * blk + 3];
    const int copy = blocks[5 * blk + 4];
    wave_of += (size_t)copy * nx * ny;
    const int LL = L * L;
    const int b = (L - B) / 2;
    const int oy = by - b, ox = bx - b;
    __global REAL* plane = img + ((size_t)copy * nc + get_group_id(1)) * nx * ny;
    const REAL two_pi_l = (REAL)6.283185307179586 / (REAL)L;

    for (int j = lid; j < L; j += SPECTRAL_GROUP) {
        REAL c;
        const REAL s = sincos(two_pi_l * (REAL)j, &c);
        tw[j] = c;
        tw[SPECTRAL_MAXL + j] = s;
    }
    // the window: f in T[0, LL), w in X[LL, 2 LL); then a weighted least-squares plane
    // (plane[0] + plane[1] v + plane[2] u, u and v the centred coordinates over L) is taken
    // out, X[0, LL) = w (f - plane), and added back to the model
    const REAL centre = (REAL)0.5 * (REAL)(L - 1);
    const REAL log_rho = log(rho);
    REAL acc[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};  // w, w u, w v, w u u, w u v, w v v, w f, w f u, w f v
    for (int i = lid; i < LL; i += SPECTRAL_GROUP) {
        const int m = i / L, n = i - m * L;
        const int y = oy + m, x = ox + n;
        REAL w = 0, f = 0;
        if (y >= 0 && y < ny && x >= 0 && x < nx) {
            const int p = y * nx + x;
            const int s = wave_of[p];
            w = s < 0 ? (REAL)1 : (s < wave ? delta : (REAL)0);
            if (w > 0) {
                const REAL dy = (REAL)m - centre, dx = (REAL)n - centre;
                w *= exp(log_rho * sqrt(dx * dx + dy * dy));
                f = plane[p];
            }
        }
        T[i] = f;
        X[LL + i] = w;
        const REAL u = ((REAL)m - centre) / (REAL)L, v = ((REAL)n - centre) / (REAL)L;
        const REAL wf = w * f;
        acc[0] += w; acc[1] += w * u; acc[2] += w * v;
        acc[3] += w * u * u; acc[4] += w * u * v; acc[5] += w * v * v;
        acc[6] += wf; acc[7] += wf * u; acc[8] += wf * v;
    }
    for (int q = 0; q < 9; ++q) sums[q * SPECTRAL_GROUP + lid] = acc[q];
    barrier(CLK_LOCAL_MEM_FENCE);
    if (lid == 0) {
        REAL t[9];
        for (int q = 0; q < 9; ++q) {
            REAL a = 0;
            for (int j = 0; j < SPECTRAL_GROUP; ++j) a += sums[q * SPECTRAL_GROUP + j];
            t[q] = a;
        }
        // normal equations for (c0, cu, cv); a small ridge on the slopes keeps windows whose
        // known pixels lie on a line solvable
        const REAL ridge = (REAL)1e-3 * t[0];
        const REAL a00 = t[0], a01 = t[1], a02 = t[2];
        const REAL a11 = t[3] + ridge, a12 = t[4], a22 = t[5] + ridge;
        const REAL c0 = a11 * a22 - a12 * a12, c1 = a02 * a12 - a01 * a22, c2 = a01 * a12 - a02 * a11;
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
    barrier(CLK_LOCAL_MEM_FENCE);
    for (int i = lid; i < LL; i += SPECTRAL_GROUP) {
        const int m = i / L, n = i - m * L;
        const REAL u = ((REAL)m - centre) / (REAL)L, v = ((REAL)n - centre) / (REAL)L;
        X[i] = X[LL + i] * (T[i] - (fit[0] + fit[1] * u + fit[2] * v));
    }
    barrier(CLK_LOCAL_MEM_FENCE);
    // rows: T = (transform along x of w f, re, im; of w, re, im)
    for (int i = lid; i < LL; i += SPECTRAL_GROUP) {
        const int m = i / L, k = i - m * L;
        REAL ar = 0, ai = 0, wr = 0, wi = 0;
        for (int n = 0, t = 0; n < L; ++n, t = t + k < L ? t + k : t + k - L) {
            const REAL a = X[m * L + n], w = X[LL + m * L + n];
            const REAL c = tw[t], s = tw[SPECTRAL_MAXL + t];
            ar += a * c;
            ai -= a * s;
            wr += w * c;
            wi -= w * s;
        }
        T[i] = ar;
        T[LL + i] = ai;
        T[2 * LL + i] = wr;
        T[3 * LL + i] = wi;
    }
    barrier(CLK_LOCAL_MEM_FENCE);
    // columns: X = (R re, R im, W re, W im), index ky * L + kx
    for (int i = lid; i < LL; i += SPECTRAL_GROUP) {
        const int ky = i / L, kx = i - ky * L;
        REAL rr = 0, ri = 0, wr = 0, wi = 0;
        for (int m = 0, t = 0; m < L; ++m, t = t + ky < L ? t + ky : t + ky - L) {
            const REAL c = tw[t], s = tw[SPECTRAL_MAXL + t];
            const int q = m * L + kx;
            rr += T[q] * c + T[LL + q] * s;
            ri += T[LL + q] * c - T[q] * s;
            wr += T[2 * LL + q] * c + T[3 * LL + q] * s;
            wi += T[3 * LL + q] * c - T[2 * LL + q] * s;
        }
        X[i] = rr;
        X[LL + i] = ri;
        X[2 * LL + i] = wr;
        X[3 * LL + i] = wi;
    }
    barrier(CLK_LOCAL_MEM_FENCE);

    // the half plane, compacted: candidate j is (ky, kx) = (j / H, j % H); its score is
    // qa R_re^2 + qb R_re R_im + qc R_im^2, the pair's error reduction times the prior
    const REAL W0 = X[2 * LL];
    const int H = L / 2 + 1;
    const int NH = L * H;
    __local REAL* const coef_r = T;
    __local REAL* const coef_i = T + SPECTRAL_MAXK;
    __local REAL* const qa = T + 2 * SPECTRAL_MAXK;
    __local REAL* const qb = qa + SPECTRAL_MAXH;
    __local REAL* const qc = qb + SPECTRAL_MAXH;
    __local REAL* const rre = qc + SPECTRAL_MAXH;
    __local REAL* const rim = rre + SPECTRAL_MAXH;
    const REAL inv_kmax = (REAL)1 / ((REAL)0.5 * (REAL)L * sqrt((REAL)2));
    for (int j = lid; j < NH; j += SPECTRAL_GROUP) {
        const int ky = j / H, kx = j - ky * H;
        const int idx = ky * L + kx;
        half_y[j] = (short)ky;
        half_x[j] = (short)kx;
        rre[j] = X[idx];
        rim[j] = X[LL + idx];
        const REAL fy = (REAL)(ky <= L / 2 ? ky : ky - L);
        const REAL nu = fmin(sqrt(fy * fy + (REAL)(kx * kx)) * inv_kmax, (REAL)1);
        const REAL prior = alpha == 0 ? (REAL)1 : pow((REAL)1 - nu, alpha);
        const int k2y = 2 * ky < L ? 2 * ky : 2 * ky - L, k2x = 2 * kx < L ? 2 * kx : 2 * kx - L;
        if (!(W0 > 0)) {
            qa[j] = qb[j] = qc[j] = 0;
        } else if (k2y == 0 && k2x == 0) {  // self-conjugate: one real coefficient
            qa[j] = prior / W0;
            qb[j] = qc[j] = 0;
        } else {
            const REAL vr = X[2 * LL + k2y * L + k2x], vi = X[3 * LL + k2y * L + k2x];
            const REAL den = fmax(W0 * W0 - (vr * vr + vi * vi), (REAL)1e-3 * W0 * W0);
            const REAL pd = prior / den;
            qa[j] = 2 * (W0 - vr) * pd;
            qb[j] = -4 * vi * pd;
            qc[j] = 2 * (W0 + vr) * pd;
        }
    }
    barrier(CLK_LOCAL_MEM_FENCE);

    REAL first_gain = 0;  // item 0's
    int count = 0;
    if (W0 > 0) {
        for (int it = 0; it < iterations; ++it) {
            REAL bs = -1;
            int bi = 0;
            for (int j = lid; j < NH; j += SPECTRAL_GROUP) {
                const REAL rr = rre[j], ri = rim[j];
                const REAL score = (qa[j] * rr + qb[j] * ri) * rr + qc[j] * ri * ri;
                if (score > bs) {
                    bs = score;
                    bi = j;
                }
            }
            best[lid] = bs;
            best_at[lid] = bi;
            barrier(CLK_LOCAL_MEM_FENCE);
            if (lid == 0) {
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
                REAL cr, ci = 0, gain;
                if (k2y == 0 && k2x == 0) {
                    cr = rr / W0;
                    gain = rr * cr;
                } else {
                    const REAL vr = X[2 * LL + k2y * L + k2x], vi = X[3 * LL + k2y * L + k2x];
                    const REAL den = fmax(W0 * W0 - (vr * vr + vi * vi), (REAL)1e-3 * W0 * W0);
                    cr = (rr * W0 - (vr * rr + vi * ri)) / den;
                    ci = (ri * W0 - (vi * rr - vr * ri)) / den;
                    gain = 2 * (cr * rr + ci * ri);
                }
                if (it == 0) first_gain = gain;
                if (!(gain > 0) || gain < stop * first_gain) {
                    pick_k[0] = -1;
                } else {
                    const bool self = k2y == 0 && k2x == 0;
                    pick_k[0] = ky * L + kx;
                    pick_k[1] = self;
                    pick_c[0] = gamma * cr;
                    pick_c[1] = gamma * ci;
                    picks[it] = self ? -1 - (ky * L + kx) : ky * L + kx;
                    coef_r[it] = gamma * cr;
                    coef_i[it] = gamma * ci;
                }
            }
            barrier(CLK_LOCAL_MEM_FENCE);
            const int k = pick_k[0];
            if (k < 0) break;
            count = it + 1;
            const int ky = k / L, kx = k - ky * L;
            const REAL cr = pick_c[0], ci = pick_c[1];
            const int self = pick_k[1];
            for (int j = lid; j < NH; j += SPECTRAL_GROUP) {
                const int ly = half_y[j], lx = half_x[j];
                int dy = ly - ky, dx = lx - kx;
                dy += dy < 0 ? L : 0;
                dx += dx < 0 ? L : 0;
                const int dm = dy * L + dx;
                const REAL ar = X[2 * LL + dm], ai = X[3 * LL + dm];
                REAL ur = cr * ar - ci * ai, ui = cr * ai + ci * ar;  // c W(l - k)
                if (!self) {
                    int sy = ly + ky, sx = lx + kx;
                    sy -= sy >= L ? L : 0;
                    sx -= sx >= L ? L : 0;
                    const int dp = sy * L + sx;
                    const REAL pr = X[2 * LL + dp], pi = X[3 * LL + dp];
                    ur += cr * pr + ci * pi;  // conj(c) W(l + k)
                    ui += cr * pi - ci * pr;
                }
                rre[j] -= ur;
                rim[j] -= ui;
            }
            barrier(CLK_LOCAL_MEM_FENCE);
        }
    }
    // the block's pixels that this wave fills, from the model
    for (int i = lid; i < B * B; i += SPECTRAL_GROUP) {
        const int u = i / B, v = i - u * B;
        const int y = by + u, x = bx + v;
        if (y < 0 || x < 0 || y >= ny || x >= nx) continue;
        const int p = y * nx + x;
        if (wave_of[p] != wave) continue;
        const int m = b + u, n = b + v;
        REAL g = fit[0] + fit[1] * (((REAL)m - centre) / (REAL)L)
                 + fit[2] * (((REAL)n - centre) / (REAL)L);
        for (int t = 0; t < count; ++t) {
            const int code = picks[t];
            const int k = code < 0 ? -1 - code : code;
            const int ky = k / L, kx = k - ky * L;
            const int e = (ky * m + kx * n) % L;
            const REAL cr = coef_r[t], ci = coef_i[t];
            g += code < 0 ? cr * tw[e] : 2 * (cr * tw[e] - ci * tw[SPECTRAL_MAXL + e]);
        }
        plane[p] = g;
    }
}
