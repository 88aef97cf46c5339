"""Meshes in (exact band distance, orientation-free sign) and pictures out."""

import warnings

import numpy as np
import pytest
import trimesh

from clpde.errors import InputError
from clpde.surface import ImplicitSurface
from clpde.surface.mesh_sdf import grid_for_mesh, mesh_to_sdf
from clpde.surface.render import colormap, export_mesh


@pytest.fixture(scope="module")
def icosphere():
    return trimesh.creation.icosphere(4, radius=1.0)


def exact_mesh_distance(mesh, points):
    from trimesh.triangles import closest_point

    tri = np.asarray(mesh.triangles)
    best = np.full(len(points), np.inf)
    for p_idx in range(len(points)):
        cp = closest_point(tri, np.repeat(points[p_idx : p_idx + 1], len(tri), 0))
        best[p_idx] = np.linalg.norm(cp - points[p_idx], axis=1).min()
    return best


def grid_points(origin, h, shape):
    nz, ny, nx = shape
    z, y, x = np.meshgrid(np.arange(nz), np.arange(ny), np.arange(nx), indexing="ij")
    return origin + h * np.stack([x, y, z], axis=-1).reshape(-1, 3)


def test_band_distance_is_exact_and_sign_is_right(icosphere, rng):
    origin, h, shape = grid_for_mesh(icosphere, resolution=32, padding=8)
    psi, face, cp = mesh_to_sdf(icosphere, origin, h, shape, 6.0)
    pts = grid_points(origin, h, shape)
    r = np.linalg.norm(pts, axis=1)
    band = np.flatnonzero(np.abs(r - 1) < 5 * h)
    pick = rng.choice(band, 60, replace=False)
    exact = exact_mesh_distance(icosphere, pts[pick])
    np.testing.assert_allclose(np.abs(psi.ravel()[pick]), exact, atol=1e-4)
    # the closest points lie on the reported triangles' planes at the reported distance
    cells = np.flatnonzero(face.ravel() >= 0)
    assert len(cells) == len(cp) and np.isin(pick, cells).all()
    rows = np.searchsorted(cells, pick)
    np.testing.assert_allclose(np.linalg.norm(pts[pick] - cp[rows], axis=1), exact, atol=1e-4)
    away = np.abs(r - 1) > 0.02  # the icosphere sits slightly inside the sphere
    assert np.all(np.sign(psi.ravel()[away]) == np.sign(r[away] - 1))


def test_sign_ignores_flipped_faces_and_seals_small_holes(icosphere):
    flipped = icosphere.copy()
    faces = flipped.faces.copy()
    faces[::3] = faces[::3, ::-1]
    flipped.faces = faces
    holed = icosphere.copy()
    holed.update_faces(np.arange(len(icosphere.faces)) != 7)
    origin, h, shape = grid_for_mesh(icosphere, resolution=32, padding=8)
    reference, _, _ = mesh_to_sdf(icosphere, origin, h, shape, 6.0)
    for mesh in (flipped, holed):
        psi, _, _ = mesh_to_sdf(mesh, origin, h, shape, 6.0)
        far = np.abs(reference) > h
        assert np.all(np.sign(psi[far]) == np.sign(reference[far]))


def test_surface_from_mesh_runs_heat_to_the_exact_solution(icosphere):
    mesh = trimesh.creation.icosphere(5, radius=1.0)
    surf = ImplicitSurface.from_mesh(mesh, resolution=40)
    u = surf.field_from_mesh(mesh.vertices[:, 0] * mesh.vertices[:, 1])
    pts = np.random.default_rng(2).standard_normal((300, 3))
    pts /= np.linalg.norm(pts, axis=1)[:, None]
    pts *= 0.9997  # the icosphere's mean radius
    np.testing.assert_allclose(surf.sample(u, pts), pts[:, 0] * pts[:, 1], atol=2e-3)
    out = surf.sample(surf.heat(u, t=0.1), pts)
    assert np.abs(out - np.exp(-0.6) * pts[:, 0] * pts[:, 1]).max() < 2e-3
    with pytest.raises(InputError, match="vertex"):
        surf.field_from_mesh(np.zeros(3))


def test_open_mesh_warns_and_bad_files_are_errors(tmp_path, icosphere):
    holed = icosphere.copy()
    holed.update_faces(np.arange(len(icosphere.faces)) != 7)
    with pytest.warns(UserWarning, match="watertight"):
        ImplicitSurface.from_mesh(holed, resolution=24)
    bad = tmp_path / "broken.ply"
    bad.write_text("not a mesh")
    with pytest.raises(InputError, match="could not read"):
        ImplicitSurface.from_mesh(bad)


def test_to_mesh_export_and_render(tmp_path):
    s = ImplicitSurface.sphere(1.0, 0.1)
    u = s.field(lambda x, y, z: z)
    mesh = s.to_mesh(u)
    r = np.linalg.norm(mesh.vertices, axis=1)
    assert np.abs(r - 1).max() < 0.02
    np.testing.assert_allclose(mesh.vertex_attributes["u"], mesh.vertices[:, 2], atol=1e-3)
    # normals point outwards
    assert np.mean(np.einsum("ij,ij->i", mesh.face_normals, mesh.triangles_center)) > 0.9
    # colours follow the ramp: the top is yellow-ish, the bottom dark
    top, bottom = mesh.vertices[:, 2].argmax(), mesh.vertices[:, 2].argmin()
    assert mesh.visual.vertex_colors[top, 0] > 200 and mesh.visual.vertex_colors[bottom, 0] < 100
    for ext in ("ply", "glb"):
        export_mesh(mesh, tmp_path / f"s.{ext}")
        back = trimesh.load(tmp_path / f"s.{ext}", force="mesh")
        assert len(back.faces) == len(mesh.faces)
    image = s.render(u, tmp_path / "s.png", views=[(0, 0), (0, 90)], size=64, colour_bar=False)
    assert image.shape == (64, 128, 3) and (tmp_path / "s.png").stat().st_size > 0
    # a sphere seen from the side fills a disk: about pi/4 * 0.92^2 of the square
    filled = (image[:, :64] != 255).any(axis=2).mean()
    assert 0.55 < filled < 0.75
    # seen from the side (elevation 0) with u = z the top row of the disk is bright
    rows = np.flatnonzero((image[:, :64] != 255).any(axis=2).any(axis=1))
    assert image[rows[2], 32].sum() > image[rows[-3], 32].sum()
    with pytest.raises(InputError, match="png"):
        s.render(u, tmp_path / "s.jpg")


def test_colormap_ends():
    c = colormap(np.array([0.0, 0.5, 1.0]))
    assert c.shape == (3, 3) and c[0].sum() < c[2].sum()


# ---- holes wider than a cell: the winding number ------------------------------------------


def winding_reference(mesh, points):
    """Exact generalized winding number in float64: Van Oosterom-Strackee per triangle."""
    tri = np.asarray(mesh.triangles, dtype=np.float64)
    out = np.empty(len(points))
    for k, p in enumerate(points):
        a, b, c = (tri[:, i] - p for i in range(3))
        la, lb, lc = (np.linalg.norm(v, axis=1) for v in (a, b, c))
        det = np.einsum("ij,ij->i", a, np.cross(b, c))
        den = (
            la * lb * lc
            + np.einsum("ij,ij->i", a, b) * lc
            + np.einsum("ij,ij->i", b, c) * la
            + np.einsum("ij,ij->i", c, a) * lb
        )
        out[k] = np.arctan2(det, den).sum() / (2 * np.pi)
    return out


def test_winding_kernel_matches_the_exact_sum_and_its_far_field_approximation(rng):
    from clpde.surface.winding import winding_number

    small = trimesh.creation.icosphere(2, radius=1.0)
    pts = rng.uniform(-1.6, 1.6, (300, 3))
    np.testing.assert_allclose(
        winding_number(small, pts, exact=True), winding_reference(small, pts), atol=1e-5
    )
    mesh = trimesh.creation.icosphere(4, radius=1.0)
    pts = np.concatenate(
        [rng.uniform(-1.6, 1.6, (1500, 3)), mesh.vertices[:500] * rng.uniform(0.9, 1.1, (500, 1))]
    )
    exact = winding_number(mesh, pts, exact=True)
    np.testing.assert_allclose(exact[:300], winding_reference(mesh, pts[:300]), atol=1e-5)
    fast = winding_number(mesh, pts)  # two-level far field, beta = 2 (its documented bound)
    assert np.abs(fast - exact).max() < 0.05
    r = np.linalg.norm(pts, axis=1)
    assert np.abs(exact[r < 0.95] - 1).max() < 1e-4 and np.abs(exact[r > 1.05]).max() < 1e-4
    assert np.abs(fast[r < 0.95] - 1).max() < 0.05 and np.abs(fast[r > 1.05]).max() < 0.05


def _cap_removed(mesh, radius):
    """The mesh without the faces within `radius` of its top, and the removed faces."""
    gone = np.linalg.norm(mesh.triangles_center - [0, 0, 1], axis=1) < radius
    holed = mesh.copy()
    holed.update_faces(~gone)
    removed = mesh.copy()
    removed.update_faces(gone)
    return holed, removed


def _check_sphere_sign(surf, removed=None, cells_away=2.0):
    """Every band cell farther than cells_away cells from the removed faces has the exact
    sphere's side, and its psi is the sphere's distance there (the zero level set is the
    sphere's)."""
    from scipy.spatial import cKDTree

    from clpde.surface.mesh_sdf import _surface_samples

    h = surf.spacing
    pts = grid_points(surf.origin, h, surf.shape)
    band = np.flatnonzero(surf._mesh_face.ravel() >= 0)
    keep, near = band, np.zeros(band.size, dtype=bool)
    if removed is not None:
        samples, _ = _surface_samples(removed, 0.2 * h)
        tree = cKDTree(samples)
        keep = band[tree.query(pts[band])[0] > cells_away * h]
        # cells whose nearest point on the sphere is near the hole: |psi| is the distance to
        # the hole's rim there, not to the sphere
        radial = pts[keep] / np.linalg.norm(pts[keep], axis=1)[:, None]
        near = tree.query(radial)[0] <= cells_away * h
    r = np.linalg.norm(pts[keep], axis=1)
    psi = surf.psi.ravel()[keep]
    off_surface = np.abs(r - 1) > 0.01  # the icosphere lies within 0.003 inside the sphere
    assert keep.size > 0.8 * band.size
    assert np.all((psi[off_surface] < 0) == (r[off_surface] < 1))
    cap = np.abs(surf.psi).max()  # cells past the band hold the band's cap
    assert np.abs(psi - np.clip(r - 1, -cap, cap))[~near].max() < 0.01


def test_hole_wider_than_cells_is_closed_by_the_winding_number():
    mesh = trimesh.creation.icosphere(4, radius=1.0)
    holed, removed = _cap_removed(mesh, 0.25)  # a hole about 12 cells across at resolution 48
    assert not holed.is_watertight
    with pytest.warns(UserWarning, match="winding number"):
        surf = ImplicitSurface.from_mesh(holed, resolution=48)
    _check_sphere_sign(surf, removed)
    # one missing triangle several cells wide (the example)
    coarse = trimesh.creation.icosphere(2)
    one = coarse.copy()
    one.update_faces(np.arange(len(coarse.faces)) != 7)
    gone = coarse.copy()
    gone.update_faces(np.arange(len(coarse.faces)) == 7)
    with pytest.warns(UserWarning, match="watertight"):
        surf = ImplicitSurface.from_mesh(one, resolution=64)
    pts = grid_points(surf.origin, surf.spacing, surf.shape)
    band = np.flatnonzero(surf._mesh_face.ravel() >= 0)
    inner = np.linalg.norm(pts[band], axis=1) < 0.7  # well inside the coarse icosphere
    assert np.all(surf.psi.ravel()[band[inner]] < 0)


def test_inside_out_and_half_flipped_meshes_with_a_big_hole():
    mesh = trimesh.creation.icosphere(4, radius=1.0)
    inverted = mesh.copy()
    inverted.invert()
    surf = ImplicitSurface.from_mesh(inverted, resolution=40)  # closed, inside out
    _check_sphere_sign(surf, None)
    holed, removed = _cap_removed(mesh, 0.3)
    holed_inverted = holed.copy()
    holed_inverted.invert()
    flipped = holed.copy()
    faces = flipped.faces.copy()
    faces[::2] = faces[::2, ::-1]
    flipped.faces = faces
    for case in (holed_inverted, flipped):
        vertices, faces = case.vertices.copy(), case.faces.copy()
        with pytest.warns(UserWarning, match="watertight"):
            surf = ImplicitSurface.from_mesh(case, resolution=40)
        _check_sphere_sign(surf, removed)
        # the caller's mesh is left as it was
        np.testing.assert_array_equal(case.faces, faces)
        np.testing.assert_array_equal(case.vertices, vertices)


def test_a_closed_hole_is_a_distance_and_carries_flows_across():
    """Where a hole was closed, |psi| was the distance to its rim and psi jumped across the
    closing sheet; the rim's cells are reinitialised, so psi is a distance there too and the
    heat flow away from the hole stays close to the closed sphere's (benchmarks/
    surface_accuracy.py section 5c: error 9.0e-4 against 2.8e-4 closed, 8.6e-3 without the
    reinitialisation)."""
    mesh = trimesh.creation.icosphere(4, radius=1.0)
    holed, _ = _cap_removed(mesh, 0.45)  # a polar hole about 18 cells across
    pts = np.random.default_rng(4).standard_normal((600, 3))
    pts /= np.linalg.norm(pts, axis=1)[:, None]
    away = pts[pts[:, 2] < 0.7] * 0.999
    errors = []
    for case in (mesh, holed):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            surf = ImplicitSurface.from_mesh(case, resolution=40)
        slope = np.sqrt(sum(g**2 for g in np.gradient(surf.psi, surf.spacing)))
        band = np.abs(surf.psi) < 2 * surf.spacing
        assert np.mean(np.abs(slope[band] - 1) > 0.1) < 0.005
        u = surf.field(lambda x, y, z: x * y)
        v = surf.heat(u, t=0.1)
        errors.append(np.abs(surf.sample(v, away) - np.exp(-0.6) * away[:, 0] * away[:, 1]).max())
        surf.sample(v, [[0.0, 0.0, 0.93]])  # the sheet closing the hole is a surface to sample
    assert errors[1] < 3 * errors[0], errors


@pytest.mark.parametrize("variant", ["holed", "half-flipped", "inside-out"])
def test_face_sides_agree_with_the_winding_number(monkeypatch, variant):
    """Leaked components decide most band cells by the side of their closest triangle's
    plane; every band cell gets the side the winding number alone gives it."""
    from clpde.surface import mesh_sdf

    holed, _ = _cap_removed(trimesh.creation.icosphere(4, radius=1.0), 0.3)
    if variant == "half-flipped":
        faces = holed.faces.copy()
        faces[::2] = faces[::2, ::-1]
        holed.faces = faces
    elif variant == "inside-out":
        holed.invert()
    origin, h, shape = grid_for_mesh(holed, None, 40, 9)
    stats = {}
    fast, face, _ = mesh_to_sdf(holed, origin, h, shape, 8.0, stats=stats)
    assert stats["decided_by_faces"] > stats["winding_points"]  # most cells skip the winding number

    def undecided(triangles, components, face, *rest, **options):
        return np.zeros(len(face), dtype=bool), np.zeros(len(face), dtype=bool)

    monkeypatch.setattr(mesh_sdf, "_face_sides", undecided)
    slow, _, _ = mesh_to_sdf(holed, origin, h, shape, 8.0)
    band = face >= 0
    np.testing.assert_array_equal(np.sign(fast[band]), np.sign(slow[band]))


@pytest.mark.parametrize(
    ("lo", "hi", "labels"),
    [
        (-3.02e-06, 1.0, ("0", "1")),  # data in [0, 1] with a round-off below 0
        (0.2, 0.2000001, ("0.2", "0.2000001")),  # a narrow range: its ends still differ
        (-1.5, 2.25, ("-1.5", "2.25")),
        (0.0, 12345.678, ("0", "12300")),
    ],
)
def test_colour_bar_ends_are_rounded(lo, hi, labels):
    from clpde.surface.render import _label_format

    assert _label_format(lo, hi) == labels
