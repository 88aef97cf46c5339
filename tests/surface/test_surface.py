"""Implicit surfaces: each kernel against its numpy reference, the heat flow against exact
solutions on the unit sphere (second-order convergence measured through surf.sample)."""

import numpy as np
import pyopencl.array as cla
import pytest

from clpde.errors import InputError
from clpde.surface import ImplicitSurface, flows
from clpde.surface import storage as surface_storage
from clpde.surface.exact import exp3z_exact, sphere_points
from clpde.surface.storage import _offsets
from tests.reference import surface as ref


@pytest.fixture(scope="module")
def small_sphere():
    return ImplicitSurface.sphere(1.0, 0.2)


def padded_host(surf, rng, nc):
    return rng.standard_normal((nc,) + surf.grid.padded_shape)


def band_host(band):
    return band.indices.get()[: band.n].astype(np.int64)


# ---- kernels against references ------------------------------------------------------------


def test_band_lists_match_reference(small_sphere):
    s = small_sphere
    psi_pad = s.psi_dev.get()[0].astype(np.float64)
    for width, band in ((s.inner, s.step_band), (s.outer, s.ext_band)):
        expect = ref.band_indices(psi_pad / s.spacing, width, s.grid.ghost)
        got = band_host(band)
        # float32 psi can move a cell sitting on the band edge by a rounding error
        assert abs(got.size - expect.size) <= 2
        assert np.setdiff1d(got, expect).size + np.setdiff1d(expect, got).size <= 2


def test_closest_points_match_reference(small_sphere):
    s = small_sphere
    band = band_host(s.ext_band)
    expect = ref.closest_points(s.psi_dev.get()[0].astype(np.float64), band, 1 / s.spacing)
    got = np.stack([c.get()[: band.size] for c in s.cp])
    np.testing.assert_allclose(got, expect, atol=2e-4)
    # and they lie on the unit sphere: |origin + h (cp - G)| = 1 to second order
    world = s.origin[:, None] + s.spacing * (got - s.grid.ghost)
    assert np.abs(np.linalg.norm(world, axis=0) - 1).max() < 0.02


@pytest.mark.parametrize("interpolation,order", [("tricubic", 3), ("trilinear", 1)])
def test_cp_stencils_match_reference(small_sphere, interpolation, order):
    s = (
        ImplicitSurface.sphere(1.0, 0.2, interpolation=interpolation)
        if order == 1
        else small_sphere
    )
    n = s.ext_band.n
    cp = np.stack([c.get()[:n] for c in s.cp]).astype(np.float64)
    base, frac = ref.cp_stencils(cp, s.grid.padded_shape, order)
    np.testing.assert_array_equal(s.cp_base.get()[:n], base)
    np.testing.assert_allclose(s.cp_frac.get()[:, :n], frac, atol=1e-6)


@pytest.mark.parametrize("interpolation,order", [("tricubic", 3), ("trilinear", 1)])
@pytest.mark.parametrize(
    "nc,normalize,lines", [(1, False, False), (3, True, False), (3, True, True)]
)
def test_extend_cp_matches_reference(small_sphere, rng, interpolation, order, nc, normalize, lines):
    s = (
        ImplicitSurface.sphere(1.0, 0.2, interpolation=interpolation)
        if order == 1
        else small_sphere
    )
    g, q = s.grid, s.runtime.queue
    for u in (
        padded_host(s, rng, nc),
        np.broadcast_to(np.linspace(-1, 2, g.padded_shape[2]), (nc,) + g.padded_shape),
    ):
        src = cla.to_device(q, np.ascontiguousarray(u, np.float32))
        dst = cla.zeros_like(src)
        kernel = g.kernel(
            "surface/extend.cl",
            "extend_cp",
            INTERP=order,
            NC=nc,
            NORMALIZE=int(normalize),
            LINE_FIELD=int(lines),
        )
        g.launch_list(
            kernel, s.ext_band, src.data, dst.data, s.cp_base.data, s.cp_frac.data, *g.strides()
        )
        band = band_host(s.ext_band)
        cp = np.stack([c.get()[: band.size] for c in s.cp]).astype(np.float64)
        expect = ref.extend_cp(
            u.astype(np.float32).astype(np.float64), band, cp, order, normalize, line_field=lines
        )
        got = dst.get().reshape(nc, -1)[:, band]
        np.testing.assert_allclose(got, expect, atol=5e-5 * np.abs(expect).max() + 1e-5)


def test_tricubic_sample_is_exact_on_cubics(small_sphere):
    s = small_sphere
    x, y, z = s.coordinates()

    def cubic(x, y, z):
        return 0.3 * x**3 - x * y * z + 0.5 * z**2 * y + y - 0.2

    u = np.broadcast_to(cubic(x, y, z), s.shape)
    pts = sphere_points(300) * 1.01
    np.testing.assert_allclose(s.sample(u, pts), cubic(*pts.T), atol=2e-5)

    def linear(x, y, z):
        return 0.3 * x - 2 * y + z

    u = np.broadcast_to(linear(x, y, z), s.shape)
    np.testing.assert_allclose(s.sample(u, pts, "trilinear"), linear(*pts.T), atol=2e-5)
    # trilinear is not exact on the cubic: the test can tell the two apart
    u = np.broadcast_to(cubic(x, y, z), s.shape)
    assert np.abs(s.sample(u, pts, "trilinear") - cubic(*pts.T)).max() > 1e-3


def test_sample_matches_reference_on_random_data(small_sphere, rng):
    s = small_sphere
    u = rng.standard_normal((2,) + s.shape)
    pts = sphere_points(200)
    idx = s.world_to_index(pts)
    u_pad = s.grid.pad(u.astype(np.float32).astype(np.float64))
    expect = ref.interpolate(u_pad, idx, 3).T
    np.testing.assert_allclose(s.sample(u, pts), expect, atol=1e-4)


@pytest.mark.parametrize("weighted", [False, True])
@pytest.mark.parametrize("sides", [0, 5, 7])
def test_heat_step_matches_reference(rng, weighted, sides):
    s = ImplicitSurface.sphere(1.0, 0.2)
    g, q = s.grid, s.runtime.queue
    x, y, z = s.coordinates()
    structured = np.broadcast_to(np.sign(x) * y + z**2, s.shape)[None]
    # psi scaled by a non-distance factor exercises the |N| weights of eq. (4.7)
    psi = s.psi_dev.get() * (1.5 if weighted else 1.0)
    psi_dev = cla.to_device(q, psi)
    for u in (padded_host(s, rng, 2), g.pad(structured)):
        u32 = np.ascontiguousarray(u, np.float32)
        src = cla.to_device(q, u32)
        dst = cla.zeros_like(src)
        offsets = _offsets(g, sides)
        kernel = g.kernel("surface/heat.cl", "heat_step", WEIGHTED=int(weighted))
        g.launch_runs(
            kernel,
            s.step_runs,
            src.data,
            dst.data,
            psi_dev.data,
            g.scalar(0.1),
            *offsets,
            *g.strides(),
            channels=u.shape[0],
        )
        band = band_host(s.node_band)
        expect = ref.heat_step(
            u32.astype(np.float64),
            psi.astype(np.float64),
            band,
            0.1,
            [int(o) for o in offsets],
            weighted,
        )
        out = dst.get().reshape(u.shape[0], -1)
        np.testing.assert_allclose(out[:, band], expect, atol=2e-5 * max(1, np.abs(expect).max()))
        # nothing is written outside the runs
        runs = s.step_runs
        spans = [
            np.arange(a, b)
            for a, b in zip(runs.start.get()[: runs.n], runs.end.get()[: runs.n], strict=False)
        ]
        out[:, np.concatenate(spans)] = 0
        assert not out.any()


def test_node_and_reach_bands_match_reference(small_sphere):
    s = small_sphere
    g = s.grid
    base, _ = ref.cp_stencils(
        np.stack([c.get()[: s.ext_band.n] for c in s.cp]).astype(np.float64), g.padded_shape, 3
    )
    nodes = ref.node_cells(base, g.padded_shape, 3)
    np.testing.assert_array_equal(band_host(s.node_band), nodes)
    np.testing.assert_array_equal(band_host(s.reach_band), ref.stencil_cells(nodes, g.padded_shape))
    # narrower than the distance bands they replace, and inside them
    step, ext = band_host(s.step_band), band_host(s.ext_band)
    assert np.isin(nodes, step).all() and np.isin(band_host(s.reach_band), ext).all()
    assert nodes.size < 0.9 * step.size and s.reach_band.n < 0.9 * ext.size


@pytest.mark.parametrize("flow", ["heat", "harmonic"])
def test_narrow_bands_give_the_whole_band_scheme(small_sphere, flow):
    """Stepping only the nodes and re-extending only what the steps read is the same scheme
    as stepping the step band and re-extending the whole band every step."""
    s = small_sphere
    g = s.grid
    x, y, z = s.coordinates()
    if flow == "heat":
        u = np.broadcast_to(np.sin(3 * x) * y + z, s.shape)
        got = s.heat(u, 0.02)
        kernel, nc, normalize = g.kernel("surface/heat.cl", "heat_step", WEIGHTED=0), 1, False
    else:
        v = np.stack(np.broadcast_arrays(x + 0.3 * y, np.cos(2 * y), z + 0.5))
        u = v / np.sqrt((v**2).sum(axis=0))
        got = s.harmonic_map(u, 0.02)
        kernel = g.kernel(
            "surface/flows.cl",
            "flows_step",
            NC=3,
            FLOW_P=2,
            HARMONIC=1,
            FIDELITY=0,
            ALONG=0,
            WEIGHTED=0,
        )
        nc, normalize = 3, True
    steps, dt = flows.check_time(0.02, None, s.stability_limit("heat"), "heat")
    whole = surface_storage.BandFlow(s, u, normalize=normalize)
    r = g.scalar(dt / s.spacing**2)
    full_runs = g.runs(s.step_band)
    for n in range(steps):
        args = (whole.cur.data, whole.tmp.data, s.psi_dev.data)
        if flow == "heat":
            args += (r,)
        else:
            lam = cla.zeros(s.runtime.queue, 1, g.dtype)
            args += (s.psi_dev.data, s.psi_dev.data, r, g.scalar(dt), lam.data, g.scalar(1))
        g.launch_runs(
            kernel,
            full_runs,
            *args,
            *surface_storage._offsets(g, n % 8),
            *g.strides(),
            channels=1 if flow != "heat" else nc,
        )
        whole._extend(whole.tmp, whole.cur, s.ext_band, s.cp_base, s.cp_frac)
    expect = g.download(whole.cur)
    expect = expect[0] if nc == 1 else expect
    band = np.abs(s.psi) < s.outer * s.spacing
    np.testing.assert_allclose(got[..., band], expect[..., band], rtol=0, atol=1e-6)


def test_band_runs_cover_the_band_in_row_stretches(small_sphere):
    s = small_sphere
    g = s.grid
    band = band_host(s.node_band)
    runs = s.step_runs
    start, end = runs.start.get()[: runs.n], runs.end.get()[: runs.n]
    assert np.all(end > start) and np.all(start[1:] >= end[:-1])  # ordered, disjoint
    cells = np.concatenate([np.arange(a, b) for a, b in zip(start, end, strict=False)])
    assert np.isin(band, cells).all()
    # runs stay inside the interior of their row
    x = cells % g.sx
    assert x.min() >= g.ghost and x.max() < g.ghost + g.nx
    if s.runtime.is_cpu:
        first = band[np.diff(band, prepend=-2) != 1]
        np.testing.assert_array_equal(start, first)  # one run per maximal stretch
        assert runs.n < band.size / 3
        # lengthened to multiples of 16 cells unless the row or the next run is in the way
        short = (end - start) % 16 != 0
        blocked = np.append(end[:-1] == start[1:], True) | ((end - g.ghost) % g.sx == g.nx)
        assert np.all(blocked[short])


# ---- the mathematics --------------------------------------------------------------------------


def heat_error(h, f, exact, t=0.1, alternate=True):
    s = ImplicitSurface.sphere(1.0, h)
    v = s.heat(s.field(f), t=t, alternate=alternate)
    pts = sphere_points()
    return np.abs(s.sample(v, pts) - exact(pts, t)).max()


def test_heat_on_sphere_xy_converges_at_second_order():
    def exact(p, t):
        return np.exp(-6 * t) * p[:, 0] * p[:, 1]

    for alternate in (True, False):  # both one-sided variants of appendix E
        coarse = heat_error(0.1, lambda x, y, z: x * y, exact, alternate=alternate)
        fine = heat_error(0.05, lambda x, y, z: x * y, exact, alternate=alternate)
        order = np.log2(coarse / fine)
        assert fine <= 6e-4, fine
        assert order > 1.8, (coarse, fine, order)


def test_heat_on_sphere_exp3z_converges_at_second_order():
    def exact(p, t):
        return exp3z_exact(p[:, 2], t)

    coarse = heat_error(0.1, lambda x, y, z: np.exp(3 * z), exact)
    fine = heat_error(0.05, lambda x, y, z: np.exp(3 * z), exact)
    order = np.log2(coarse / fine)
    assert order > 1.8, (coarse, fine, order)
    assert fine < 0.01  # relative to a solution of size up to e^3 = 20


def test_legendre_reference_is_right():
    z = np.linspace(-1, 1, 11)
    np.testing.assert_allclose(exp3z_exact(z, 0.0), np.exp(3 * z), rtol=1e-10)
    # the mean over the sphere (the l = 0 term) is kept: sinh(3)/3
    assert abs(exp3z_exact(z, 50.0)[0] - np.sinh(3) / 3) < 1e-10


def test_heat_keeps_constants_and_the_weighted_form_agrees():
    s = ImplicitSurface.sphere(1.0, 0.2)
    const = np.full(s.shape, 2.5)
    np.testing.assert_allclose(s.sample(s.heat(const, t=0.05), sphere_points(100)), 2.5, atol=1e-5)
    u = s.field(lambda x, y, z: x * y)
    a = s.sample(s.heat(u, t=0.05), sphere_points(100))
    b = s.sample(s.heat(u, t=0.05, weighted=True), sphere_points(100))
    assert np.abs(a - b).max() < 1e-3  # |grad psi| = 1 for a distance function


def test_heat_output_dtype_and_input_untouched():
    s = ImplicitSurface.sphere(1.0, 0.2)
    u = s.field(lambda x, y, z: z).astype(np.float32)
    keep = u.copy()
    v = s.heat(u, t=0.01)
    assert v.dtype == np.float32 and v.shape == u.shape
    np.testing.assert_array_equal(u, keep)


def test_unstable_time_step_is_an_error_naming_the_limit():
    s = ImplicitSurface.sphere(1.0, 0.2)
    limit = s.stability_limit("heat")
    assert limit == pytest.approx(0.2**2 / 6)
    with pytest.raises(InputError, match=f"{limit:g}"):
        s.heat(s.field(lambda x, y, z: x), t=0.1, dt=2 * limit)


def test_shapes_build_bands():
    # tubes of 3-4 cells' radius: the band reaches their core, which is warned about
    with pytest.warns(UserWarning, match="too coarse"):
        torus = ImplicitSurface.torus(1.0, 0.4, spacing=0.1)
    with pytest.warns(UserWarning, match="too coarse"):
        genus2 = ImplicitSurface.double_torus(spacing=0.1)
    for s in (torus, genus2):
        assert s.step_band.n > 0 and s.ext_band.n > s.step_band.n
    # a volume array with its spacing gives the same surface as the analytic constructor
    with pytest.warns(UserWarning, match="too coarse"):
        again = ImplicitSurface.from_volume(torus.psi, torus.spacing, torus.origin)
    assert again.ext_band.n == torus.ext_band.n
    # heat keeps a constant on the torus and smooths a function of position
    u = torus.field(lambda x, y, z: x)
    v = torus.heat(u, t=0.05)
    band = np.abs(torus.psi) < 0.05
    assert np.abs(v[band]).max() < np.abs(u[band]).max()


def test_bad_inputs_are_clear_errors():
    psi = np.linalg.norm(np.mgrid[-1:1:21j, -1:1:21j, -1:1:21j], axis=0) - 0.5
    with pytest.raises(InputError, match="NaN"):
        bad = psi.copy()
        bad[0, 0, 0] = np.nan
        ImplicitSurface.from_volume(bad, 0.1)
    with pytest.raises(InputError, match="never changes sign"):
        ImplicitSurface.from_volume(np.abs(psi) + 1, 0.1)
    with pytest.raises(InputError, match="3D"):
        ImplicitSurface.from_volume(psi[0], 0.1)
    with pytest.raises(InputError, match="border"):
        ImplicitSurface.from_volume(
            np.linalg.norm(np.mgrid[-1:1:21j, -1:1:21j, -1:1:21j], axis=0) - 0.95, 0.1
        )
    s = ImplicitSurface.sphere(1.0, 0.2)
    with pytest.raises(InputError, match="shape"):
        s.heat(np.zeros((3, 3, 3)), t=0.1)
    with pytest.raises(InputError, match="cells from the surface"):
        s.sample(np.zeros(s.shape), np.array([[0.0, 0.0, 0.0]]))


def surface_mean(surf, u, width=1.5):
    """Mean of u over the surface: smeared-delta quadrature on the grid."""
    d = surf.psi / surf.spacing
    delta = np.where(np.abs(d) < width, 1 + np.cos(np.pi * d / width), 0.0)
    return float((delta * u).sum() / delta.sum())


def test_heat_on_a_torus_keeps_the_mean_and_decays_to_it():
    s = ImplicitSurface.torus(1.0, 0.5, spacing=0.08)
    u = s.field(lambda x, y, z: np.cos(np.arctan2(y, x)) + z + 0.3)
    before = surface_mean(s, u)
    v = s.heat(u, t=0.05)
    w = s.heat(u, t=1.0)
    # the intrinsic heat flow conserves the integral over the closed surface ...
    assert abs(surface_mean(s, v) - before) < 2e-3
    # ... and tends to the constant equal to the mean (the slowest mode, cos of the angle
    # around the axis, decays as exp(-t / R^2) on average over the tube)
    band = np.abs(s.psi) < s.spacing
    assert np.abs(w[band] - before).max() < 0.5 * np.abs(u[band] - before).max()
    assert np.abs(w[band] - before).max() < np.abs(v[band] - before).max()
