// Rudin-Osher-Fatemi denoising with exact total variation, solved in the dual:
//
//     min_u  TV(u) + lambda/2 |u - f|^2,     u = f + div(p) / lambda,  |p| <= 1 per cell,
//
// by fast projected gradient on p (Beck and Teboulle's FGP: a projected gradient step from
// an extrapolated point q, step 1/8 since |div|^2 <= 8 on the unit grid).
//
// Discretisation (unit spacing): grad u is the forward difference, zero across the image
// border; div is its negative adjoint, the backward difference of p with no flux through
// the border. p lives on cell faces: px(x, y) on the face between (x, y) and (x + 1, y),
// py(x, y) on the face between (x, y) and (x, y + 1). They are stored interleaved, px of
// padded cell i at p[2i] and py at p[2i + 1]: with separate px and py arrays the step kernel
// has more pointers than PoCL's loop vectoriser will check for overlap, and runs scalar
// (docs/planar.md has the measured cost); interleaved pairs vectorise.
//
// Borders without branches in the cell loop: the ghost layer of p holds the reflection of p
// about the border faces (px odd and py even across a vertical border, the converse across
// a horizontal one). With f mirrored too, u = f + div(p)/lambda comes out mirrored, so the
// forward difference across the border is exactly zero and the border-face flux stays zero.
// Ghosts that reflect to zero (px left of column 0, py above row 0) are zero from the start
// and never written; the others are written by the step kernel from values it has just
// computed itself (one small epilogue per row), which saves four ghost-fill launches per
// iteration; on PoCL a launch costs tens of microseconds, as much as a small image's step.
#include "common.h"
#include "reduce.h"

// The extrapolated dual point q = p + beta (p - p_old), formed on the fly from the last two
// iterates rather than stored: reading two iterates of p costs the same as storing q and
// reading p once more, and saves writing q.
#define QX(j) (p[2 * (j)] + beta * (p[2 * (j)] - p_old[2 * (j)]))
#define QY(j) (p[2 * (j) + 1] + beta * (p[2 * (j) + 1] - p_old[2 * (j) + 1]))

// One FGP iteration: p_new = P(q + grad(lambda f + div q) / 8), P the projection onto the
// unit disc per cell. `lambda` holds one value per channel (it may be updated on the device,
// see rof_dual_lambda). Reads p (ghosts included) and p_old, writes p_new with its ghosts.
__kernel void rof_dual_step(__global const REAL* restrict p, __global const REAL* restrict p_old,
                            __global REAL* restrict p_new, __global const REAL* restrict f,
                            __global const REAL* restrict lambda, const REAL beta, GRID_ARGS)
{
    const int y = get_global_id(1);
    if (y >= ny) return;
    const REAL lam = lambda[get_global_id(2)];
    const int x0 = get_global_id(0) * xrun;
    const int x1 = min(x0 + xrun, nx);
    const int row = get_global_id(2) * plane + (y + G) * sx + G;
    for (int i = row + x0; i < row + x1; ++i) {
        const REAL qx = QX(i), qx_w = QX(i - 1), qx_e = QX(i + 1);
        const REAL qx_n = QX(i + sx), qx_nw = QX(i + sx - 1);
        const REAL qy = QY(i), qy_s = QY(i - sx), qy_e = QY(i + 1);
        const REAL qy_se = QY(i + 1 - sx), qy_n = QY(i + sx);
        // w = lambda u = lambda f + div q at the cell and its east and north neighbours.
        const REAL w = lam * f[i] + (qx - qx_w + qy - qy_s);
        const REAL w_e = lam * f[i + 1] + (qx_e - qx + qy_e - qy_se);
        const REAL w_n = lam * f[i + sx] + (qx_n - qx_nw + qy_n - qy);
        const REAL ax = qx + (REAL)0.125 * (w_e - w);
        const REAL ay = qy + (REAL)0.125 * (w_n - w);
        // Projection onto |p| <= 1: p / max(1, |p|). The max as a select of plain values,
        // with the square root outside it: PoCL calls fmax out of line, and a square root
        // under a condition stays a branch; either keeps the loop from vectorising.
        const REAL norm2 = ax * ax + ay * ay;
        const REAL shrink = RSQRT(norm2 > 1 ? norm2 : (REAL)1);
        p_new[2 * i] = ax * shrink;
        p_new[2 * i + 1] = ay * shrink;
    }
    // Reflected ghosts of p_new, each written by the work-item that owns its source cell:
    // right of the last column px = -px(nx - 2), py = py(nx - 1); below the last row
    // px = px(ny - 1), py = -py(ny - 2).
    if (x0 <= nx - 2 && nx - 2 < x1) p_new[2 * (row + nx)] = -p_new[2 * (row + nx - 2)];
    if (x0 < nx && x1 == nx) p_new[2 * (row + nx) + 1] = p_new[2 * (row + nx - 1) + 1];
    if (y == ny - 1)
        for (int i = row + x0; i < row + x1; ++i) p_new[2 * (i + sx)] = p_new[2 * i];
    if (y == ny - 2)
        for (int i = row + x0; i < row + x1; ++i)
            p_new[2 * (i + 2 * sx) + 1] = -p_new[2 * i + 1];
}

// Every K iterations, per interior row (work-item (0, y, c)): the primal image
// u = f + div(p)/lambda written into `u`, and four row partials written to
// partial[(c * 4 + k) * ny + y]: k = 0 sum (div p)^2, 1 sum (u - u_before)^2, 2 sum u^2,
// 3 max |u - u_before|. The first feeds lambda (rof_dual_lambda) and the residual
// |u - f|^2 = sum (div p)^2 / lambda^2. The stopping test reads the largest change of any
// pixel (k = 3), not a sum over the image: a sum normalised by the image's size lets the
// many pixels that settle early (smooth areas of a large image) hide the few still moving,
// so the same pixels would stop at a different point depending on what surrounds them.
__kernel void rof_dual_rows(__global const REAL* restrict p, __global const REAL* restrict f,
                            __global const REAL* restrict lambda, __global REAL* restrict u,
                            __global REAL* restrict partial, GRID_ARGS)
{
    REASSOCIATE_SUMS
    ROW_OF_ITEM(y, row);
    const int c = get_global_id(2);
    const REAL inv_lam = (REAL)1 / lambda[c];
    REAL sum_dd = 0, sum_du = 0, sum_uu = 0, max_du = 0;
    for (int i = row; i < row + nx; ++i) {
        const REAL d = p[2 * i] - p[2 * (i - 1)] + p[2 * i + 1] - p[2 * (i - sx) + 1];
        const REAL v = f[i] + d * inv_lam;
        const REAL du = FABS(v - u[i]);
        sum_dd += d * d;
        sum_du += du * du;
        sum_uu += v * v;
        max_du = MAX_SEL(max_du, du);
        u[i] = v;
    }
    partial[(c * 4 + 0) * ny + y] = sum_dd;
    partial[(c * 4 + 1) * ny + y] = sum_du;
    partial[(c * 4 + 2) * ny + y] = sum_uu;
    partial[(c * 4 + 3) * ny + y] = max_du;
}

// Dynamic lambda (thesis eq. C.2 in this dual form). At the minimiser div p = lambda (u - f);
// multiplying by (u - f) and summing, -sum p . grad(u - f) = sum div(p) (u - f)
// = sum (div p)^2 / lambda, so asking sum (u - f)^2 = N sigma^2 gives
//     lambda_new = sum (div p)^2 / (lambda N sigma^2),
// which grows lambda while the residual is larger than the noise and shrinks it otherwise.
// One work-item per channel; lambda stays above `lam_min` so u = f + div(p)/lambda is defined.
// A channel whose inv_n_sigma2 is 0 keeps its lambda (the host fixes it for channels whose
// sigma exceeds their own spread, where no lambda reaches it).
__kernel void rof_dual_lambda(__global const REAL* restrict partial,
                              __global REAL* restrict lambda, const int ny,
                              __global const REAL* restrict inv_n_sigma2, const REAL lam_min)
{
    const int c = get_global_id(0);
    if (inv_n_sigma2[c] == 0) return;
    lambda[c] = fmax(lam_min, sum_rows(partial + c * 4 * ny, ny) * inv_n_sigma2[c] / lambda[c]);
}

// Colour-coupled (vectorial) TV: min_u sum_cells sqrt(sum_c |grad u_c|^2) + lambda/2 |u - f|^2,
// one lambda for all channels. Its dual is the same per-channel FGP step, except that the
// projection acts on the whole cell's vector (px_c, py_c)_c at once, onto the unit ball of
// R^(2 nc): an edge present in one channel then lets every channel keep its edge there, and
// no channel is flattened alone into a blotch of another colour.
//
// One work-item per row (the launch's channel range is 1); the channels, nch of them, are
// walked inside, `plane` apart (see the blocks below). lambda[0] is the shared lambda.
inline REAL dual_step_x(__global const REAL* restrict p, __global const REAL* restrict p_old,
                        __global const REAL* restrict f, const REAL lam, const REAL beta,
                        const int i, const int sx, REAL* ay_out)
{
    const REAL qx = QX(i), qx_w = QX(i - 1), qx_e = QX(i + 1);
    const REAL qx_n = QX(i + sx), qx_nw = QX(i + sx - 1);
    const REAL qy = QY(i), qy_s = QY(i - sx), qy_e = QY(i + 1);
    const REAL qy_se = QY(i + 1 - sx), qy_n = QY(i + sx);
    const REAL w = lam * f[i] + (qx - qx_w + qy - qy_s);
    const REAL w_e = lam * f[i + 1] + (qx_e - qx + qy_e - qy_se);
    const REAL w_n = lam * f[i + sx] + (qx_n - qx_nw + qy_n - qy);
    *ay_out = qy + (REAL)0.125 * (w_n - w);
    return qx + (REAL)0.125 * (w_e - w);
}

// Cells in blocks of VEC_BLOCK along the row: per channel, a plain loop over the block writes
// the unprojected step into p_new and adds its square to the block's norms; a last loop per
// channel scales p_new. Every inner loop has a run of cells and no loop over the channels
// inside it, so PoCL vectorises each (a channel loop inside the cell loop kept the whole step
// scalar: twice the time per iteration, docs/planar.md), and the step is computed once.
#define VEC_BLOCK 64
__kernel void rof_dual_step_vec(__global const REAL* restrict p,
                                __global const REAL* restrict p_old, __global REAL* restrict p_new,
                                __global const REAL* restrict f,
                                __global const REAL* restrict lambda, const REAL beta,
                                const int nch, GRID_ARGS)
{
    const int y = get_global_id(1);
    if (y >= ny) return;
    const REAL lam = lambda[0];
    const int x0 = get_global_id(0) * xrun;
    const int x1 = min(x0 + xrun, nx);
    const int row = (y + G) * sx + G;
    REAL norm2[VEC_BLOCK];  // the block's squared norms, then their projection factors
    for (int b = row + x0; b < row + x1; b += VEC_BLOCK) {
        const int n = min(VEC_BLOCK, row + x1 - b);
        for (int k = 0; k < n; ++k) norm2[k] = 0;
        for (int c = 0; c < nch; ++c) {
            const int o = c * plane + b;
            for (int k = 0; k < n; ++k) {
                REAL ay;
                const REAL ax = dual_step_x(p, p_old, f, lam, beta, o + k, sx, &ay);
                p_new[2 * (o + k)] = ax;
                p_new[2 * (o + k) + 1] = ay;
                norm2[k] += ax * ax + ay * ay;
            }
        }
        for (int k = 0; k < n; ++k) norm2[k] = RSQRT(norm2[k] > 1 ? norm2[k] : (REAL)1);
        for (int c = 0; c < nch; ++c) {
            const int o = c * plane + b;
            for (int k = 0; k < n; ++k) {
                p_new[2 * (o + k)] *= norm2[k];
                p_new[2 * (o + k) + 1] *= norm2[k];
            }
        }
    }
    // The reflected ghosts of every channel, as in rof_dual_step.
    for (int c = 0; c < nch; ++c) {
        const int crow = c * plane + row;
        if (x0 <= nx - 2 && nx - 2 < x1) p_new[2 * (crow + nx)] = -p_new[2 * (crow + nx - 2)];
        if (x0 < nx && x1 == nx) p_new[2 * (crow + nx) + 1] = p_new[2 * (crow + nx - 1) + 1];
        if (y == ny - 1)
            for (int i = crow + x0; i < crow + x1; ++i) p_new[2 * (i + sx)] = p_new[2 * i];
        if (y == ny - 2)
            for (int i = crow + x0; i < crow + x1; ++i)
                p_new[2 * (i + 2 * sx) + 1] = -p_new[2 * i + 1];
    }
}

// Dynamic lambda of the vectorial model: the per-channel rule of rof_dual_lambda with the
// sums taken over all channels, lambda_new = sum_c sum (div p_c)^2 / (lambda N nc sigma^2),
// sigma^2 the channels' mean noise variance (inv_n_sigma2 = 1 / (N nc sigma^2)). One
// work-item; the shared lambda is written to every channel's entry, since rof_dual_rows
// reads lambda per channel.
__kernel void rof_dual_lambda_vec(__global const REAL* restrict partial,
                                  __global REAL* restrict lambda, const int ny, const int nch,
                                  const REAL inv_n_sigma2, const REAL lam_min)
{
    if (get_global_id(0) != 0 || inv_n_sigma2 == 0) return;
    REAL total = 0;
    for (int c = 0; c < nch; ++c) total += sum_rows(partial + c * 4 * ny, ny);
    const REAL lam = fmax(lam_min, total * inv_n_sigma2 / lambda[0]);
    for (int c = 0; c < nch; ++c) lambda[c] = lam;
}
