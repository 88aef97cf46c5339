// Inpainting on implicit surfaces (clpde/surface/inpainting.py): data missing over part of the
// surface is filled by a PDE written intrinsically (chapter 4), stepped over the hole's
// cells only; the known cells hold their data, extended along the normals, throughout
// (the Dirichlet condition). Defines: NC. Layout and conventions: surface.h.
// flux.h's TV flux (FLOW_P 1) for the transport's anisotropic diffusion; the harmonic fill
// uses heat_div, which FLOW_P leaves alone.
#define FLOW_P 1
#include "common.h"
#include "surface/surface.h"
#include "surface/flux.h"

#define NEG(a) ((a) < 0 ? (a) : (REAL)0)
#define POS(a) ((a) > 0 ? (a) : (REAL)0)

// The intrinsic Laplacian (appendix E's scheme, grid units) of channel array u at cell i,
// averaged over the two complementary one-sided choices (forward gradient / backward
// divergence and the reverse): one fixed operator, so the fill has a steady state to
// converge to (the flows' cycling through eight choices has none), and the first-order
// terms of the two choices cancel.
INLINE REAL lb_cell(__global const REAL* restrict u, const int i,
                    __global const REAL* restrict psi, const int sx, const int sxy)
{
    return (REAL)0.5 * (heat_div(u, i, 1, sx, sxy, psi, i, sx, sxy) +
                        heat_div(u, i, -1, -sx, -sxy, psi, i, sx, sxy));
}

// One step of the harmonic fill, Laplace-Beltrami u = 0 in the hole, at the hole's nodes:
// Chebyshev's semi-iterative method (second-order Richardson) in the closest-point form,
//   x_new = u + mom (u - prev) + gain * LB(u),   u = E x,
// u being the node values x re-extended over the hole's reach band (extend.cl's extend_cp:
// the step starts from the extended value, not from x, else x - E x has growing modes).
// mom = 0, gain = r is the explicit heat step. prev takes u; change[c * nlist + k] takes
// |u - prev|, the last step's change, which the host reads every so many steps to stop.
// (Not |x_new - u|: at the steady state of the closest-point form, x differs from its own
// re-extension E x by gain * LB(u), which is of the order of the scheme's error, not 0.)
__kernel void inpaint_harmonic_step(__global const REAL* restrict u, __global REAL* restrict x,
                                    __global REAL* restrict prev,
                                    __global const REAL* restrict psi, const REAL mom,
                                    const REAL gain, __global REAL* restrict change,
                                    const int sx, const int sxy, LIST_ARGS)
{
    LIST_RANGE(k0, k1, chan);
    const int c = get_global_id(1);
    for (int k = k0; k < k1; ++k) {
        const int i = list[k];
        const REAL ui = u[chan + i];
        const REAL moved = ui - prev[chan + i];
        x[chan + i] = ui + mom * moved + gain * lb_cell(u + chan, i, psi, sx, sxy);
        prev[chan + i] = ui;
        change[c * nlist + k] = FABS(moved);
    }
}

// ---- the thesis' transport inpainting (chapter 3, appendix A) written intrinsically ----------
// Every derivative is taken in the embedding's Cartesian grid on data kept constant along the
// normals, and projected on the tangent plane (P_N, N from central differences of psi), as
// chapter 4 writes its flows: the surface gradient, the Laplace-Beltrami operator and the
// isophote direction N x grad_S u all come from the fixed grid. Grid units throughout, and
// appendix A's scaling of the terms (delta L over two cells), so dt means what it means in
// the plane (clpde/inpainting/transport.py).

// The Laplace-Beltrami operator of u at the listed nodes into lap (the smoothness L that the
// transport carries; the host re-extends it along the normals around the hole).
__kernel void inpaint_lap(__global const REAL* restrict u, __global REAL* restrict lap,
                          __global const REAL* restrict psi, const int sx, const int sxy,
                          LIST_ARGS)
{
    LIST_RANGE(k0, k1, chan);
    for (int k = k0; k < k1; ++k) {
        const int i = list[k];
        lap[chan + i] = lb_cell(u + chan, i, psi, sx, sxy);
    }
}

INLINE vec3r tangential(const vec3r v, const vec3r n)
{
    const REAL s = v.x * n.x + v.y * n.y + v.z * n.z;
    vec3r t;
    t.x = v.x - s * n.x;
    t.y = v.y - s * n.y;
    t.z = v.z - s * n.z;
    return t;
}

// One transport step at the hole's nodes, eqs. (3.5)-(3.11) on the surface:
//   beta = P grad L . (n x P grad u) / |P grad u|,   u_t = beta |grad u|_upwind,
// with central differences for grad L (over two cells, eq. 3.7) and grad u (over one), n the
// unit normal, and appendix A's slope-limited |grad u| on the three axes (the data is constant
// along the normals, so the Cartesian gradient is the surface's). n x P grad u turns the
// gradient a quarter counter-clockwise seen from outside: in the plane z = 0 with n = z it is
// (-u_y, u_x), the plane's choice. x takes the stepped value, clamped to the channel's
// [bounds[2c], bounds[2c + 1]], change |x - u|.
__kernel void inpaint_transport_step(__global const REAL* restrict u, __global REAL* restrict x,
                                     __global const REAL* restrict lap,
                                     __global const REAL* restrict psi, const REAL dt,
                                     const REAL grad_eps2, const REAL min_slope2,
                                     __global const REAL* restrict bounds,
                                     __global REAL* restrict change, const int sx,
                                     const int sxy, LIST_ARGS)
{
    LIST_RANGE(k0, k1, chan);
    const int ch = get_global_id(1);
    const REAL lo = bounds[2 * ch], hi = bounds[2 * ch + 1];
    for (int k = k0; k < k1; ++k) {
        const int i = list[k];
        __global const REAL* uc = u + chan;
        __global const REAL* lc = lap + chan;
        vec3r n = psi_normal(psi, i, sx, sxy);
        const REAL inv = RSQRT(n.x * n.x + n.y * n.y + n.z * n.z + (REAL)1e-30);
        n.x *= inv;
        n.y *= inv;
        n.z *= inv;
        const REAL c = uc[i];
        vec3r g, dl;
        g.x = (REAL)0.5 * (uc[i + 1] - uc[i - 1]);
        g.y = (REAL)0.5 * (uc[i + sx] - uc[i - sx]);
        g.z = (REAL)0.5 * (uc[i + sxy] - uc[i - sxy]);
        dl.x = lc[i + 1] - lc[i - 1];
        dl.y = lc[i + sx] - lc[i - sx];
        dl.z = lc[i + sxy] - lc[i - sxy];
        g = tangential(g, n);
        dl = tangential(dl, n);
        // n x g: the isophote's direction, |n x g| = |g|
        const REAL tx = n.y * g.z - n.z * g.y, ty = n.z * g.x - n.x * g.z,
                   tz = n.x * g.y - n.y * g.x;
        const REAL beta = (dl.x * tx + dl.y * ty + dl.z * tz) *
                          RSQRT(g.x * g.x + g.y * g.y + g.z * g.z + grad_eps2);
        const REAL xb = c - uc[i - 1], xf = uc[i + 1] - c;
        const REAL yb = c - uc[i - sx], yf = uc[i + sx] - c;
        const REAL zb = c - uc[i - sxy], zf = uc[i + sxy] - c;
        const REAL up = SQR(NEG(xb)) + SQR(POS(xf)) + SQR(NEG(yb)) + SQR(POS(yf)) +
                        SQR(NEG(zb)) + SQR(POS(zf));
        const REAL down = SQR(POS(xb)) + SQR(NEG(xf)) + SQR(POS(yb)) + SQR(NEG(yf)) +
                          SQR(POS(zb)) + SQR(NEG(zf));
        // clamped to the known data's range (bounds[2c], bounds[2c + 1]): the transport, an
        // upwinded Hamilton-Jacobi equation, keeps to it in the continuum, and where the
        // normals are ill-defined (a mesh's sharp edges) the discrete one can leave it
        // no transport where psi's slope is well below 1 (min_slope2: its square, times h^2):
        // a kink of psi (a mesh's sharp edge, a medial axis) has no normal to project on
        const REAL nn = SQR(n.x / inv) + SQR(n.y / inv) + SQR(n.z / inv);
        const REAL rate = nn > min_slope2 ? beta * SQRT(beta > 0 ? up : down) : (REAL)0;
        const REAL next = clamp(c + dt * rate, lo, hi);
        x[chan + i] = next;
        change[ch * nlist + k] = FABS(next - c);
    }
}

// One step of the anisotropic diffusion (3.4) on the surface at the hole's nodes,
//   u_t = |P grad u| div(P grad u / |P grad u|_e)   (the intrinsic curvature flow),
// the divergence from flux.h's TV flux (FLOW_P 1, the channels' joint gradient of appendix
// D) averaged over the two complementary one-sided choices, |P grad u| that same joint norm
// from central differences. All NC channels per work-item (launch with one channel).
__kernel void inpaint_diffusion_step(__global const REAL* restrict u, __global REAL* restrict x,
                                     __global const REAL* restrict psi, const REAL dt,
                                     const REAL e2, const int sx, const int sxy, LIST_ARGS)
{
    LIST_RANGE(k0, k1, chan);
    for (int k = k0; k < k1; ++k) {
        const int i = list[k];
        REAL fwd[NC], bwd[NC];
        flow_cell(u, plane, i, 1, sx, sxy, psi, psi, plane, i, sx, sxy, e2, (REAL)1, fwd);
        flow_cell(u, plane, i, -1, -sx, -sxy, psi, psi, plane, i, sx, sxy, e2, (REAL)1, bwd);
        vec3r n = psi_normal(psi, i, sx, sxy);
        const REAL inv = RSQRT(n.x * n.x + n.y * n.y + n.z * n.z + (REAL)1e-30);
        n.x *= inv;
        n.y *= inv;
        n.z *= inv;
        REAL g2 = 0;
        #pragma unroll
        for (int c = 0; c < NC; ++c) {
            __global const REAL* uc = u + c * plane;
            vec3r g;
            g.x = (REAL)0.5 * (uc[i + 1] - uc[i - 1]);
            g.y = (REAL)0.5 * (uc[i + sx] - uc[i - sx]);
            g.z = (REAL)0.5 * (uc[i + sxy] - uc[i - sxy]);
            g = tangential(g, n);
            g2 += g.x * g.x + g.y * g.y + g.z * g.z;
        }
        const REAL speed = SQRT(g2);
        #pragma unroll
        for (int c = 0; c < NC; ++c) {
            const REAL uc = u[c * plane + i];
            const REAL div = (REAL)0.5 * ((fwd[c] - uc) + (bwd[c] - uc));
            x[c * plane + i] = uc + dt * speed * div;
        }
    }
}
