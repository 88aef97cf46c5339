"""Every surface flow on the band's bricks (ImplicitSurface(storage="bricks"),
kernels/surface/bricks.cl): the brick kernels of TV / harmonic maps / diffusion along a field,
Turk's
reaction-diffusion and TV's dynamic lambda against the numpy references of the same discrete
scheme, read through the brick layout, in both launch geometries (a work-item walking whole
bricks, as on CPUs; a work-group per brick, as on GPUs); then every flow of the public API
on bricks against the same flow on the band lists."""

import numpy as np
import pyopencl.array as cla
import pytest
from test_surface_flows import CASES

from clpde.bricks import APRON, NODE
from clpde.errors import InputError
from clpde.runtime import Runtime
from clpde.surface import ImplicitSurface
from clpde.surface import storage as surface_storage
from clpde.surface.band import extend_defines
from tests.reference import bricks as bref
from tests.reference import surface as ref


@pytest.fixture(scope="module")
def gpu_like(runtime):
    rt = Runtime(runtime.index, runtime.platform, runtime.device)
    rt.is_cpu = False  # launch geometry only
    return rt


@pytest.fixture(scope="module")
def spheres(runtime, gpu_like):
    """A sphere on bricks per launch geometry."""
    return {
        geometry: ImplicitSurface.sphere(1.0, 0.2, device=device, storage="bricks")
        for geometry, device in (("cpu", runtime), ("gpu", gpu_like))
    }


def band_host(band):
    return band.indices.get()[: band.n].astype(np.int64)


def brick_flow(s, nc, **defines):
    """A BrickFlow shell on s's bricks (no data), for its kernels and layouts."""
    flow = surface_storage.BrickFlow.__new__(surface_storage.BrickFlow)
    flow.surf = s
    flow.bricks, flow.psi, flow.lists = s.band.bricks()
    flow.defines = {**extend_defines(s.interp, nc), **defines}
    return flow


def stepped_at(dst, nc, cells, s, bb):
    """The stepped values (apron layout) at flat padded cells."""
    coords = [tuple(c) for c in bb.coords]
    index = bref.brick_index(cells, s.grid.padded_shape, coords, bb.brick, APRON)
    return dst.get().reshape(nc, -1)[:, index]


@pytest.mark.parametrize("geometry", ["cpu", "gpu"])
@pytest.mark.parametrize("case", sorted(CASES))
def test_brick_flow_step_matches_reference(spheres, rng, geometry, case):
    s = spheres[geometry]
    g, bb = s.grid, s.band.bricks()[0]
    opts = dict(CASES[case])
    nc = opts.pop("nc")
    weighted = opts.get("WEIGHTED", 0)
    psi = g.pad(s.psi[None], mode="linear") * (1.3 if weighted else 1.0)
    direction = rng.standard_normal((3,) + g.padded_shape)
    direction /= np.sqrt((direction**2).sum(axis=0))
    u = rng.standard_normal((nc,) + g.padded_shape).astype(np.float32).astype(np.float64)
    u0 = (u + 0.1 * rng.standard_normal(u.shape)).astype(np.float32).astype(np.float64)
    flow = brick_flow(s, nc, **opts)
    dst = bb.scatter(np.zeros_like(u), np.float32, APRON)
    q = s.runtime.queue
    r, dt, lam, e2 = 0.05, 0.01, 2.0, 0.04
    sides = 6
    bb.launch(
        flow.step_kernel("flow"),
        bb.scatter(u, np.float32).data,
        dst.data,
        bb.scatter_tiles(psi, np.float32, 2).data,
        bb.scatter_tiles(direction, np.float32, 2).data,
        bb.scatter(u0, np.float32).data,
        g.scalar(r),
        g.scalar(dt),
        cla.to_device(q, np.float32([lam])).data,
        g.scalar(e2),
        *surface_storage._signs(sides),
        bb.node_rows.data,
    )
    node = band_host(s.node_band)
    f32 = np.float32
    expect = ref.flow_step(
        u,
        psi.astype(f32).astype(np.float64),
        node,
        r,
        dt,
        lam,
        e2,
        [int(o) for o in surface_storage._offsets(g, sides)],
        flow_p=opts["FLOW_P"],
        harmonic=bool(opts["HARMONIC"]),
        u0_pad=u0 if opts["FIDELITY"] else None,
        direction=direction.astype(f32).astype(np.float64) if opts["ALONG"] else None,
        weighted=bool(weighted),
        line_field=bool(opts.get("LINE_FIELD", 0)),
    )
    got = stepped_at(dst, nc, node, s, bb)
    np.testing.assert_allclose(got, expect, atol=3e-5 * max(1, np.abs(expect).max()))


@pytest.mark.parametrize("geometry", ["cpu", "gpu"])
def test_brick_turk_step_matches_reference(spheres, rng, geometry):
    s = spheres[geometry]
    g, bb = s.grid, s.band.bricks()[0]
    u = (4 + rng.standard_normal((2,) + g.padded_shape)).astype(np.float32).astype(np.float64)
    beta = (12 + 0.1 * rng.uniform(-1, 1, g.padded_shape)).astype(np.float32)
    d = rng.standard_normal((3,) + g.padded_shape)
    d = (d / np.sqrt((d**2).sum(axis=0))).astype(np.float32).astype(np.float64)
    psi = g.pad(s.psi[None], mode="linear")
    node = band_host(s.node_band)
    for along in (False, True):
        flow = brick_flow(s, 2, ALONG=int(along))
        dst = bb.scatter(np.zeros_like(u), np.float32, APRON)
        bb.launch(
            flow.step_kernel("turk"),
            bb.scatter(u, np.float32).data,
            dst.data,
            bb.scatter_tiles(psi, np.float32, 2).data,
            bb.scatter_tiles(d, np.float32, 2).data,
            bb.scatter(beta[None], np.float32).data,
            g.scalar(1.0),
            g.scalar(0.125),
            g.scalar(1 / 32),
            g.scalar(0.0125),
            *surface_storage._signs(2),
            bb.node_rows.data,
        )
        expect = ref.turk_step(
            u,
            psi[0].astype(np.float32).astype(np.float64),
            node,
            beta,
            1.0,
            0.125,
            1 / 32,
            0.0125,
            [int(o) for o in surface_storage._offsets(g, 2)],
            d if along else None,
        )
        np.testing.assert_allclose(stepped_at(dst, 2, node, s, bb), expect, atol=3e-5)


@pytest.mark.parametrize("geometry", ["cpu", "gpu"])
def test_brick_lambda_terms_match_reference(spheres, rng, geometry):
    """The terms at every node, zero at every other stored cell."""
    s = spheres[geometry]
    g, bb = s.grid, s.band.bricks()[0]
    u = rng.standard_normal((1,) + g.padded_shape).astype(np.float32).astype(np.float64)
    u0 = (u + 0.2 * rng.standard_normal(u.shape)).astype(np.float32).astype(np.float64)
    flow = brick_flow(s, 1, FLOW_P=1, FIDELITY=1)
    flow.cur = bb.scatter(u, np.float32)
    terms = [cla.zeros(s.runtime.queue, flow.terms_size, np.float32) for _ in range(3)]
    flow.lambda_terms(bb.scatter(u0, np.float32), terms, 3, eps=0.5)
    node = band_host(s.node_band)
    psi = g.pad(s.psi[None], mode="linear").astype(np.float32)
    expect = ref.tv_lambda_terms(
        u,
        u0,
        psi,
        node,
        1 / s.spacing,
        1.5,
        (s.spacing * 0.5) ** 2,
        [int(o) for o in surface_storage._offsets(g, 3)],
    )
    coords = [tuple(c) for c in bb.coords]
    index = bref.brick_index(node, g.padded_shape, coords, bb.brick)
    for got, want in zip(terms, expect, strict=True):
        got = got.get()
        np.testing.assert_allclose(got[index], want, atol=2e-4 * max(1, np.abs(want).max()))
        got[index] = 0
        assert not got.any()
    assert (bb.mask_host.reshape(-1)[index] & NODE).all()


def _sphere_data(s):
    x, y, z = s.coordinates()
    u = np.broadcast_to(np.sin(3 * x) * y + z, s.shape)
    v = np.stack(np.broadcast_arrays(x + 0.2, y, z))
    v = v / np.sqrt((v**2).sum(axis=0))
    return u, v


FLOWS = {
    "tv": lambda s, u, v, d: s.tv(u, 0.01),
    "tv-weighted": lambda s, u, v, d: s.tv(u, 0.01, weighted=True, alternate=False),
    "denoise-sigma": lambda s, u, v, d: s.denoise_tv(u, sigma=0.05, t=0.01, return_info=True),
    "denoise-lam": lambda s, u, v, d: s.denoise_tv(u, lam=3.0, t=0.01),
    "harmonic2": lambda s, u, v, d: s.harmonic_map(v, 0.01),
    "harmonic1-lines": lambda s, u, v, d: s.harmonic_map(d, 0.01, p=1, line_field=True),
    "along": lambda s, u, v, d: s.diffuse_along(u, d, 0.02),
    "colour": lambda s, u, v, d: s.denoise_colour(np.abs(v), 0.01),
    "turk": lambda s, u, v, d: s.reaction_diffusion(20),
    "turk-along": lambda s, u, v, d: s.reaction_diffusion(20, direction=d),
    "extend": lambda s, u, v, d: s.extend(u),
    "band-form": lambda s, u, v, d: s.tv(s.band_values(u), 0.01),
}


@pytest.mark.parametrize("geometry", ["cpu", "gpu"])
@pytest.mark.parametrize("name", sorted(FLOWS))
def test_every_flow_on_bricks_is_the_flow_on_lists(spheres, geometry, name):
    """The public flows in both storages: the same numbers to rounding (on PoCL's CPU path,
    bitwise but for the dynamic lambda's sums, whose order differs)."""
    s = spheres[geometry]
    u, v = _sphere_data(s)
    d = s.principal_directions()[0]
    got = FLOWS[name](s, u, v, d)
    s.storage = "lists"
    try:
        expect = FLOWS[name](s, u, v, d)
    finally:
        s.storage = "bricks"
    if name == "denoise-sigma":
        (got, got_info), (expect, info) = got, expect
        assert got_info.steps == info.steps
        np.testing.assert_allclose(got_info.lam_history, info.lam_history, rtol=1e-4)
        assert got_info.residual_variance == pytest.approx(info.residual_variance, rel=1e-4)
    assert got.shape == expect.shape and got.dtype == expect.dtype
    np.testing.assert_allclose(got, expect, atol=2e-6 * max(1, np.abs(expect).max()))


def test_storage_is_checked_and_kept_by_the_constructors():
    s = ImplicitSurface.sphere(1.0, 0.2, center=(0.5, 0, 0), storage="bricks")
    assert s.storage == "bricks"
    assert isinstance(
        surface_storage.make_flow(s, s.field(lambda x, y, z: x)), surface_storage.BrickFlow
    )
    assert ImplicitSurface.sphere(1.0, 0.2).storage == "lists"
    with pytest.raises(InputError, match="storage must be one of 'lists', 'bricks'"):
        ImplicitSurface.sphere(1.0, 0.2, storage="dense")
    with pytest.raises(InputError, match="storage must be one of"):
        s.storage = "brick"


def test_too_many_channels_for_a_gpus_local_tiles_is_a_clear_error(gpu_like):
    """On GPUs a brick's tiles (one per channel) live in local memory; data with more channels
    than it holds is refused with the way out, before anything is launched."""
    s = ImplicitSurface.sphere(1.0, 0.2, device=gpu_like, storage="bricks")
    many = 1 + gpu_like.device.local_mem_size // (10**3 * 4)  # 8^3 bricks' tiles of 10^3 cells
    u = np.zeros((many,) + s.shape)
    with pytest.raises(InputError, match="storage='lists'"):
        s.tv(u, 0.001)
