// The 2D band in bricks (clpde/tracking/levelset.py, LevelSet(layout='bricks8x8' or 'bricks16x4')):
// the band's work goes in BX x BY bricks of the dense padded frame instead of a list of
// cells. The values stay in the frame (the features are dense frames), so a brick is a unit
// of work, not of storage: `bricks` lists the bricks that hold a band cell, by their index
// bx + nbx by over the movable region [x0, x1) x [y0, y1) (padded coordinates; bricks at
// its far edges are cut short), and a kernel visits every movable cell of its bricks and
// tests the band's mask, so each cell runs the same inline arithmetic as in the list kernels.
//
// Launch geometry (GROUP_PER_BRICK): on CPUs (0) one work-item walks per_item whole bricks,
// row after row; on GPUs (1) one work-group of BX BY work-items takes a brick, one cell each.
#ifndef CLPDE_BRICKS2D_H
#define CLPDE_BRICKS2D_H

#ifndef BX
#define BX 8
#endif
#ifndef BY
#define BY 8
#endif
#ifndef GROUP_PER_BRICK
#define GROUP_PER_BRICK 0
#endif

// Arguments every 2D brick kernel takes last (LevelSet.launch_band); rs is the row stride.
#define BRICK2D_ARGS __global const int* restrict bricks, const int nbricks, const int nbx, \
                     const int x0, const int y0, const int x1, const int y1, const int rs,  \
                     const int per_item

// Loop over the movable cells of this work-item's bricks; `i` is the padded linear index.
#if GROUP_PER_BRICK
#define FOR_EACH_BRICK_CELL(i)                                                           \
    for (int b_ = get_group_id(0), l_ = get_local_id(0), once_ = b_ < nbricks; once_;   \
         once_ = 0)                                                                      \
        for (int ox_ = x0 + (bricks[b_] % nbx) * BX + l_ % BX,                           \
                 oy_ = y0 + (bricks[b_] / nbx) * BY + l_ / BX, i = oy_ * rs + ox_,       \
                 in_ = (ox_ < x1) & (oy_ < y1); in_; in_ = 0)
#else
#define FOR_EACH_BRICK_CELL(i)                                                           \
    for (int b_ = get_global_id(0) * per_item,                                           \
             e_ = min(b_ + per_item, nbricks); b_ < e_; ++b_)                            \
        for (int ox_ = x0 + (bricks[b_] % nbx) * BX, oy_ = y0 + (bricks[b_] / nbx) * BY,  \
                 y_ = oy_, xe_ = min(ox_ + BX, x1); y_ < min(oy_ + BY, y1); ++y_)        \
            for (int i = y_ * rs + ox_; i < y_ * rs + xe_; ++i)
#endif

#endif
