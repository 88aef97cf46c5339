"""method="auto": the per-box choice between the structure method and the exemplar
(clpde/inpainting/choose.py)."""

import numpy as np

import clpde
from clpde.inpainting import choose
from clpde.inpainting import registry as inpainting


def _textured(ny=160, nx=200, seed=0):
    """A periodic texture (tiles of period 10 with sharp edges) plus a little noise."""
    rng = np.random.default_rng(seed)
    y, x = np.mgrid[0:ny, 0:nx]
    image = 0.25 + 0.5 * (((x // 5) + (y // 5)) % 2) + 0.02 * rng.standard_normal((ny, nx))
    return np.clip(np.round(image * 255), 0, 255).astype(np.uint8)


def test_features_of_a_disc_in_flat_periodic_and_stochastic_surroundings():
    y, x = np.mgrid[0:80, 0:80]
    disc = np.hypot(y - 40, x - 40) <= 12
    flat = np.full((1, 80, 80), 0.4)
    f = choose.features(flat, disc)
    assert f["texture"] < 1e-6 and f["periodicity"] == 0 and 11.5 <= f["radius"] <= 13.5
    f = choose.features(_textured(80, 80)[None] / 255.0, disc)
    assert f["texture"] > 0.1 and f["periodicity"] > choose.MIN_PERIODICITY
    noise = np.random.default_rng(3).random((1, 80, 80))
    f = choose.features(noise, disc)
    assert f["texture"] > 0.1 and f["periodicity"] < 0.3
    # the values in the hole are never read
    noisy = flat.copy()
    noisy[:, disc] = np.random.default_rng(1).random(int(disc.sum()))
    assert choose.features(noisy, disc) == choose.features(flat, disc)


def test_auto_gives_thick_texture_holes_to_the_exemplar_and_thin_ones_to_the_structure():
    assert "exemplar" in inpainting.available()  # part of the package: never skipped
    image = _textured(160, 260)
    y, x = np.mgrid[0:160, 0:260]
    smooth = 0.3 + 0.3 * np.sin(x / 17.0) * np.cos(y / 23.0)
    right = x >= 130
    image[right] = np.round(255 * smooth[right]).astype(np.uint8)  # not periodic
    mask = np.zeros(image.shape, bool)
    mask[40:70, 30:60] = True  # thick, in the periodic texture
    mask[120:122, 170:250] = True  # a scratch, 2 px, in the smooth part
    out, info = clpde.inpaint(image, mask, method="auto", return_info=True, progress=False,
                              seed=0)
    assert sorted(info.box_methods) == sorted(["exemplar", info.method])
    assert info.method == next(m for m in inpainting.AUTO if m in inpainting.available())
    assert np.array_equal(out[~mask], image[~mask])
    # the periodic texture comes back nearly exact in the thick hole
    err = np.abs(out.astype(float) - image)[40:70, 30:60]
    assert err.mean() < 8, err.mean()
    again = clpde.inpaint(image, mask, method="auto", progress=False, seed=0)
    assert np.array_equal(out, again)


def test_auto_keeps_the_structure_method_on_smooth_images():
    y, x = np.mgrid[0:100, 0:120]
    image = np.clip(np.round(255 * (0.3 + 0.4 * x / 120 + 0.1 * y / 100)), 0, 255).astype(np.uint8)
    mask = np.zeros(image.shape, bool)
    mask[30:70, 40:80] = True
    _, info = clpde.inpaint(image, mask, method="auto", return_info=True, progress=False)
    assert info.box_methods == [info.method]


def test_exemplar_part_keeps_blobs_and_leaves_strokes():
    y, x = np.mgrid[0:100, 0:100]
    disc = np.hypot(y - 50, x - 50) <= 12
    assert np.array_equal(choose.exemplar_part(disc), disc)
    stroke = (np.abs(y - 20) <= 1) & (x >= 10) & (x < 90)  # 3 px wide: never thick
    assert not choose.exemplar_part(stroke).any()
    # a thin stroke touching the disc stays out; the disc stays in
    part = choose.exemplar_part(disc | ((np.abs(x - 50) <= 1) & (y >= 10)))
    assert np.array_equal(part & ~disc, np.zeros_like(disc)) and part.sum() >= 0.95 * disc.sum()
    # a cross of 9 px bold strokes is 6 px thick only where they cross: a stroke
    plus = ((np.abs(y - 50) <= 4) & (np.abs(x - 50) <= 40)) | \
        ((np.abs(x - 50) <= 4) & (np.abs(y - 50) <= 40))
    assert choose.features(np.zeros((1, 100, 100)), plus)["radius"] >= choose.MIN_RADIUS
    assert not choose.exemplar_part(plus).any()


def test_auto_sends_only_the_thick_blob_of_a_box_of_strokes_to_the_exemplar():
    assert "exemplar" in inpainting.available()  # part of the package: never skipped
    rng = np.random.default_rng(5)
    y, x = np.mgrid[0:140, 0:160]
    image = 0.3 + 0.3 * np.sin(x / 19.0) * np.cos(y / 27.0) + 0.08 * rng.standard_normal(x.shape)
    image = np.clip(np.round(255 * image), 0, 255).astype(np.uint8)  # stochastic texture
    blob = np.hypot(y - 70, x - 80) <= 12
    strokes = (np.abs(y - 40) <= 1) & (x >= 30) & (x < 130)
    strokes |= (np.abs(x - y - 10) <= 1) & (y >= 85) & (y < 120)
    strokes |= (np.abs(x - 80) <= 1) & (y >= 40) & (y < 70)  # from the first one to the blob
    mask = blob | strokes
    out, info = clpde.inpaint(image, mask, method="auto", return_info=True, progress=False,
                              seed=0)
    assert len(info.boxes) == 1
    assert info.box_methods == [f"{info.method}+exemplar"]
    assert 0.95 * blob.sum() <= info.box_exemplar_pixels[0] <= blob.sum()
    # the strokes are the structure method's fill of the box, bit for bit; the blob is not
    coherent = clpde.inpaint(image, mask, method=info.method, progress=False)
    thin = mask & ~blob
    assert np.array_equal(out[thin], coherent[thin])
    assert not np.array_equal(out[blob], coherent[blob])
    assert np.array_equal(out[~mask], image[~mask])
    assert np.array_equal(out, clpde.inpaint(image, mask, method="auto", progress=False, seed=0))
