"""Inpainting builds its programs once: a new image size builds nothing, and a second channel
count (grey after colour) builds no new program. Builds are counted on a runtime of its own,
whose program cache starts empty."""

import numpy as np
import pytest

import clpde
from clpde import runtime as rt


@pytest.fixture
def fresh(monkeypatch):
    base = rt.get_runtime()
    own = rt.Runtime(base.index, base.platform, base.device)
    built = []
    build = rt.Runtime._build

    def counting(self, filename, dtype, defines):
        if self is own:
            built.append((filename, dict(defines)))
        return build(self, filename, dtype, defines)

    monkeypatch.setattr(rt.Runtime, "_build", counting)
    return own, built


def _case(ny, nx, channels, seed=0):
    rng = np.random.default_rng(seed)
    y, x = np.mgrid[0:ny, 0:nx]
    base = 0.5 + 0.3 * np.sin(x / 5.0) * np.cos(y / 7.0)
    image = base[..., None] + 0.05 * rng.standard_normal((ny, nx, channels))
    image = np.clip(np.round(255 * image), 0, 255).astype(np.uint8)
    mask = np.hypot(y - ny / 2, x - nx / 3) <= 5
    mask[ny // 4, 3 : nx - 3] = True  # a scratch: a second component, far enough apart
    return (image[..., 0] if channels == 1 else image), mask


@pytest.mark.parametrize("method", [None, "transport", "navier-stokes", "spectral"])
def test_new_size_and_channel_count_build_nothing(fresh, method):
    own, built = fresh
    kw = {"method": method} if method else {}

    def run(ny, nx, channels):
        image, mask = _case(ny, nx, channels)
        clpde.inpaint(
            image,
            mask,
            channel_axis=-1 if channels > 1 else None,
            device=own,
            progress=False,
            seed=0,
            **kw,
        )

    run(48, 56, 3)
    first = list(built)
    assert first, "the first call builds its programs"
    run(61, 45, 3)  # a new size
    assert built == first, built[len(first) :]
    run(52, 60, 1)  # grey after colour
    assert built == first, built[len(first) :]


def test_first_use_says_it_builds_and_leaves_the_build_out_of_its_time(capsys):
    """A runtime that has built nothing yet (a first use): the notice on stderr, the build's
    seconds in info.build_seconds and not in info.seconds; the second call builds nothing
    and says nothing."""
    from clpde.runtime import Runtime, get_runtime

    shared = get_runtime("cpu")
    fresh = Runtime(shared.index, shared.platform, shared.device)
    image = np.tile(np.linspace(0, 1, 40, dtype=np.float32), (40, 1))
    mask = np.zeros((40, 40), bool)
    mask[15:22, 10:30] = True
    _, info = clpde.inpaint(image, mask, device=fresh, progress=True, return_info=True)
    assert "building kernels (once)" in capsys.readouterr().err
    assert info.build_seconds > 0 and fresh.build_seconds >= info.build_seconds
    _, again = clpde.inpaint(image, mask, device=fresh, progress=True, return_info=True)
    assert "building kernels" not in capsys.readouterr().err
    assert again.build_seconds == 0
