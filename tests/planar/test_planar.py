"""Planar flows: each kernel against its numpy reference, each flow against its mathematics."""

import numpy as np
import pytest
from skimage import data

import clpde
from clpde.errors import InputError
from clpde.fields import Field, Grid
from tests.reference import planar as ref


def structured(ny=40, nx=56):
    """Edges, a ramp, a disk and a corner: every branch of the stencils gets exercised."""
    y, x = np.mgrid[:ny, :nx]
    img = 0.3 * (x > nx // 2) + 0.2 * x / nx
    img += 0.4 * ((x - 15) ** 2 + (y - 20) ** 2 < 64)
    img[: ny // 4, : nx // 4] = 0.9
    return img


def device_step(runtime, kernel_name, u, *args, defines=None, extra_fields=()):
    """One step of a planar kernel on (nc, ny, nx) data, returned as the new interior."""
    nc, ny, nx = u.shape
    grid = Grid(runtime, nx, ny, nc)
    cur = Field.from_host(grid, u)
    nxt = Field.from_host(grid, np.zeros_like(u))
    kernel = grid.kernel("planar/planar.cl", kernel_name, **(defines or {}))
    buffers = [f.data.data for f in extra_fields]
    grid.launch(kernel, cur.data.data, nxt.data.data, *buffers, *args)
    return nxt.to_host(), grid


def inputs(rng):
    return {
        "random": rng.random((2, 23, 31)),
        "structured": structured()[None],
    }


@pytest.mark.parametrize("kind", ["random", "structured"])
def test_heat_kernel_matches_reference(runtime, rng, kind):
    u = inputs(rng)[kind]
    out, _ = device_step(runtime, "planar_heat_step", u, np.float32(0.2))
    np.testing.assert_allclose(out, ref.heat_step(ref.pad_neumann(u), 0.2), atol=2e-6)


@pytest.mark.parametrize("kind", ["random", "structured"])
@pytest.mark.parametrize("edge", ["exp", "rational"])
def test_perona_malik_kernel_matches_reference(runtime, rng, kind, edge):
    u = inputs(rng)[kind]
    kappa = 0.1
    out, _ = device_step(
        runtime,
        "planar_perona_malik_step",
        u,
        np.float32(0.2),
        np.float32(1 / kappa**2),
        defines={"EDGE_STOP": int(edge == "rational")},
    )
    expected = ref.perona_malik_step(ref.pad_neumann(u), 0.2, kappa, edge)
    np.testing.assert_allclose(out, expected, atol=3e-6)


@pytest.mark.parametrize("kind", ["random", "structured"])
def test_tv_kernel_matches_reference(runtime, rng, kind):
    u = inputs(rng)[kind]
    eps = 0.05
    out, _ = device_step(runtime, "planar_tv_step", u, np.float32(0.01), np.float32(eps**2))
    np.testing.assert_allclose(out, ref.tv_step(ref.pad_neumann(u), 0.01, eps), atol=3e-6)


@pytest.mark.parametrize("kind", ["random", "structured"])
@pytest.mark.parametrize("weighted", [False, True])
def test_curvature_kernel_matches_reference(runtime, rng, kind, weighted):
    u = inputs(rng)[kind]
    _, ny, nx = u.shape
    eps = 1e-6
    weight = rng.random((ny, nx)) if weighted else None
    if weighted:
        wgrid = Grid(runtime, nx, ny, 1)
        wfield = Field.from_host(wgrid, weight[None])
        out, _ = device_step(
            runtime,
            "planar_curvature_step",
            u,
            np.float32(0.2),
            np.float32(eps),
            defines={"HAS_WEIGHT": 1},
            extra_fields=(wfield,),
        )
    else:
        dummy = Field.from_host(Grid(runtime, nx, ny, 1), np.zeros((1, ny, nx)))
        out, _ = device_step(
            runtime,
            "planar_curvature_step",
            u,
            np.float32(0.2),
            np.float32(eps),
            extra_fields=(dummy,),
        )
    expected = ref.curvature_step(ref.pad_neumann(u), 0.2, eps, weight)
    np.testing.assert_allclose(out, expected, atol=5e-5)


def test_flow_steps_match_repeated_reference_steps(rng):
    """The host loop (ghost refill + swap) is the reference's pad-then-step, repeated."""
    u = rng.random((24, 20))
    u[0, 0], u[0, 1] = 0.0, 1.0  # range exactly [0, 1]: the float scaling is the identity
    out = clpde.diffuse(u, "tv", steps=30, dt=0.01, eps=0.1)
    expected = u[None]
    for _ in range(30):
        expected = ref.tv_step(ref.pad_neumann(expected), 0.01, 0.1)
    np.testing.assert_allclose(out, expected[0], atol=2e-5)


# ---- mathematics ------------------------------------------------------------------------


def test_gaussian_stays_gaussian_with_variance_growing_by_2t():
    n, s0 = 129, 4.0
    y, x = np.mgrid[:n, :n] - n // 2
    u0 = np.exp(-(x**2 + y**2) / (2 * s0**2))
    steps, dt = 200, 0.25
    t = steps * dt
    out = clpde.diffuse(u0, "heat", steps=steps, dt=dt).astype(np.float64)

    def variance(u):
        return float((u * x**2).sum() / u.sum())

    measured = variance(out)
    expected = variance(u0) + 2 * t
    assert measured == pytest.approx(expected, rel=2e-3)
    gauss = np.exp(-(x**2 + y**2) / (2 * (s0**2 + 2 * t)))
    gauss *= out.sum() / gauss.sum()
    assert np.abs(out - gauss).max() / out.max() < 5e-3


@pytest.mark.parametrize(
    "flow,params", [("heat", {}), ("perona-malik", {"kappa": 0.1}), ("tv", {"eps": 0.1})]
)
def test_mass_is_conserved_with_neumann_borders(rng, flow, params):
    u = rng.random((48, 40))
    out = clpde.diffuse(u, flow, steps=200, **params)
    assert out.sum() == pytest.approx(u.sum(), rel=2e-6)


@pytest.mark.parametrize("flow", ["heat", "perona-malik"])
def test_maximum_principle(rng, flow):
    u = (rng.random((40, 40)) * 200 + 20).astype(np.uint8)
    out = clpde.diffuse(u, flow, steps=100, dt=0.25)
    assert out.min() >= u.min() and out.max() <= u.max()
    assert out.std() < u.std()


def edge_width(profile):
    """Equivalent width of an edge: its total rise over its steepest one-pixel rise."""
    return float((profile.max() - profile.min()) / np.abs(np.diff(profile)).max())


def test_tv_keeps_a_step_sharp_where_heat_blurs_it():
    step = np.zeros((32, 64))
    step[:, 32:] = 1.0
    t, eps = 5.0, 0.01
    heat = clpde.diffuse(step, "heat", steps=int(t / 0.25), dt=0.25)
    tv = clpde.diffuse(step, "tv", steps=int(t / (eps / 4)), dt=eps / 4, eps=eps)
    w_heat, w_tv = edge_width(heat[16]), edge_width(tv[16])
    # heat: an erf of standard deviation sqrt(2t), equivalent width sqrt(2 pi 2t) = 7.9 px
    assert w_heat == pytest.approx(np.sqrt(4 * np.pi * t), rel=0.05)
    assert w_tv < 2.5, (w_heat, w_tv)


def test_perona_malik_smooths_noise_but_keeps_edges(rng):
    step = np.zeros((40, 64))
    step[:, 32:] = 1.0
    noisy = step + 0.02 * rng.standard_normal(step.shape)
    noisy = np.clip(noisy, 0, 1)
    out = clpde.diffuse(noisy, "perona-malik", steps=100, kappa=0.1)
    flat = out[:, 5:25]
    assert flat.std() < 0.3 * noisy[:, 5:25].std()
    assert edge_width(out.mean(axis=0)) <= 2


def test_curvature_flow_shrinks_a_circle_as_r2_minus_2t():
    n, r0 = 80, 24.0
    y, x = np.mgrid[:n, :n] - (n - 1) / 2
    u = np.clip(r0 - np.hypot(x, y) + 0.5, 0, 1)  # anti-aliased disk
    t = 100.0
    out = clpde.diffuse(u, "curvature", steps=int(t / 0.2), dt=0.2)
    radius = np.sqrt((out > 0.5).sum() / np.pi)
    assert radius == pytest.approx(np.sqrt(r0**2 - 2 * t), rel=0.04)


def test_zero_weight_freezes_curvature_flow(rng):
    u = rng.random((30, 30))
    weight = np.zeros((30, 30))
    weight[10:20, 10:20] = 1.0
    out = clpde.diffuse(u, "curvature", steps=20, weight=weight)
    frozen = weight == 0
    np.testing.assert_allclose(out[frozen], u[frozen], atol=1e-6)
    assert not np.allclose(out[~frozen], u[~frozen])


# ---- API behaviour ------------------------------------------------------------------------


def test_dtypes_and_shapes_are_preserved():
    img = data.astronaut()[::8, ::8]  # uint8 (64, 64, 3)
    out = clpde.diffuse(img, "heat", steps=5, channel_axis=-1)
    assert out.dtype == np.uint8 and out.shape == img.shape
    first = np.moveaxis(img, -1, 0).copy()
    out0 = clpde.diffuse(first, "heat", steps=5, channel_axis=0)
    np.testing.assert_array_equal(np.moveaxis(out0, 0, -1), out)
    for dtype in (np.uint16, np.float32, np.float64, np.int16):
        grey = (img[..., 0].astype(np.float64) * 100).astype(dtype)
        res = clpde.diffuse(grey, "perona-malik", steps=3)
        assert res.dtype == dtype and res.shape == grey.shape


def test_colour_channels_are_independent():
    img = data.astronaut()[::8, ::8]
    out = clpde.diffuse(img, "perona-malik", steps=10, channel_axis=-1)
    for c in range(3):
        single = clpde.diffuse(np.ascontiguousarray(img[..., c]), "perona-malik", steps=10)
        np.testing.assert_array_equal(out[..., c], single)


def test_input_is_not_modified(rng):
    u = rng.random((20, 20))
    before = u.copy()
    clpde.diffuse(u, "tv", steps=10)
    np.testing.assert_array_equal(u, before)


def test_object_form_yields_states():
    flow = clpde.PlanarFlow(data.camera()[::8, ::8], "heat", dt=0.25)
    states = list(flow.iterate(steps=25, every=10))
    assert [s.step for s in states] == [10, 20, 25]
    assert states[-1].time == pytest.approx(6.25)
    assert states[-1].image.std() < states[0].image.std()


@pytest.mark.parametrize(
    "flow,limit", [("heat", 0.25), ("perona-malik", 0.25), ("curvature", 0.25), ("tv", 0.0125)]
)
def test_unstable_dt_is_an_error_stating_the_limit(flow, limit):
    params = {"eps": 0.05} if flow == "tv" else {}
    with pytest.raises(InputError, match=f"stability limit {limit:g}"):
        clpde.diffuse(np.zeros((8, 8)), flow, steps=1, dt=limit * 1.01, **params)


@pytest.mark.parametrize(
    "image,kwargs,match",
    [
        (np.full((8, 8), np.nan), {}, "NaN"),
        (np.zeros((2, 8, 8, 3)), {}, "dimensions"),
        (np.zeros((8, 8, 3)), {}, "channel_axis"),
        (np.zeros((0, 8)), {}, "empty"),
        (np.zeros((8, 8, 3)), {"channel_axis": 5}, "channel_axis"),
        (np.zeros((8, 8)), {"channel_axis": -1}, "3-D"),
        (np.zeros((8, 8), complex), {}, "dtype"),  # (bool images are binary ones)
        (np.zeros((8, 8)), {"flow": "wave"}, "unknown flow"),
        (np.zeros((8, 8)), {"steps": -1}, "steps"),
        (np.zeros((8, 8)), {"dt": -0.1}, "dt"),
        (np.zeros((8, 8)), {"flow": "perona-malik", "kappa": 0}, "kappa"),
        (np.zeros((8, 8)), {"flow": "perona-malik", "edge": "tukey"}, "edge"),
        (np.zeros((8, 8)), {"flow": "curvature", "weight": np.ones((4, 4))}, "weight"),
    ],
)
def test_bad_inputs_raise_clear_errors(image, kwargs, match):
    with pytest.raises(InputError, match=match):
        clpde.diffuse(image, **kwargs)


@pytest.mark.parametrize("geometry", ["cpu-rows", "one-cell-per-item"])
@pytest.mark.parametrize("ghost", [1, 2])
def test_steps_write_their_own_mirror_ghosts(runtime, rng, geometry, ghost):
    """The step leaves `v` fully padded (as Field.fill_ghosts would) under either launch
    geometry: one row per work-item (PoCL) or one cell per work-item (GPUs)."""
    nc, ny, nx = 2, 7, 9
    grid = Grid(runtime, nx, ny, nc, ghost)
    cur = Field.from_host(grid, rng.random((nc, ny, nx)))
    nxt = Field.from_host(grid, np.full((nc, ny, nx), np.nan))
    nxt.data.fill(np.nan)
    kernel = grid.kernel("planar/planar.cl", "planar_heat_step")
    if geometry == "cpu-rows":
        gsize, lsize, xrun = (1, ny, nc), (1, 1, 1), nx
    else:
        gsize, lsize, xrun = (12, 8, nc), (4, 4, 1), 1  # rounded up past the interior
    kernel(
        runtime.queue, gsize, lsize, cur.data.data, nxt.data.data, np.float32(0.2), *grid.args(xrun)
    )
    padded = nxt.data.get()
    expected = np.pad(
        grid.interior(padded), ((0, 0), (ghost, ghost), (ghost, ghost)), mode="symmetric"
    )
    np.testing.assert_array_equal(padded, expected)
