// 3D volumes: total-variation (ROF) denoising in the dual, explicit diffusion (heat,
// Perona-Malik with Catte's pre-smoothing, TV flow) and the harmonic fill of holes, on
// (channels, nz, ny, nx) fields stored without ghosts, x fastest, with voxel spacing
// (hz, hy, hx) given as inverse spacings (ihz, ihy, ihx) and their squares.
//
// Borders are Neumann: a neighbour outside the volume is the voxel itself (a zero difference
// across the border face), tested per voxel. Volumes are small next to the planar images'
// hot loops, and the tests keep every kernel equal to tests/reference/volumes.py, which
// writes the same scheme with numpy's slices.
#include "common.h"

// Every volume kernel takes these after its own arguments: the size, the channels (walked
// inside the kernel, `n` voxels apart) and the voxels each work-item walks along x (the
// runtime's grid_launch: a whole row on CPUs, one voxel on GPUs).
#define VOL_ARGS const int nx, const int ny, const int nz, const int nch, const int xrun

#define FOR_EACH_VOXEL(i, x, y, z)                                        \
    const int y = get_global_id(1), z = get_global_id(2);                 \
    if (y >= ny || z >= nz) return;                                       \
    const int n = nx * ny * nz;                                           \
    const int x0_ = get_global_id(0) * xrun, x1_ = min(x0_ + xrun, nx);   \
    for (int x = x0_, i = (z * ny + y) * nx + x0_; x < x1_; ++x, ++i)

// ---- TV denoising: fast projected gradient on the dual (as kernels/planar/rof.cl) ---------
//     min_u TV(u) + lambda/2 |u - f|^2,  u = f + div(p) / lambda,  |p| <= 1 per voxel,
// grad the forward difference over the spacing (zero across the far border), div its
// negative adjoint. p holds three planes per channel (px, py, pz) at p[(3c + k) n + i]; the
// component across a far border face stays zero. One FGP iteration is two launches: w =
// lambda f + div q (volume_dual_div), then p_new = P(q + tau grad w) (volume_dual_step),
// q = p + beta (p - p_old) the extrapolated point, tau = 1 / (4 sum 1/h^2) >= 1 / |div|^2.
// The row (y, z) and the run [x0, x1) of it this work-item walks; the loops over x are
// innermost, under the channel loop, so that PoCL can vectorise them.
#define ROW_RUN(y, z, row, x0, x1)                                        \
    const int y = get_global_id(1), z = get_global_id(2);                 \
    if (y >= ny || z >= nz) return;                                       \
    const int n = nx * ny * nz, row = (z * ny + y) * nx;                  \
    const int x0 = get_global_id(0) * xrun, x1 = min(x0 + xrun, nx)

#define QV(a, j) (a[j] + beta * (a[j] - a##_old[j]))

__kernel void volume_dual_div(__global const REAL* restrict p,
                              __global const REAL* restrict p_old,
                              __global const REAL* restrict f,
                              __global const REAL* restrict lambda, const REAL beta,
                              __global REAL* restrict w, const REAL ihx, const REAL ihy,
                              const REAL ihz, VOL_ARGS)
{
    ROW_RUN(y, z, row, x0, x1);
    const int s = nx * ny;
    for (int c = 0; c < nch; ++c) {
        __global const REAL* restrict px = p + 3 * c * n;
        __global const REAL* restrict py = px + n;
        __global const REAL* restrict pz = px + 2 * n;
        __global const REAL* restrict px_old = p_old + 3 * c * n;
        __global const REAL* restrict py_old = px_old + n;
        __global const REAL* restrict pz_old = px_old + 2 * n;
        const REAL lam = lambda[c];
        // the component behind the near border face is zero (no flux): y and z per row,
        // x by starting the run's loop after x = 0
        const REAL fy = y > 0 ? 1 : 0, fz = z > 0 ? 1 : 0;
        const int sy = y > 0 ? nx : 0, sz = z > 0 ? s : 0;
        for (int x = x0; x < x1; ++x) {
            const int i = row + x;
            const REAL west = x > 0 ? QV(px, i - 1) : 0;
            const REAL dx = QV(px, i) - west;
            const REAL dy = QV(py, i) - fy * QV(py, i - sy);
            const REAL dz = QV(pz, i) - fz * QV(pz, i - sz);
            w[c * n + i] = lam * f[c * n + i] + ihx * dx + ihy * dy + ihz * dz;
        }
    }
}

// vectorial != 0: the projection acts on the voxel's whole (3 nch)-vector (colour-coupled TV);
// 0: on each channel's 3-vector. Cells in blocks of VOL_BLOCK along the row: per channel a
// plain loop writes the unprojected step and adds its square to the block's norms, a last
// loop scales (kernels/planar/rof.cl's rof_dual_step_vec, for the same vectorisation).
#define VOL_BLOCK 64
__kernel void volume_dual_step(__global const REAL* restrict p,
                               __global const REAL* restrict p_old,
                               __global const REAL* restrict w, __global REAL* restrict p_new,
                               const REAL beta, const REAL tau, const int vectorial,
                               const REAL ihx, const REAL ihy, const REAL ihz, VOL_ARGS)
{
    ROW_RUN(y, z, row, x0, x1);
    // beyond the far border the gradient is zero: a zero factor on a difference read from
    // the voxel itself
    const REAL ty = y < ny - 1 ? tau * ihy : 0, tz = z < nz - 1 ? tau * ihz : 0;
    const int sy = y < ny - 1 ? nx : 0, sz = z < nz - 1 ? nx * ny : 0;
    REAL norm2[VOL_BLOCK];
    for (int b = x0; b < x1; b += VOL_BLOCK) {
        const int m = min(VOL_BLOCK, x1 - b);
        for (int k = 0; k < m; ++k) norm2[k] = 0;
        for (int c = 0; c < nch; ++c) {
            __global const REAL* restrict px = p + 3 * c * n;
            __global const REAL* restrict py = px + n;
            __global const REAL* restrict pz = px + 2 * n;
            __global const REAL* restrict px_old = p_old + 3 * c * n;
            __global const REAL* restrict py_old = px_old + n;
            __global const REAL* restrict pz_old = px_old + 2 * n;
            __global const REAL* restrict wc = w + c * n;
            __global REAL* restrict nx_ = p_new + 3 * c * n;
            for (int k = 0; k < m; ++k) {
                const int x = b + k, i = row + x;
                const int e = x < nx - 1 ? i + 1 : i;
                const REAL ax = QV(px, i) + tau * ihx * (wc[e] - wc[i]);
                const REAL ay = QV(py, i) + ty * (wc[i + sy] - wc[i]);
                const REAL az = QV(pz, i) + tz * (wc[i + sz] - wc[i]);
                const REAL a2 = ax * ax + ay * ay + az * az;
                // per channel: projected now; vectorial: scaled below, once the norm is known
                const REAL shrink = vectorial ? (REAL)1 : RSQRT(a2 > 1 ? a2 : (REAL)1);
                nx_[i] = ax * shrink;
                nx_[n + i] = ay * shrink;
                nx_[2 * n + i] = az * shrink;
                norm2[k] += a2;
            }
        }
        if (!vectorial) continue;
        for (int k = 0; k < m; ++k) norm2[k] = RSQRT(norm2[k] > 1 ? norm2[k] : (REAL)1);
        for (int c = 0; c < 3 * nch; ++c)
            for (int k = 0; k < m; ++k) p_new[c * n + row + b + k] *= norm2[k];
    }
}

// Every check_every iterations, one work-item per row (0, y, z): u = w / lambda (w from
// volume_dual_div with beta 0, so u = f + div(p) / lambda), and two partials per channel and
// row, partial[(2c + k) nrows + row]: k = 0 the largest |u - u_before|, 1 sum (u - f)^2 (the
// residual lambda is fitted with). Only these come back to the host.
__kernel void volume_dual_primal(__global const REAL* restrict w,
                                 __global const REAL* restrict f,
                                 __global const REAL* restrict lambda, __global REAL* restrict u,
                                 __global REAL* restrict partial, VOL_ARGS)
{
    const int y = get_global_id(1), z = get_global_id(2);
    if (y >= ny || z >= nz) return;
    const int n = nx * ny * nz, row = z * ny + y, nrows = ny * nz;
    for (int c = 0; c < nch; ++c) {
        const REAL inv_lam = (REAL)1 / lambda[c];
        REAL largest = 0, sum = 0;
        for (int i = c * n + row * nx; i < c * n + row * nx + nx; ++i) {
            const REAL v = w[i] * inv_lam;
            const REAL du = FABS(v - u[i]), r = v - f[i];
            largest = du > largest ? du : largest;
            sum += r * r;
            u[i] = v;
        }
        partial[2 * c * nrows + row] = largest;
        partial[(2 * c + 1) * nrows + row] = sum;
    }
}

// ---- explicit diffusion -----------------------------------------------------------------
// A neighbour's value along axis k, the voxel's own beyond the border (Neumann).
#define EAST(u, i) (x < nx - 1 ? u[(i) + 1] : u[i])
#define WEST(u, i) (x > 0 ? u[(i) - 1] : u[i])
#define NORTH(u, i) (y < ny - 1 ? u[(i) + nx] : u[i])
#define SOUTH(u, i) (y > 0 ? u[(i) - nx] : u[i])
#define UP(u, i) (z < nz - 1 ? u[(i) + nx * ny] : u[i])
#define DOWN(u, i) (z > 0 ? u[(i) - nx * ny] : u[i])

// Heat u_t = Lap u, the seven-point Laplacian with spacing. Stable for
// dt <= 1 / (2 sum 1/h^2).
__kernel void volume_heat_step(__global const REAL* restrict u, __global REAL* restrict v,
                               const REAL dt, const REAL ihx2, const REAL ihy2,
                               const REAL ihz2, VOL_ARGS)
{
    FOR_EACH_VOXEL(i, x, y, z) {
        for (int c = 0; c < nch; ++c) {
            __global const REAL* uc = u + c * n;
            const REAL m = uc[i];
            v[c * n + i] = m + dt * (ihx2 * (EAST(uc, i) + WEST(uc, i) - 2 * m) +
                                     ihy2 * (NORTH(uc, i) + SOUTH(uc, i) - 2 * m) +
                                     ihz2 * (UP(uc, i) + DOWN(uc, i) - 2 * m));
        }
    }
}

// Perona-Malik u_t = div(g grad u) with g read per face from the difference of `us` across
// it, as a gradient (over the spacing): us = u is the plain flow, us = G_s * u Catte's
// regularised one. EDGE 0: g = exp(-(d/K)^2); 1: g = 1 / (1 + (d/K)^2). g <= 1, so the heat
// step's limit holds.
inline REAL pm_face(const REAL d, const REAL ds, const REAL inv_k2, const int edge)
{
    const REAL s2 = ds * ds * inv_k2;
    return d * (edge == 0 ? EXP(-s2) : (REAL)1 / (1 + s2));
}

__kernel void volume_pm_step(__global const REAL* restrict u, __global const REAL* restrict us,
                             __global REAL* restrict v, const REAL dt, const REAL inv_k2,
                             const int edge, const REAL ihx, const REAL ihy, const REAL ihz,
                             VOL_ARGS)
{
    FOR_EACH_VOXEL(i, x, y, z) {
        for (int c = 0; c < nch; ++c) {
            __global const REAL* uc = u + c * n;
            __global const REAL* sc = us + c * n;
            const REAL m = uc[i], s = sc[i];
            const REAL fx = pm_face(EAST(uc, i) - m, (EAST(sc, i) - s) * ihx, inv_k2, edge) +
                            pm_face(WEST(uc, i) - m, (WEST(sc, i) - s) * ihx, inv_k2, edge);
            const REAL fy = pm_face(NORTH(uc, i) - m, (NORTH(sc, i) - s) * ihy, inv_k2, edge) +
                            pm_face(SOUTH(uc, i) - m, (SOUTH(sc, i) - s) * ihy, inv_k2, edge);
            const REAL fz = pm_face(UP(uc, i) - m, (UP(sc, i) - s) * ihz, inv_k2, edge) +
                            pm_face(DOWN(uc, i) - m, (DOWN(sc, i) - s) * ihz, inv_k2, edge);
            v[c * n + i] = m + dt * (ihx * ihx * fx + ihy * ihy * fy + ihz * ihz * fz);
        }
    }
}

// The TV flow u_t = div(grad u / |grad u|_eps) as div(g grad u) with g = 1 / |grad u|_eps per
// voxel (forward differences), averaged onto each face by volume_tv_step. g <= 1/eps, so
// dt <= eps / (2 sum 1/h^2) is stable.
__kernel void volume_tv_conductance(__global const REAL* restrict u, __global REAL* restrict g,
                                    const REAL eps2, const REAL ihx, const REAL ihy,
                                    const REAL ihz, VOL_ARGS)
{
    FOR_EACH_VOXEL(i, x, y, z) {
        for (int c = 0; c < nch; ++c) {
            __global const REAL* uc = u + c * n;
            const REAL m = uc[i];
            const REAL gx = (EAST(uc, i) - m) * ihx, gy = (NORTH(uc, i) - m) * ihy;
            const REAL gz = (UP(uc, i) - m) * ihz;
            g[c * n + i] = RSQRT(gx * gx + gy * gy + gz * gz + eps2);
        }
    }
}

__kernel void volume_tv_step(__global const REAL* restrict u, __global const REAL* restrict g,
                             __global REAL* restrict v, const REAL dt, const REAL ihx2,
                             const REAL ihy2, const REAL ihz2, VOL_ARGS)
{
    FOR_EACH_VOXEL(i, x, y, z) {
        for (int c = 0; c < nch; ++c) {
            __global const REAL* uc = u + c * n;
            __global const REAL* gc = g + c * n;
            const REAL m = uc[i], h = gc[i];
            // beyond the border the difference is zero, whatever the face's conductance
            const REAL fx = (EAST(gc, i) + h) * (EAST(uc, i) - m) +
                            (WEST(gc, i) + h) * (WEST(uc, i) - m);
            const REAL fy = (NORTH(gc, i) + h) * (NORTH(uc, i) - m) +
                            (SOUTH(gc, i) + h) * (SOUTH(uc, i) - m);
            const REAL fz = (UP(gc, i) + h) * (UP(uc, i) - m) +
                            (DOWN(gc, i) + h) * (DOWN(uc, i) - m);
            v[c * n + i] = m + dt * (REAL)0.5 * (ihx2 * fx + ihy2 * fy + ihz2 * fz);
        }
    }
}

// Level-set mean curvature flow u_t = |grad u| div(grad u / |grad u|)
//   = [(uyy + uzz) ux^2 + (uxx + uzz) uy^2 + (uxx + uyy) uz^2
//      - 2 (ux uy uxy + ux uz uxz + uy uz uyz)] / (|grad u|^2 + eps),
// central differences over the spacing (the planar curvature_step's, kernels/common/
// stencil.h, in 3D); a neighbour beyond the border is the voxel's own index along that
// axis, diagonal ones included (Neumann, as tests/reference/volumes.py's _shift).
__kernel void volume_curvature_step(__global const REAL* restrict u, __global REAL* restrict v,
                                    const REAL dt, const REAL eps, const REAL ihx,
                                    const REAL ihy, const REAL ihz, VOL_ARGS)
{
    FOR_EACH_VOXEL(i, x, y, z) {
        const int xp = x < nx - 1 ? 1 : 0, xm = x > 0 ? -1 : 0;
        const int yp = y < ny - 1 ? nx : 0, ym = y > 0 ? -nx : 0;
        const int zp = z < nz - 1 ? nx * ny : 0, zm = z > 0 ? -nx * ny : 0;
        for (int c = 0; c < nch; ++c) {
            __global const REAL* uc = u + c * n + i;
            const REAL m = uc[0];
            const REAL ux = (REAL)0.5 * ihx * (uc[xp] - uc[xm]);
            const REAL uy = (REAL)0.5 * ihy * (uc[yp] - uc[ym]);
            const REAL uz = (REAL)0.5 * ihz * (uc[zp] - uc[zm]);
            const REAL uxx = ihx * ihx * (uc[xp] - 2 * m + uc[xm]);
            const REAL uyy = ihy * ihy * (uc[yp] - 2 * m + uc[ym]);
            const REAL uzz = ihz * ihz * (uc[zp] - 2 * m + uc[zm]);
            const REAL uxy = (REAL)0.25 * ihx * ihy *
                             (uc[xp + yp] - uc[xm + yp] - uc[xp + ym] + uc[xm + ym]);
            const REAL uxz = (REAL)0.25 * ihx * ihz *
                             (uc[xp + zp] - uc[xm + zp] - uc[xp + zm] + uc[xm + zm]);
            const REAL uyz = (REAL)0.25 * ihy * ihz *
                             (uc[yp + zp] - uc[ym + zp] - uc[yp + zm] + uc[ym + zm]);
            const REAL num = (uyy + uzz) * ux * ux + (uxx + uzz) * uy * uy +
                             (uxx + uyy) * uz * uz -
                             2 * (ux * uy * uxy + ux * uz * uxz + uy * uz * uyz);
            v[c * n + i] = m + dt * num / (ux * ux + uy * uy + uz * uz + eps);
        }
    }
}

// One axis of a separable Gaussian (Catte's pre-smoothing): weights w[0..radius] for offsets
// +-k, mirrored at the border (index -1 reads 0). axis 0 is x, 1 y, 2 z.
inline int volume_mirror(int k, const int m)
{
    for (int pass = 0; pass < 8 && (k < 0 || k >= m); ++pass) k = k < 0 ? -k - 1 : 2 * m - k - 1;
    return clamp(k, 0, m - 1);
}

__kernel void volume_gauss_axis(__global const REAL* restrict u, __global REAL* restrict v,
                                __global const REAL* restrict w, const int radius,
                                const int axis, VOL_ARGS)
{
    FOR_EACH_VOXEL(i, x, y, z) {
        const int pos = axis == 0 ? x : axis == 1 ? y : z;
        const int len = axis == 0 ? nx : axis == 1 ? ny : nz;
        const int stride = axis == 0 ? 1 : axis == 1 ? nx : nx * ny;
        const int base = i - pos * stride;
        for (int c = 0; c < nch; ++c) {
            __global const REAL* uc = u + c * n + base;
            REAL acc = w[0] * uc[pos * stride];
            for (int k = 1; k <= radius; ++k)
                acc += w[k] * (uc[volume_mirror(pos - k, len) * stride] +
                               uc[volume_mirror(pos + k, len) * stride]);
            v[c * n + i] = acc;
        }
    }
}

// ---- harmonic fill --------------------------------------------------------------------
// One red-black SOR half-sweep of Lap u = 0 (seven points, with spacing) over the voxels of
// `hole` whose parity (x + y + z) % 2 equals `colour`: u <- u + omega (mean - u), the mean
// weighted by 1/h^2 over the neighbours inside the box (Neumann at the box's border; voxels
// outside the hole hold the known values). In place: a colour's voxels read only the other's.
__kernel void volume_harmonic_sweep(__global REAL* restrict u,
                                    __global const uchar* restrict hole, const int colour,
                                    const REAL omega, const REAL ihx2, const REAL ihy2,
                                    const REAL ihz2, VOL_ARGS)
{
    FOR_EACH_VOXEL(i, x, y, z) {
        if (!hole[i] || ((x + y + z) & 1) != colour) continue;
        for (int c = 0; c < nch; ++c) {
            __global REAL* uc = u + c * n;
            REAL sum = 0, weight = 0;
            if (x > 0) { sum += ihx2 * uc[i - 1]; weight += ihx2; }
            if (x < nx - 1) { sum += ihx2 * uc[i + 1]; weight += ihx2; }
            if (y > 0) { sum += ihy2 * uc[i - nx]; weight += ihy2; }
            if (y < ny - 1) { sum += ihy2 * uc[i + nx]; weight += ihy2; }
            if (z > 0) { sum += ihz2 * uc[i - nx * ny]; weight += ihz2; }
            if (z < nz - 1) { sum += ihz2 * uc[i + nx * ny]; weight += ihz2; }
            uc[i] += omega * (sum / weight - uc[i]);
        }
    }
}

// ---- biharmonic fill ------------------------------------------------------------------
// L(L u) = 0 at the hole's voxels, L the seven-point Laplacian with spacing and Neumann
// borders (the box's: a neighbour outside it is the voxel itself), solved for one channel
// by conjugate gradients on A = (L L) restricted to the hole (symmetric positive definite),
// from x the harmonic fill (clpde/volumes/biharmonic.py). The boxes are small and CG needs
// two sums per iteration, so one work-group runs the whole solve: barriers instead of a
// launch and a read-back per step. Work-item k takes the voxels k, k + G, k + 2G, ...
inline REAL box_laplacian(__global const REAL* u, const int i, const int nx, const int ny,
                          const int nz, const REAL ihx2, const REAL ihy2, const REAL ihz2)
{
    const int x = i % nx, y = (i / nx) % ny, z = i / (nx * ny);
    const REAL m = u[i];
    return ihx2 * (EAST(u, i) + WEST(u, i) - 2 * m) + ihy2 * (NORTH(u, i) + SOUTH(u, i) - 2 * m) +
           ihz2 * (UP(u, i) + DOWN(u, i) - 2 * m);
}

// The work-group's sum of each item's v (sum[] holds G = a power of two entries).
inline REAL group_sum(REAL v, __local REAL* sum)
{
    const int k = get_local_id(0), g = get_local_size(0);
    sum[k] = v;
    barrier(CLK_LOCAL_MEM_FENCE);
    for (int w = g / 2; w > 0; w /= 2) {
        if (k < w) sum[k] += sum[k + w];
        barrier(CLK_LOCAL_MEM_FENCE);
    }
    const REAL total = sum[0];
    barrier(CLK_LOCAL_MEM_FENCE);
    return total;
}

#define BOTH_FENCES (CLK_GLOBAL_MEM_FENCE | CLK_LOCAL_MEM_FENCE)
#define LAP(u, i) box_laplacian(u, i, nx, ny, nz, ihx2, ihy2, ihz2)

// x: the start, then the fill. r, p, t, ap: scratch of the box's size. Stops after
// `iterations` or when |r|^2 fell below rtol2 times its start; steps[0] gets the count.
__kernel void volume_biharmonic_cg(__global REAL* restrict x, __global REAL* restrict r,
                                   __global REAL* restrict p, __global REAL* restrict t,
                                   __global REAL* restrict ap,
                                   __global const uchar* restrict hole, __local REAL* sum,
                                   __global int* restrict steps, const int iterations,
                                   const REAL rtol2, const REAL ihx2, const REAL ihy2,
                                   const REAL ihz2, const int nx, const int ny, const int nz)
{
    const int n = nx * ny * nz, k0 = get_local_id(0), g = get_local_size(0);
    for (int i = k0; i < n; i += g) t[i] = LAP(x, i);
    barrier(BOTH_FENCES);
    REAL acc = 0;
    for (int i = k0; i < n; i += g) {
        const REAL v = hole[i] ? -LAP(t, i) : (REAL)0;  // r = -A x: the correction's rhs
        r[i] = v;
        p[i] = v;
        acc += v * v;
    }
    REAL rr = group_sum(acc, sum);
    barrier(BOTH_FENCES);
    const REAL stop = rtol2 * rr;
    int step = 0;
    for (; step < iterations && rr > stop && rr > 0; ++step) {
        for (int i = k0; i < n; i += g) t[i] = LAP(p, i);
        barrier(BOTH_FENCES);
        acc = 0;
        for (int i = k0; i < n; i += g) {
            const REAL v = hole[i] ? LAP(t, i) : (REAL)0;
            ap[i] = v;
            acc += p[i] * v;
        }
        const REAL alpha = rr / group_sum(acc, sum);
        acc = 0;
        for (int i = k0; i < n; i += g) {
            x[i] += alpha * p[i];
            const REAL v = r[i] - alpha * ap[i];
            r[i] = v;
            acc += v * v;
        }
        const REAL rr_new = group_sum(acc, sum);
        const REAL beta = rr_new / rr;
        for (int i = k0; i < n; i += g) p[i] = r[i] + beta * p[i];
        rr = rr_new;
        barrier(BOTH_FENCES);  // p is read across items by the next L p
    }
    if (k0 == 0) steps[0] = step;
}

// ---- spectral fill: sparsity in 4 x 4 x 4 DCT blocks --------------------------------------
// Every 4^3 block of the box (each corner, so every shift) that holds a hole voxel is taken
// to its orthonormal DCT-II, its coefficients below `threshold` are zeroed (the mean is
// kept), and it is taken back (volume_threshold_blocks, one work-item per block, into
// out[64 b + j]); each hole voxel then becomes the mean of its blocks' values
// (volume_average_blocks). The host lowers the threshold from launch pair to launch pair.

// The orthonormal 4-point DCT-II, X_k = a_k sum_m cos(pi (2 m + 1) k / 8) x_m (a_0 = 1/2,
// a_k = 1/sqrt(2)), as butterflies; C1 = cos(pi/8) / sqrt(2), C3 = cos(3 pi/8) / sqrt(2).
#define VOLUME_C1 ((REAL)0.6532814824381883)
#define VOLUME_C3 ((REAL)0.2705980500730985)

#if REAL_IS_DOUBLE
#define VOLUME_REAL4 double4
#else
#define VOLUME_REAL4 float4
#endif

// One 4-point transform of four values (forward: the DCT; else its inverse), as a macro
// so that it serves rows of four x positions (the y and z transforms) and scalars (x).
#define VOLUME_DCT4_FWD(T, a, b, c, d)                                                   \
    {                                                                                    \
        const T s0 = a + d, s1 = b + c, d0 = a - d, d1 = b - c;                          \
        a = (REAL)0.5 * (s0 + s1);                                                       \
        b = VOLUME_C1 * d0 + VOLUME_C3 * d1;                                             \
        c = (REAL)0.5 * (s0 - s1);                                                       \
        d = VOLUME_C3 * d0 - VOLUME_C1 * d1;                                             \
    }
#define VOLUME_DCT4_INV(T, a, b, c, d)                                                   \
    {                                                                                    \
        const T e0 = (REAL)0.5 * (a + c), e1 = (REAL)0.5 * (a - c);                      \
        const T o0 = VOLUME_C1 * b + VOLUME_C3 * d, o1 = VOLUME_C3 * b - VOLUME_C1 * d;  \
        a = e0 + o0;                                                                     \
        b = e1 + o1;                                                                     \
        c = e1 - o1;                                                                     \
        d = e0 - o0;                                                                     \
    }

// The block as 16 rows r[4 z + y] of four x values: y and z transforms act on whole rows,
// the x transform inside each row.
inline void volume_dct4_block(VOLUME_REAL4* r, const int inverse)
{
    for (int j = 0; j < 16; ++j) {
        REAL a = r[j].x, b = r[j].y, c = r[j].z, d = r[j].w;
        if (inverse) VOLUME_DCT4_INV(REAL, a, b, c, d) else VOLUME_DCT4_FWD(REAL, a, b, c, d)
        r[j] = (VOLUME_REAL4)(a, b, c, d);
    }
    for (int z = 0; z < 4; ++z) {
        VOLUME_REAL4* q = r + 4 * z;  // along y
        if (inverse) VOLUME_DCT4_INV(VOLUME_REAL4, q[0], q[1], q[2], q[3])
        else VOLUME_DCT4_FWD(VOLUME_REAL4, q[0], q[1], q[2], q[3])
    }
    for (int y = 0; y < 4; ++y) {  // along z
        if (inverse) VOLUME_DCT4_INV(VOLUME_REAL4, r[y], r[4 + y], r[8 + y], r[12 + y])
        else VOLUME_DCT4_FWD(VOLUME_REAL4, r[y], r[4 + y], r[8 + y], r[12 + y])
    }
}

// corner[b]: the index of block b's first voxel in the (nz, ny, nx) box.
__kernel void volume_threshold_blocks(__global const REAL* restrict u,
                                      __global const int* restrict corner, const int blocks,
                                      const REAL threshold, __global REAL* restrict out,
                                      const int nx, const int ny)
{
    const int b = get_global_id(0);
    if (b >= blocks) return;
    const int c0 = corner[b];
    VOLUME_REAL4 r[16];
    for (int j = 0; j < 16; ++j) r[j] = vload4(0, u + c0 + ((j >> 2) * ny + (j & 3)) * nx);
    volume_dct4_block(r, 0);
    const VOLUME_REAL4 zero = (VOLUME_REAL4)(0), t = (VOLUME_REAL4)(threshold);
    const REAL mean = r[0].x;
    for (int j = 0; j < 16; ++j) r[j] = select(r[j], zero, isless(fabs(r[j]), t));
    r[0].x = mean;
    volume_dct4_block(r, 1);
    for (int j = 0; j < 16; ++j) vstore4(r[j], 0, out + 64 * b + 4 * j);
}

// voxels[k]: the hole's voxel indices; block_of[i]: the block whose corner is voxel i, or -1.
__kernel void volume_average_blocks(__global REAL* restrict u,
                                    __global const int* restrict voxels, const int count,
                                    __global const int* restrict block_of,
                                    __global const REAL* restrict values, const int nx,
                                    const int ny)
{
    const int k = get_global_id(0);
    if (k >= count) return;
    const int i = voxels[k], x = i % nx, y = (i / nx) % ny, z = i / (nx * ny);
    REAL sum = 0;
    int hits = 0;
    for (int dz = 0; dz < 4 && dz <= z; ++dz)
        for (int dy = 0; dy < 4 && dy <= y; ++dy)
            for (int dx = 0; dx < 4 && dx <= x; ++dx) {
                const int b = block_of[i - (dz * ny + dy) * nx - dx];
                if (b >= 0) {
                    sum += values[64 * b + (dz * 4 + dy) * 4 + dx];
                    ++hits;
                }
            }
    if (hits > 0) u[i] = sum / hits;
}
