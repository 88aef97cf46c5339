// The surface's shape from psi (clpde/surface/flows.py): principal curvature directions.
// Layout and conventions: surface.h.
#include "common.h"
#include "surface/surface.h"

// ---- principal curvature directions ---------------------------------------------------------
// Hessian of psi by central differences, restricted to the tangent plane spanned by an
// orthonormal pair (t1, t2) orthogonal to N; the 2x2 form's eigenvectors are the principal
// directions and its eigenvalues the principal curvatures (1/R for a sphere of radius R, psi
// negative inside). For a distance function the directions are constant along the normals,
// so every band cell gets its own values, no interpolation. Outputs per band entry k: the major direction (larger curvature) in
// dir[0..2][k], the minor in dir[3..5][k] and the curvatures in curv[0..1][k] (world units).
__kernel void shape_principal_directions(__global const REAL* restrict psi, const REAL inv_h,
                                   __global REAL* restrict dir, __global REAL* restrict curv,
                                   const int sx, const int sxy, LIST_ARGS)
{
    LIST_RANGE(k0, k1, chan);
    for (int k = k0; k < k1; ++k) {
        const int i = list[k];
        const vec3r g = psi_normal(psi, i, sx, sxy);
        const REAL inv = RSQRT(g.x * g.x + g.y * g.y + g.z * g.z + (REAL)1e-30);
        const REAL nx = g.x * inv, ny = g.y * inv, nz = g.z * inv;
        const REAL c = psi[i];
        const REAL hxx = psi[i + 1] - 2 * c + psi[i - 1];
        const REAL hyy = psi[i + sx] - 2 * c + psi[i - sx];
        const REAL hzz = psi[i + sxy] - 2 * c + psi[i - sxy];
        const REAL hxy = (REAL)0.25 * (psi[i + 1 + sx] - psi[i - 1 + sx] - psi[i + 1 - sx] + psi[i - 1 - sx]);
        const REAL hxz = (REAL)0.25 * (psi[i + 1 + sxy] - psi[i - 1 + sxy] - psi[i + 1 - sxy] + psi[i - 1 - sxy]);
        const REAL hyz = (REAL)0.25 * (psi[i + sx + sxy] - psi[i - sx + sxy] - psi[i + sx - sxy] + psi[i - sx - sxy]);
        // t1 = N x e, e the axis least aligned with N; t2 = N x t1
        REAL ex = 0, ey = 0, ez = 0;
        if (FABS(nx) <= FABS(ny) && FABS(nx) <= FABS(nz)) ex = 1;
        else if (FABS(ny) <= FABS(nz)) ey = 1;
        else ez = 1;
        REAL ax = ny * ez - nz * ey, ay = nz * ex - nx * ez, az = nx * ey - ny * ex;
        const REAL ia = RSQRT(ax * ax + ay * ay + az * az);
        ax *= ia; ay *= ia; az *= ia;
        const REAL bx = ny * az - nz * ay, by = nz * ax - nx * az, bz = nx * ay - ny * ax;
        // H t for t = a and t = b
        const REAL hax = hxx * ax + hxy * ay + hxz * az, hay = hxy * ax + hyy * ay + hyz * az,
                   haz = hxz * ax + hyz * ay + hzz * az;
        const REAL hbx = hxx * bx + hxy * by + hxz * bz, hby = hxy * bx + hyy * by + hyz * bz,
                   hbz = hxz * bx + hyz * by + hzz * bz;
        const REAL p = ax * hax + ay * hay + az * haz;
        const REAL q = ax * hbx + ay * hby + az * hbz;
        const REAL r = bx * hbx + by * hby + bz * hbz;
        const REAL mean = (REAL)0.5 * (p + r);
        const REAL dev = SQRT(SQR((REAL)0.5 * (p - r)) + q * q);
        const REAL theta = (REAL)0.5 * atan2(2 * q, p - r);
        const REAL ct = cos(theta), st = sin(theta);
        dir[k] = ct * ax + st * bx;
        dir[nlist + k] = ct * ay + st * by;
        dir[2 * nlist + k] = ct * az + st * bz;
        dir[3 * nlist + k] = -st * ax + ct * bx;
        dir[4 * nlist + k] = -st * ay + ct * by;
        dir[5 * nlist + k] = -st * az + ct * bz;
        // curvature = tangential Hessian / |grad psi| in world units: second differences
        // are h^2 psi'' and |grad psi| = 1 / (inv h), so the factor is inv / h
        const REAL scale = inv * inv_h;
        // a distance function's level set at distance d = psi has curvatures k / (1 + d k):
        // undo that so every band cell carries the surface's own curvatures
        const REAL k1 = (mean + dev) * scale, k2 = (mean - dev) * scale;
        curv[k] = k1 / (1 - c * k1);
        curv[nlist + k] = k2 / (1 - c * k2);
    }
}
