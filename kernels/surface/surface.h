// Helpers shared by the surface kernel files (surface_*.cl, bricks.cl). Include after
// common.h.
//
// Volumes are ghost-padded 3D arrays, layout (channels, nz + 2G, ny + 2G, nx + 2G), x
// fastest: `sx` is the row stride, `sxy` the slab stride and `plane` (LIST_ARGS) the channel
// stride. Kernels visit the cells of a compacted band list (flat padded indices, built on
// the device by fields.cl's compaction) and never test for borders: the band keeps clear of
// the ghost layer by construction.
//
// Accuracy: data is kept constant along the normals by closest-point re-extension of the whole
// band after every step (surface/extend.cl). Without it the 2001 scheme drifts off the surface
// and its error grows under refinement.
//
// The files, one family each (thesis chapter 4, appendices B-E):
//   surface/band.cl    closest points and their stencils (once per psi; the bands and their
//                      runs are common/grid3d.cl's)
//   surface/extend.cl  closest-point re-extension, sampling, extension by the PDE
//   surface/heat.cl    the heat flow (4.7, 4.8) and Turk's reaction-diffusion
//   surface/flows.cl   TV, harmonic maps, diffusion along a field; TV's dynamic lambda
//   surface/reinit.cl  reinitialisation of psi to a signed distance
//   surface/shape.cl   principal curvature directions
//   surface/mesh.cl    mesh -> distance (exact point-triangle distances)
//   surface/flux.h     the flows' per-cell arithmetic, shared by the lists' and the bricks'
//   bricks.cl          every flow and the re-extension on dense bricks
//   bricks/tiles.cl     bricks' tiles of a device volume (psi's, once per psi)
#ifndef CLPDE_SURFACE_H
#define CLPDE_SURFACE_H

// INTERP 3: tricubic Lagrange interpolation (4x4x4 nodes); 1: trilinear (2x2x2).
#ifndef INTERP
#define INTERP 3
#endif
// Channels handled together by one work-item in the extension and sampling kernels.
#ifndef NC
#define NC 1
#endif

#ifdef REAL_IS_DOUBLE
#define REAL2 double2
#define REAL4 double4
#else
#define REAL2 float2
#define REAL4 float4
#endif
// Four consecutive REALs read as one vector at any REAL-aligned address (PoCL's vload4 is an
// out-of-line call; this is a plain unaligned vector load).
typedef REAL4 __attribute__((aligned(sizeof(REAL)))) unaligned_real4;
#define LOAD4(p) (*(__global const unaligned_real4*)(p))

// Interpolation nodes per axis: 4 (tricubic Lagrange) or 2 (trilinear).
#if INTERP == 3
#define NODES 4
#else
#define NODES 2
#endif

// Weights of the nodes along one axis from the position t in [0, 1) relative to floor(p):
// axis_weights' polynomials, the four cubic ones expanded in powers of t and computed at once.
#if INTERP == 3
#define NODE_WEIGHTS REAL4
INLINE REAL4 node_weights(const REAL t)
{
    const REAL4 c3 = (REAL4)(-1, 3, -3, 1) / 6;
    const REAL4 c2 = (REAL4)(3, -6, 3, 0) / 6;
    const REAL4 c1 = (REAL4)(-2, -3, 6, -1) / 6;
    const REAL4 c0 = (REAL4)(0, 1, 0, 0);
    return ((c3 * t + c2) * t + c1) * t + c0;
}
#else
#define NODE_WEIGHTS REAL2
INLINE REAL2 node_weights(const REAL t) { return (REAL2)(1 - t, t); }
#endif

// LINE_FIELD: u is a line field (u and -u mean the same line, e.g. principal directions):
// every vector a step or the re-extension reads is first turned to the side of a reference
// vector u(ref) (the updated cell's own; floor(cp)'s node), so sign flips between neighbours
// are not mistaken for jumps.
#ifndef LINE_FIELD
#define LINE_FIELD 0
#endif

// +1 or -1: the sign that turns the NC-vector at p to the side of the one at ref.
INLINE REAL line_sign(__global const REAL* restrict u, const int ref, const int p,
                      const int plane)
{
    REAL dot = 0;
    #pragma unroll
    for (int c = 0; c < NC; ++c) dot += u[c * plane + ref] * u[c * plane + p];
    return dot < 0 ? (REAL)-1 : (REAL)1;
}

#define ONE_SIDED_SIGN(e) ((e) > 0 ? (REAL)1 : (REAL)-1)

typedef struct { REAL x, y, z; } vec3r;

INLINE vec3r psi_normal(__global const REAL* restrict psi, const int j, const int sx,
                        const int sxy)
{
    vec3r n;
    n.x = (REAL)0.5 * (psi[j + 1] - psi[j - 1]);
    n.y = (REAL)0.5 * (psi[j + sx] - psi[j - sx]);
    n.z = (REAL)0.5 * (psi[j + sxy] - psi[j - sxy]);
    return n;
}

#endif
