"""The band in dense bricks (clpde/bricks.py, kernels/surface/bricks.cl): the layout and its
tables against a loop-by-loop numpy reference, each brick kernel against the dense numpy
reference of the same discrete scheme read through that layout, in both launch geometries
(a work-item walking whole bricks, as on CPUs; a work-group per brick with a local tile, as
on GPUs) and for the three brick sizes measured; and the heat flow on bricks against the
same flow on the band lists."""

import numpy as np
import pyopencl.array as cla
import pytest

from clpde.bricks import APRON, BRICK_SIZES, EXT, NODE, REACH
from clpde.runtime import Runtime
from clpde.surface import ImplicitSurface
from clpde.surface import storage as surface_storage
from clpde.surface.exact import sphere_points, xy_exact
from tests.reference import bricks as bref
from tests.reference import surface as ref


@pytest.fixture(scope="module")
def gpu_like(runtime):
    rt = Runtime(runtime.index, runtime.platform, runtime.device)
    rt.is_cpu = False  # launch geometry only
    return rt


def band_host(band):
    return band.indices.get()[: band.n].astype(np.int64)


def surface(device, brick, h=0.2):
    s = ImplicitSurface.sphere(1.0, h, device=device)
    s.band.brick = brick
    return s


@pytest.mark.parametrize("brick", BRICK_SIZES)
def test_layout_and_tables_match_reference(runtime, brick):
    s = surface(runtime, brick)
    bb, psi, _ = s.band.bricks()
    g = s.grid
    # what is stored: every cell a kernel reads
    node, reach, ext = (band_host(b) for b in (s.node_band, s.reach_band, s.ext_band))
    need = np.zeros(g.padded_shape, bool)
    for cells, reach_cells in ((node, 2), (np.union1d(reach, ext), 1)):
        z, y, x = np.unravel_index(cells, g.padded_shape)
        for axis, c in enumerate((x, y, z)):
            for d in range(-reach_cells, reach_cells + 1):
                shifted = [x, y, z]
                shifted[axis] = c + d
                need[shifted[2], shifted[1], shifted[0]] = True
    coords = bref.brick_coords(need, brick)
    np.testing.assert_array_equal(bb.coords, np.array(coords))
    np.testing.assert_array_equal(bb.nbr.get(), bref.neighbours(coords))
    # psi in tiles of halo 2 and the band bits in brick layout
    expect = bref.to_tiles(g.pad(s.psi[None], mode="linear"), coords, brick, 2)
    np.testing.assert_allclose(psi.get().reshape(expect.shape), expect, atol=1e-6)
    bits = np.zeros(g.padded_shape)
    for cells, bit in ((node, NODE), (reach, REACH), (ext, EXT)):
        bits.reshape(-1)[cells] += bit
    expect_bits = bref.to_bricks(bits[None], coords, brick)[0].reshape(len(coords) + 2, -1)
    np.testing.assert_array_equal(bb.mask_host, expect_bits)
    np.testing.assert_array_equal(
        bb.brick_bits.get(), np.bitwise_or.reduce(expect_bits.astype(np.uint8), axis=1)
    )


@pytest.mark.parametrize("brick", BRICK_SIZES)
def test_tiles_on_the_device_are_the_hosts(runtime, rng, brick):
    """BrickBand.tiles (a device volume's tiles, kernels/bricks/tiles.cl) against scatter_tiles
    (the host's) for two channels and two halos, with bricks in every corner of a grid whose
    sides are no multiples of a brick's (tile cells outside the grid are zeros)."""
    from clpde.bricks import BrickBand

    shape = (21, 19, 27)  # (PZ, PY, PX)
    places = [-(-n // b) for n, b in zip(shape[::-1], brick, strict=True)]
    coords = np.array(
        [
            (x, y, z)
            for x in (0, places[0] - 1)
            for y in (0, places[1] - 1)
            for z in (0, places[2] - 1)
        ]
        + [(1, 1, 1)],
        np.int32,
    )
    bb = BrickBand.from_coords(runtime, shape, coords, brick)
    u = rng.standard_normal((2,) + shape).astype(np.float32)
    for halo in (1, 2):
        host = bb.scatter_tiles(u, np.float32, halo).get()
        dev = bb.tiles(cla.to_device(runtime.queue, u), halo).get()
        np.testing.assert_array_equal(dev, host)
        assert (host[:, 1:-1] == 0).any()  # cells outside the grid
        assert not host[:, 0].any() and not host[:, -1].any()


@pytest.mark.parametrize("geometry", ["cpu", "gpu"])
@pytest.mark.parametrize("brick", BRICK_SIZES)
def test_apron_layout_on_the_device_is_the_hosts(runtime, gpu_like, rng, geometry, brick):
    """brick_to_apron (plain -> apron layout on the device) against scatter with an apron
    (the host's) in every brick with a band cell, wherever the apron's next brick is stored;
    zeros where it is not (bricks without band cells are never read from this layout)."""
    s = surface(runtime if geometry == "cpu" else gpu_like, brick)
    bb, _, _ = s.band.bricks()
    u = rng.standard_normal((2,) + s.grid.padded_shape).astype(np.float32)
    host = bb.scatter(u, np.float32, APRON).get()
    dev = cla.zeros_like(bb.scatter(u, np.float32, APRON))
    flow = surface_storage.BrickFlow.__new__(surface_storage.BrickFlow)
    flow.surf, flow.bricks, flow.defines = s, bb, {}
    bb.launch(
        flow.kernel("surface/bricks.cl", "bricks_to_apron"),
        bb.scatter(u, np.float32).data,
        dev.data,
        channels=2,
    )
    bx, by, bz = brick
    shape = (2, bb.nbricks + 2, bz + APRON, by + APRON, bx + APRON)
    host, dev = host.reshape(shape), dev.get().reshape(shape)
    nbr, bits = bb.nbr.get(), bb.brick_bits.get()
    assert bits[1 : bb.nbricks + 1].all() or not dev[:, bits == 0].any()
    for i in np.flatnonzero(bits):
        for hz in (0, 1):
            for hy in (0, 1):
                for hx in (0, 1):
                    part = (
                        slice(None),
                        i,
                        slice(hz * bz, None) if hz else slice(0, bz),
                        slice(hy * by, None) if hy else slice(0, by),
                        slice(hx * bx, None) if hx else slice(0, bx),
                    )
                    stored = nbr[i, (hz + 1) * 9 + (hy + 1) * 3 + hx + 1] > 0
                    np.testing.assert_array_equal(dev[part], host[part] if stored else 0)


@pytest.mark.parametrize("brick", BRICK_SIZES)
def test_scatter_and_gather_round_trip(runtime, rng, brick):
    s = surface(runtime, brick)
    bb, _, _ = s.band.bricks()
    g = s.grid
    u = rng.standard_normal((2,) + g.padded_shape).astype(np.float32)
    for apron in (0, APRON):
        dev = bb.scatter(u, np.float32, apron)
        expect = bref.to_bricks(u.astype(np.float64), [tuple(c) for c in bb.coords], brick, apron)
        np.testing.assert_array_equal(dev.get().reshape(expect.shape), expect)
    back = bb.gather(bb.scatter(u, np.float32), np.zeros_like(u), EXT)
    ext = band_host(s.ext_band)
    np.testing.assert_array_equal(back.reshape(2, -1)[:, ext], u.reshape(2, -1)[:, ext])
    back.reshape(2, -1)[:, ext] = 0
    assert not back.any()  # only the asked-for cells are written


@pytest.mark.parametrize("geometry", ["cpu", "gpu"])
@pytest.mark.parametrize("brick", BRICK_SIZES)
@pytest.mark.parametrize("weighted,sides", [(False, 5), (True, 6)])
def test_heat_step_matches_reference(runtime, gpu_like, rng, geometry, brick, weighted, sides):
    s = surface(runtime if geometry == "cpu" else gpu_like, brick)
    g = s.grid
    bb, _, _ = s.band.bricks()
    coords = [tuple(c) for c in bb.coords]
    # psi scaled by a non-distance factor exercises the |N| weights of eq. (4.7)
    psi = s.psi_dev.get().astype(np.float64) * (1.5 if weighted else 1.0)
    u = rng.standard_normal((2,) + g.padded_shape).astype(np.float32).astype(np.float64)
    src = bb.scatter(u, np.float32)
    psi_dev = bb.scatter_tiles(psi[None], np.float32, 2)
    dst = bb.scatter(np.zeros_like(u), np.float32, APRON)
    flow = surface_storage.BrickFlow.__new__(surface_storage.BrickFlow)
    flow.defines = {}
    flow.surf, flow.bricks = s, bb
    kernel = flow.kernel("surface/bricks.cl", "bricks_heat_step", WEIGHTED=int(weighted))
    bb.launch(
        kernel,
        src.data,
        dst.data,
        psi_dev.data,
        g.scalar(0.1),
        *surface_storage._signs(sides),
        bb.node_rows.data,
        channels=2,
    )
    node = band_host(s.node_band)
    offsets = [int(o) for o in surface_storage._offsets(g, sides)]
    expect = ref.heat_step(
        u, psi.astype(np.float32).astype(np.float64), node, 0.1, offsets, weighted
    )
    got = dst.get().reshape(2, -1)[:, bref.brick_index(node, g.padded_shape, coords, brick, APRON)]
    np.testing.assert_allclose(got, expect, atol=2e-5 * max(1, np.abs(expect).max()))
    # the apron repeats the next bricks' first cells wherever both bricks were stepped
    bx, by, bz = brick
    out = dst.get().reshape(2, len(coords) + 2, bz + APRON, by + APRON, bx + APRON)
    index = {c: i + 1 for i, c in enumerate(coords)}
    stepped = bb.brick_bits.get() & NODE != 0
    checked = 0
    for (x, y, z), i in index.items():
        for hx, hy, hz in ((1, 0, 0), (0, 1, 0), (0, 0, 1), (1, 1, 1)):
            j = index.get((x + hx, y + hy, z + hz))
            if j and stepped[i] and stepped[j]:
                mine = out[
                    :,
                    i,
                    hz * bz : hz * bz + APRON if hz else bz,
                    hy * by : hy * by + APRON if hy else by,
                    hx * bx : hx * bx + APRON if hx else bx,
                ]
                theirs = out[
                    :, j, : APRON if hz else bz, : APRON if hy else by, : APRON if hx else bx
                ]
                np.testing.assert_array_equal(mine, theirs)
                checked += 1
    assert checked > 0


@pytest.mark.parametrize("geometry", ["cpu", "gpu"])
@pytest.mark.parametrize("brick", BRICK_SIZES)
@pytest.mark.parametrize(
    "interpolation,order,nc,normalize", [("tricubic", 3, 3, True), ("trilinear", 1, 2, False)]
)
def test_extend_cp_matches_reference(
    runtime, gpu_like, rng, geometry, brick, interpolation, order, nc, normalize
):
    device = runtime if geometry == "cpu" else gpu_like
    s = ImplicitSurface.sphere(1.0, 0.2, interpolation=interpolation, device=device)
    s.band.brick = brick
    g = s.grid
    bb, _, lists = s.band.bricks()
    coords = [tuple(c) for c in bb.coords]
    u = rng.standard_normal((nc,) + g.padded_shape).astype(np.float32).astype(np.float64)
    src = bb.scatter(u, np.float32, APRON)
    dst = bb.scatter(np.zeros_like(u), np.float32)
    flow = surface_storage.BrickFlow.__new__(surface_storage.BrickFlow)
    flow.defines = {}
    flow.surf, flow.bricks, flow.lists = s, bb, lists
    flow.src_plane = np.int32(src.size // nc)
    flow._extend_kernel = flow.kernel(
        "surface/bricks.cl", "bricks_extend_cp", INTERP=s.interp, NC=nc, NORMALIZE=int(normalize)
    )
    for which, band in ((EXT, s.ext_band), (REACH, s.reach_band)):
        flow._extend(src, dst, which)
        cells = band_host(band)
        cp = ref.closest_points(s.psi_dev.get()[0], cells, 1 / s.spacing)
        expect = ref.extend_cp(u, cells, cp, order, normalize)
        got = dst.get().reshape(nc, -1)[:, bref.brick_index(cells, g.padded_shape, coords, brick)]
        np.testing.assert_allclose(got, expect, atol=5e-5 * max(1, np.abs(expect).max()))


@pytest.mark.parametrize("brick", BRICK_SIZES)
def test_heat_on_bricks_is_heat_on_lists(runtime, gpu_like, brick):
    """The same scheme in both storages and both launch geometries: scalar and vector data,
    both one-sided variants, the weighted form."""
    for device in (runtime, gpu_like):
        s = surface(device, brick)
        x, y, z = s.coordinates()
        u = np.broadcast_to(np.sin(3 * x) * y + z, s.shape)
        v = np.stack(np.broadcast_arrays(x, y * z, np.cos(z)))
        for data, options in ((u, {}), (v, {"alternate": False}), (u, {"weighted": True})):
            s.storage = "bricks"
            got = s.heat(data, 0.03, **options)
            s.storage = "lists"
            expect = s.heat(data, 0.03, **options)
            np.testing.assert_allclose(got, expect, atol=2e-6)
            assert got.shape == data.shape


def test_heat_on_bricks_keeps_the_accuracy():
    """The sphere's xy error within 5% of the lists' at two spacings, second order kept."""
    pts = sphere_points(2000)
    errors = {}
    for h in (0.1, 0.05):
        s = ImplicitSurface.sphere(1.0, h)
        u = s.field(lambda x, y, z: x * y)
        for storage in ("bricks", "lists"):
            s.storage = storage
            errors[storage, h] = np.abs(s.sample(s.heat(u, 0.1), pts) - xy_exact(pts, 0.1)).max()
    for h in (0.1, 0.05):
        assert errors["bricks", h] <= 1.05 * errors["lists", h], errors
    assert np.log2(errors["bricks", 0.1] / errors["bricks", 0.05]) > 1.8, errors


@pytest.mark.parametrize("brick", BRICK_SIZES)
@pytest.mark.parametrize("apron,halo", [(0, 0), (APRON, 0), (0, 2)])
def test_brick_cells_index_every_cell_and_mark_those_outside(rng, brick, apron, halo):
    """_brick_cells (the index arithmetic of scatter, tiles and the layout) against a cell by
    cell loop, with bricks on every face and corner of the grid, where cells fall outside."""
    from clpde.bricks import _brick_cells

    shape = (21, 19, 27)  # (PZ, PY, PX): no side a multiple of a brick's
    bx, by, bz = brick
    places = [-(-n // b) for n, b in zip(shape[::-1], brick, strict=True)]
    corners = [
        (x, y, z)
        for x in (0, places[0] - 1)
        for y in (0, places[1] - 1)
        for z in (0, places[2] - 1)
    ]
    coords = np.array(
        corners + [tuple(rng.integers(0, p) for p in places) for _ in range(20)], np.int32
    )
    got = _brick_cells(coords, brick, shape, apron, halo)
    a = apron + 2 * halo
    for k, (cx, cy, cz) in enumerate(coords):
        expect = []
        for lz in range(bz + a):
            for ly in range(by + a):
                for lx in range(bx + a):
                    z, y, x = cz * bz + lz - halo, cy * by + ly - halo, cx * bx + lx - halo
                    inside = 0 <= z < shape[0] and 0 <= y < shape[1] and 0 <= x < shape[2]
                    expect.append((z * shape[1] + y) * shape[2] + x if inside else -1)
        np.testing.assert_array_equal(got[k], expect)
