"""Planning a batch on the client, before anything runs: the inputs expanded and checked,
each given its output's name and its mask, as one task spec per input.

Everything a batch can refuse is refused here, before any folder is created or any worker
started: an unknown command, a missing mask, two inputs that would write one output, an
output folder that holds an input or cannot be written.
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from pathlib import Path

from ..errors import InputError
from ..io.images import IMAGE_FORMATS, PathLike, check_folder_writable
from .file_tasks import TASKS
from .manifest import MANIFEST

COMMANDS = tuple(TASKS)  # inpaint, denoise, diffuse, track, surface
FOLDER_OUTPUTS = ("track", "surface")  # one output folder per input, named by its stem
MASKED = ("inpaint", "track")  # commands that take a mask per input (track: --init)
MAY_MASK = ("restore",)  # commands that take a mask per input if given (restore: else detects)
TILED = ("diffuse", "denoise")


def find_mask(masks_dir: Path, source: Path) -> Path | None:
    """The mask named like its image: the same file name, or the same stem as any image."""
    same = masks_dir / source.name
    if same.is_file():
        return same
    if (masks_dir / source.stem).is_dir():  # a film's folder of per-frame masks
        return masks_dir / source.stem
    for suffix in IMAGE_FORMATS:
        candidate = masks_dir / f"{source.stem}{suffix}"
        if candidate.is_file():
            return candidate
    return None


def expand_inputs(inputs: Iterable[PathLike]) -> list[str]:
    """The inputs, with any pattern (``*``, ``?``, ``[``) that names no existing file
    expanded as a shell would (sorted): a quoted pattern, or one from Python. A pattern
    that matches nothing is an error, before anything is created: the shell passes such a
    pattern on as it is, and it names no file."""
    import glob

    if isinstance(inputs, (str, os.PathLike)):
        inputs = [inputs]
    out = []
    for item in inputs:
        text = os.fspath(item)
        if any(c in text for c in "*?[") and not os.path.exists(text):
            found = sorted(glob.glob(text))
            if not found:
                raise InputError(
                    f"the pattern {text} matches no file; check the folder and the spelling"
                )
            out += found
        else:
            out.append(text)
    return out


def plan_tasks(command, inputs, outdir: Path, mask, masks, options, tile) -> list[dict]:
    if command not in COMMANDS:
        raise InputError(f"unknown batch command {command!r}; choose one of {', '.join(COMMANDS)}")
    if not inputs:
        raise InputError("give at least one input")
    if command in MASKED:
        if (mask is None) == (masks is None):
            what = "--init mask" if command == "track" else "mask"
            raise InputError(
                f"batch {command} needs one {what}: --mask FILE (one for all "
                "inputs) or --masks DIR (one per input, named like it)"
            )
    elif (mask is not None or masks is not None) and command not in MAY_MASK:
        raise InputError(f"--mask and --masks apply to inpaint, track and restore, not {command}")
    if tile and command not in TILED:
        raise InputError(f"--tile applies to diffuse and denoise, not {command}")
    if command == "surface" and not options.get("flow"):
        raise InputError("batch surface needs --flow FLOW (heat, tv, denoise, ...)")
    if masks is not None and not Path(masks).is_dir():
        raise InputError(f"--masks {masks} is not a folder; give the folder of masks")
    if mask is not None and not (
        Path(mask).is_file() or (command in MAY_MASK and Path(mask).is_dir())
    ):
        raise InputError(f"mask {mask} does not exist")
    if outdir.exists() and not outdir.is_dir():
        raise InputError(f"output {outdir} exists and is not a folder")
    existing = outdir  # the folder, or the nearest folder above it that mkdir writes into
    while not existing.exists() and existing != existing.parent:
        existing = existing.parent
    check_folder_writable(existing, f"the output folder {outdir}")
    specs, names = [], {}
    for item in inputs:
        source = Path(item)
        (name,) = output_names(command, [source])
        if not name or name == MANIFEST:
            raise InputError(f"input {source} gives no usable output name")
        if name in names:
            raise InputError(
                f"inputs {names[name]} and {source} would both write {outdir / name}; "
                "rename one or run them into separate folders"
            )
        names[name] = source
        if outdir.resolve() == source.resolve().parent and command not in FOLDER_OUTPUTS:
            raise InputError(
                f"output folder {outdir} holds the input {source}; clpde never "
                "overwrites its inputs, choose another folder"
            )
        mask_path, mask_error = mask, None
        if masks is not None:
            found = find_mask(Path(masks), source)
            mask_path = str(found) if found else None
            if found is None:
                mask_error = f"no mask for {source.name} in {masks} (expected {source.name})"
        specs.append(
            {
                "command": command,
                "input": str(source),
                "output": str(outdir / name),
                "name": name,
                "mask": None if mask_path is None else str(mask_path),
                "mask_error": mask_error,
                "options": dict(options),
                "tile": bool(tile),
            }
        )
    return specs


def output_names(command, inputs) -> list[str]:
    return [Path(p).stem if command in FOLDER_OUTPUTS else Path(p).name for p in inputs]
