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
"""

from __future__ import annotations

import dataclasses
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
    """

    tv_weight: float = 1.5
    guide: float = 0.5
    structure: str | None = None
    texture: exemplar.ExemplarOptions = exemplar.ExemplarOptions(structure=0.0)

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


DEFAULTS = {f.name: f.default for f in dataclasses.fields(StructureTextureOptions)}


def MARGIN(omega=None, search=exemplar.DEFAULTS["search"], **_params) -> int:
    """The exemplar's search region, which also covers the structure methods' reach."""
    return max(int(search), 16)


def _structure_solver(name):
    """solve(data, omega, runtime, ...) of the structure method `name`, or of the first of
    STRUCTURE_METHODS that is installed."""
    for method in [name] if name else list(STRUCTURE_METHODS):
        try:
            return load(method).solve
        except InputError:
            if name:
                raise
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
    **exemplar_params,
):
    """Fill ``omega``: TV structure by a structure method, texture by the exemplar method.

    tv_weight, guide, structure, texture: StructureTextureOptions'. Other keywords
    (patch, search, iterations, ...) go to the exemplar method, over `texture`'s.
    """
    if "guide" in exemplar_params:
        raise InputError("guide is this method's weight of the structure; give a number")
    StructureTextureOptions(tv_weight, guide, structure)  # the checks
    exemplar_params = {**(keywords(texture) if texture is not None else {}), **exemplar_params}
    data = np.asarray(data)
    omega = np.asarray(omega, bool)
    out = np.array(data, copy=True)
    if not omega.any():
        return out
    u, v = decompose(np.asarray(data, np.float64), omega, runtime, float(tv_weight))
    u_filled = np.asarray(
        _structure_solver(structure)(u, omega, runtime, dtype=dtype, progress=progress, seed=seed),
        np.float64,
    )
    guide_planes = guide * u_filled if guide > 0 else None
    # the texture's own search is guided by u (above), not by a structure fill of v
    exemplar_params.setdefault("structure", 0.0)
    v_filled = exemplar.solve(
        v,
        omega,
        runtime,
        dtype=dtype,
        progress=progress,
        seed=seed,
        guide=guide_planes,
        **exemplar_params,
    )
    # the known range, not [0, 1]: the same clip for a float image alone and through
    # clpde.inpaint, which stretches it to [0, 1]
    total = np.clip(u_filled + v_filled, *known_range(data, omega))
    out[:, omega] = total[:, omega].astype(out.dtype)
    return out
