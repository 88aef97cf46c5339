"""Structure plus texture inpainting, after Bertalmio, Vese, Sapiro and Osher (IEEE TIP 2003).

The image f is split into a structure part u, the minimiser of TV(u) + lambda/2 |u - f|^2
(clpde.denoise_tv, ROF, on the device), and a texture part v = f - u. Each is filled by
the method that suits it: u, piecewise smooth, by a structure method that continues its
edges (the registry's "transport" method, the thesis's multiresolution PDE, else
"coherence", else clpde.inpaint); v, which has no large-scale structure left, by texture
synthesis (the exemplar method on v). The result is their sum.

The TV split needs values in the hole; they are set to those of the nearest known pixel
before the split, and only the split's known part is used afterwards. With ``guide`` > 0
the exemplar search on v also compares the filled structure u (weighted by ``guide``),
so that a texture patch is taken from where the structure looks alike.

A copied texture is only worth its full amplitude where it predicts the hole: copying an
unrelated sample of a random texture doubles the error that leaving it out would make. The
texture's share (``texture_gain``) is therefore chosen on probes, copies of the hole moved
onto known pixels: 1 (the paper's sum) where the full texture predicts them better than
half of it, else 1/2, with the other half left to the structure method. Periodic patterns
keep the full copy; smooth float fields, whose split puts nearly everything into v, get
half (docs/inpainting_texture.md, "Texture share").
"""

from __future__ import annotations

import dataclasses
import functools
from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from ..errors import InputError
from ..planar.rof import denoise_tv
from . import exemplar
from .registry import METHODS, keywords, load, register

# The transport first: coherence's shells of a square hole meet on its diagonals and leave
# creases there (the cup's rim as a V); the transport's structure scores higher on the
# periodic, texture and thick cases (docs/inpainting_texture.md).
STRUCTURE_METHODS = ("transport", "coherence")


@dataclass(frozen=True)
class StructureTextureOptions:
    """method="structure-texture"'s options, checked on construction.

    Parameters
    ----------
    tv_weight : float
        The ROF weight relative to the known pixels' span (larger puts more into the
        texture part); the result of a * data + b is a * result + b. 1.5: of 1, 1.5 and 2,
        the one that does best on the texture and thick cases without giving up the
        periodic ones (docs/inpainting_texture.md has the table).
    guide : float
        Weight of the filled structure in the texture's patch distance (0: none).
    structure : str, optional
        The structure method's name (default: transport, else coherence).
    texture : ExemplarOptions
        The exemplar's options for the texture part (its own structure guide off: the
        filled structure guides it).
    texture_gain : float, optional
        The share of the texture part that is copied (the rest goes to the structure
        method); None: 1 or 1/2, whichever predicts probes of the hole on known pixels
        better. 1 is the paper's method.
    """

    tv_weight: float = 1.5
    guide: float = 0.5
    structure: str | None = None
    texture: exemplar.ExemplarOptions = exemplar.ExemplarOptions(structure=0.0)
    texture_gain: float | None = None

    def __post_init__(self) -> None:
        for name in ("tv_weight", "guide"):
            value = getattr(self, name)
            if (
                not isinstance(value, (int, float, np.integer, np.floating))
                or not np.isfinite(value)
                or value < (0 if name == "guide" else 1e-12)
            ):
                wanted = "weight >= 0" if name == "guide" else "positive number"
                raise InputError(f"{name} must be a {wanted}, not {value!r}")
        if self.structure is not None and self.structure not in METHODS:
            raise InputError(
                f"structure must be an inpainting method ({', '.join(STRUCTURE_METHODS)} "
                f"suit it) or None, not {self.structure!r}"
            )
        if not isinstance(self.texture, exemplar.ExemplarOptions):
            raise InputError(
                f"texture must be an ExemplarOptions, not {type(self.texture).__name__}"
            )
        gain = self.texture_gain
        if gain is not None and (
            not isinstance(gain, (int, float, np.integer, np.floating)) or not 0 <= gain <= 1
        ):
            raise InputError(f"texture_gain must be None or in [0, 1], not {gain!r}")


DEFAULTS = {f.name: f.default for f in dataclasses.fields(StructureTextureOptions)}


def MARGIN(omega=None, search=exemplar.DEFAULTS["search"], **_params) -> int:
    """The exemplar's search region, which also covers the structure methods' reach."""
    return max(int(search), 16)


def _structure_solver(name):
    """solve(data, omega, runtime, ...) of the structure method `name`, or of the first of
    STRUCTURE_METHODS that is installed."""
    for method in [name] if name else list(STRUCTURE_METHODS):
        try:
            solve = load(method).solve
        except InputError:
            if name:
                raise
            continue
        if method == "transport":
            # the thesis's own stop: the hidden ring's probe (transport's default on periodic
            # surrounds) changed no case of the corpus's periodic calibration class here, at
            # twice the time (docs/inpainting.md, "Stopping on a hidden ring")
            return functools.partial(solve, holdout=0)
        return solve
    raise InputError(
        f"none of the structure methods {', '.join(STRUCTURE_METHODS)} is "
        "available in this installation"
    )


def known_range(data, omega):
    """(lo, hi) of the known pixels over all channels: the span clpde.inpaint maps to [0, 1]
    for a float image, so that the method sees the same problem through it as alone."""
    known = data[:, ~omega]
    lo, hi = float(known.min()), float(known.max())
    return lo, (hi if hi > lo else lo + 1.0)


def decompose(data, omega, runtime, tv_weight: float):
    """(u, v): the TV structure and the texture f - u, the hole pre-filled by nearest values.

    tv_weight is relative to the known pixels' span (ROF's weight is in the image's units):
    the split of a * f + b is then a * u + b and a * v, whatever the image's contrast."""
    lo, hi = known_range(data, omega)
    idx = ndimage.distance_transform_edt(omega, return_distances=False, return_indices=True)
    filled = data[:, idx[0], idx[1]]
    u = denoise_tv(
        np.moveaxis(filled, 0, -1),
        weight=tv_weight * (hi - lo),
        channel_axis=-1,
        device=runtime,
        progress=False,
    )
    u = np.moveaxis(np.asarray(u, np.float64), -1, 0)
    return u, filled - u


# The texture shares the probes choose between: the paper's whole copy, or half of it. Half
# is the neutral shrinkage of a copy that is as likely unrelated as matched (no finer grid
# was tried: docs/inpainting_texture.md).
GAINS = (1.0, 0.5)


def probes(omega):
    """Copies of the hole moved by half the image along each axis and both (wrapping),
    less the hole itself: known pixels hidden the way the hole hides its own."""
    rows, cols = omega.shape
    out = []
    for shift in ((rows // 2, cols // 2), (rows // 2, 0), (0, cols // 2)):
        probe = np.roll(omega, shift, axis=(0, 1)) & ~omega
        if probe.any():
            out.append(probe)
    return out


def fill(u, v, omega, gain, fill_structure, fill_texture, texture=None):
    """u + (1 - gain) v filled by the structure method plus gain times the texture fill
    of v (``texture``: a fill of v to reuse, else fill_texture(omega, structure fill))."""
    s = fill_structure(u + (1.0 - gain) * v if gain < 1 else u, omega)
    if gain == 0:
        return s
    t = fill_texture(omega, s) if texture is None else texture
    return s + gain * t


def choose_gain(u, v, omega, fill_structure, fill_texture) -> float:
    """GAINS' share whose fill of the probes is closer to the known values, summed over
    the probes (1 when there are none). The texture fill of each probe is the whole
    share's, reused for the half."""
    f = u + v
    errors = np.zeros(len(GAINS))
    for probe in probes(omega):
        hole = omega | probe
        s = fill_structure(u, hole)
        t = fill_texture(hole, s)
        for i, gain in enumerate(GAINS):
            got = s + t if gain == 1 else fill(u, v, hole, gain, fill_structure, None, t)
            # in dB, so that each probe counts alike whatever its size or contrast
            errors[i] += np.log10(np.mean((got - f)[:, probe] ** 2) + 1e-30)
    return GAINS[int(np.argmin(errors))]


@register(
    "structure-texture",
    StructureTextureOptions,
    margin=lambda omega, o: MARGIN(omega, o.texture.search),
    ghost=2,  # its structure may be the transport's, whose grids have two ghost layers
)
def solve(
    data,
    omega,
    runtime,
    *,
    dtype=np.float32,
    progress=None,
    seed=None,
    tv_weight=StructureTextureOptions.tv_weight,
    guide=StructureTextureOptions.guide,
    structure=StructureTextureOptions.structure,
    texture=None,
    texture_gain=StructureTextureOptions.texture_gain,
    **exemplar_params,
):
    """Fill ``omega``: TV structure by a structure method, texture by the exemplar method.

    tv_weight, guide, structure, texture, texture_gain: StructureTextureOptions'.
    Other keywords (patch, search, iterations, ...) go to the exemplar method, over
    `texture`'s.
    """
    if "guide" in exemplar_params:
        raise InputError("guide is this method's weight of the structure; give a number")
    StructureTextureOptions(tv_weight, guide, structure, texture_gain=texture_gain)  # checks
    exemplar_params = {**(keywords(texture) if texture is not None else {}), **exemplar_params}
    data = np.asarray(data)
    omega = np.asarray(omega, bool)
    out = np.array(data, copy=True)
    if not omega.any():
        return out
    u, v = decompose(np.asarray(data, np.float64), omega, runtime, float(tv_weight))
    solve_structure = _structure_solver(structure)
    # the texture's own search is guided by u (below), not by a structure fill of v
    exemplar_params.setdefault("structure", 0.0)

    def fill_structure(part, hole):
        return np.asarray(
            solve_structure(part, hole, runtime, dtype=dtype, progress=progress, seed=seed),
            np.float64,
        )

    def fill_texture(hole, structure_filled):
        return exemplar.solve(
            v,
            hole,
            runtime,
            dtype=dtype,
            progress=progress,
            seed=seed,
            guide=guide * structure_filled if guide > 0 else None,
            **exemplar_params,
        )

    if texture_gain is None:
        texture_gain = choose_gain(u, v, omega, fill_structure, fill_texture)
    filled = fill(u, v, omega, float(texture_gain), fill_structure, fill_texture)
    # the known range, not [0, 1]: the same clip for a float image alone and through
    # clpde.inpaint, which stretches it to [0, 1]
    total = np.clip(filled, *known_range(data, omega))
    out[:, omega] = total[:, omega].astype(out.dtype)
    return out
