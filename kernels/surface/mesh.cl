// Mesh -> distance (clpde/surface/mesh_sdf.py): exact point-triangle distances refined over
// neighbouring cells. Define: WALK.
#include "common.h"
#include "surface/surface.h"

// ---- mesh -> distance: exact point-triangle distances refined over neighbouring cells ------

// Closest point to p on triangle (a, b, c), by the Voronoi regions of its vertices, edges and
// face (as in Ericson's Real-Time Collision Detection, section 5.1.5).
INLINE vec3r v3(const REAL x, const REAL y, const REAL z) { vec3r r; r.x = x; r.y = y; r.z = z; return r; }
INLINE vec3r v3sub(const vec3r a, const vec3r b) { return v3(a.x - b.x, a.y - b.y, a.z - b.z); }
INLINE REAL v3dot(const vec3r a, const vec3r b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
INLINE vec3r v3mad(const vec3r a, const REAL s, const vec3r d) { return v3(a.x + s * d.x, a.y + s * d.y, a.z + s * d.z); }

INLINE vec3r closest_on_triangle(const vec3r p, const vec3r a, const vec3r b, const vec3r c)
{
    const vec3r ab = v3sub(b, a), ac = v3sub(c, a), ap = v3sub(p, a);
    const REAL d1 = v3dot(ab, ap), d2 = v3dot(ac, ap);
    if (d1 <= 0 && d2 <= 0) return a;
    const vec3r bp = v3sub(p, b);
    const REAL d3 = v3dot(ab, bp), d4 = v3dot(ac, bp);
    if (d3 >= 0 && d4 <= d3) return b;
    const REAL vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) return v3mad(a, d1 / (d1 - d3), ab);
    const vec3r cp = v3sub(p, c);
    const REAL d5 = v3dot(ab, cp), d6 = v3dot(ac, cp);
    if (d6 >= 0 && d5 <= d6) return c;
    const REAL vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) return v3mad(a, d2 / (d2 - d6), ac);
    const REAL va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
        return v3mad(b, (d4 - d3) / ((d4 - d3) + (d5 - d6)), v3sub(c, b));
    const REAL denom = 1 / (va + vb + vc);
    return v3mad(v3mad(a, vb * denom, ab), vc * denom, ac);
}

// For each listed cell (flat index into an unpadded nz x ny x nx volume), try the current
// nearest triangle of each of its 27 neighbours (face_in, -1 for none) and keep the closest:
// then walk up to WALK steps across edge-adjacent triangles (nbr: 3 per face, -1 for none)
// while that gets closer. A few passes make every band cell's triangle the nearest one.
// tri: 9 coordinates per face relative to the grid origin, in cells.
#ifndef WALK
#define WALK 8
#endif
__kernel void mesh_refine(__global const int* restrict cells, const int ncells,
                          __global const int* restrict face_in, __global int* restrict face_out,
                          __global REAL* restrict dist, __global REAL* restrict cpt,
                          __global const REAL* restrict tri, __global const int* restrict nbr,
                          const int nx, const int ny, const int nz)
{
    const int k = get_global_id(0);
    if (k >= ncells) return;
    const int i = cells[k];
    const int z = i / (nx * ny), y = (i / nx) % ny, x = i % nx;
    const vec3r p = v3(x, y, z);
    REAL best = INFINITY;
    int best_face = face_in[i];
    vec3r best_cp = p;
    for (int dz = -1; dz <= 1; ++dz)
    for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx) {
        const int xx = clamp(x + dx, 0, nx - 1), yy = clamp(y + dy, 0, ny - 1), zz = clamp(z + dz, 0, nz - 1);
        const int f = face_in[(zz * ny + yy) * nx + xx];
        if (f < 0) continue;
        __global const REAL* t = tri + 9 * f;
        const vec3r q = closest_on_triangle(p, v3(t[0], t[1], t[2]), v3(t[3], t[4], t[5]),
                                            v3(t[6], t[7], t[8]));
        const vec3r d = v3sub(p, q);
        const REAL dd = v3dot(d, d);
        if (dd < best) { best = dd; best_face = f; best_cp = q; }
    }
    // walk across the edges of the mesh from the best triangle while that gets closer
    for (int step = 0; step < WALK && best_face >= 0; ++step) {
        const int from = best_face;
        for (int e = 0; e < 3; ++e) {
            const int f = nbr[3 * from + e];
            if (f < 0) continue;
            __global const REAL* t = tri + 9 * f;
            const vec3r q = closest_on_triangle(p, v3(t[0], t[1], t[2]), v3(t[3], t[4], t[5]),
                                                v3(t[6], t[7], t[8]));
            const vec3r d = v3sub(p, q);
            const REAL dd = v3dot(d, d);
            if (dd < best) { best = dd; best_face = f; best_cp = q; }
        }
        if (best_face == from) break;
    }
    face_out[i] = best_face;
    dist[k] = SQRT(best);
    cpt[3 * k] = best_cp.x;
    cpt[3 * k + 1] = best_cp.y;
    cpt[3 * k + 2] = best_cp.z;
}
