// Brick tiles of a dense padded device volume (clpde/bricks.py, BrickBand.tiles):
// psi's tiles of halo 2, built on the device from the surface's padded psi once per psi, so
// the host never gathers them from a dense copy. Defines: BX, BY, BZ (bricks.h).
#include "common.h"
#include "bricks/bricks.h"

// dst (channels, nbricks + 2, tile cells): tile cell t of stored brick b = 1..nbricks (brick
// coordinates coords[b - 1], x y z) is the cell of src at its place, 0 outside the grid;
// bricks 0 and nbricks + 1 are left as they are (zeros). One work-item per tile cell and
// channel (get_global_id(1)); src's channel stride px py pz.
__kernel void tiles_from_dense(__global const REAL* restrict src, __global REAL* restrict dst,
                               __global const int* restrict coords, const int nbricks,
                               const int halo, const int px, const int py, const int pz)
{
    const int tx = BX + 2 * halo, txy = tx * (BY + 2 * halo), cells = txy * (BZ + 2 * halo);
    const int g = get_global_id(0);
    if (g >= nbricks * cells) return;  // past the last tile (Runtime.items)
    const int b = g / cells, t = g - b * cells;
    const int x = coords[3 * b] * BX + t % tx - halo;
    const int y = coords[3 * b + 1] * BY + (t / tx) % (BY + 2 * halo) - halo;
    const int z = coords[3 * b + 2] * BZ + t / txy - halo;
    const size_t c = get_global_id(1);
    const bool inside = x >= 0 && y >= 0 && z >= 0 && x < px && y < py && z < pz;
    dst[(c * (nbricks + 2) + b + 1) * cells + t] =
        inside ? src[c * px * py * pz + ((size_t)z * py + y) * px + x] : (REAL)0;
}
