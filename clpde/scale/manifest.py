"""The batch's manifest: what makes each output what it is, so that a rerun skips the
outputs that are already done.

OUTDIR/clpde-manifest.json records, for every output written, the hash of its input (and
mask), the command and its options with their defaults filled in, and the hash of the
output. An output whose record matches its task's fingerprint and whose file still has the
recorded hash is complete; an unreadable manifest makes every output be redone, which is
safe.
"""

from __future__ import annotations

import contextlib
import hashlib
import inspect
import json
import numbers
import shutil
from pathlib import Path

import numpy as np

from .._version import __version__
from ..io.images import atomic_output
from .file_tasks import TASKS

MANIFEST = "clpde-manifest.json"


def hash_path(path) -> str | None:
    """sha256 of a file, or of a folder's files (names and contents, sorted); None if absent."""
    path = Path(path)
    if path.is_file():
        files = [path]
    elif path.is_dir():
        files = sorted(p for p in path.rglob("*") if p.is_file())
    else:
        return None
    digest = hashlib.sha256()
    for p in files:
        if path.is_dir():
            digest.update(p.relative_to(path).as_posix().encode() + b"\0")
        with open(p, "rb") as f:
            for block in iter(lambda: f.read(1 << 20), b""):
                digest.update(block)
    return digest.hexdigest()


def read_manifest(outdir: Path) -> dict:
    path = outdir / MANIFEST
    if not path.is_file():
        return {}
    try:
        data = json.loads(path.read_text())
        return dict(data.get("outputs", {}))
    except (OSError, ValueError, AttributeError):
        return {}  # unreadable: every output is redone, which is safe


def write_manifest(outdir: Path, records: dict) -> None:
    data = {"clpde": __version__, "outputs": dict(sorted(records.items()))}
    with atomic_output(outdir / MANIFEST) as tmp:
        tmp.write_text(json.dumps(data, indent=1) + "\n")


def sweep_temporaries(outdir: Path, names) -> None:
    """Remove the temporary files and folders that killed workers left for these outputs."""
    for name in names:
        for stray in outdir.glob(f".{name}.*.part"):
            if stray.is_dir():
                shutil.rmtree(stray, ignore_errors=True)
            else:
                with contextlib.suppress(OSError):
                    stray.unlink()


def fingerprint(spec: dict) -> dict:
    """What makes an output what it is: the inputs' contents and the command line."""
    digest = hash_path(spec["input"])
    if digest is None and spec["command"] == "surface":  # a shape name (sphere, torus...)
        digest = hashlib.sha256(f"shape:{spec['input']}".encode()).hexdigest()
    return {
        "command": spec["command"],
        "options": fingerprint_options(spec),
        "tile": spec["tile"],
        "input_sha256": digest,
        "mask_sha256": None if spec["mask"] is None else hash_path(spec["mask"]),
    }


def fingerprint_options(spec: dict) -> dict:
    """The task's options with its defaults filled in, as JSON values (numbers as floats, so
    that the command line's flags and Python's keywords for the same run match); the device
    and progress left out."""
    task = TASKS[spec["command"]]
    params = inspect.signature(task).parameters
    values = {
        n: p.default
        for n, p in params.items()
        if p.kind is p.KEYWORD_ONLY and n not in ("mask", "device", "progress", "tile")
    }
    values.update({k: v for k, v in spec["options"].items() if k in values})
    # numbers as floats: tol=0 from Python and --tol 0 (a float) are the same run
    return {k: _json_value(v) for k, v in sorted(values.items())}


def _json_value(value):
    """`value` as it reads back from the manifest's JSON: numbers as floats (tol=0 from
    Python and --tol 0 are the same run), tuples as lists, anything else as its text."""
    if isinstance(value, numbers.Real) and not isinstance(value, bool | np.bool_):
        return float(value)
    if isinstance(value, np.bool_):
        return bool(value)
    return json.loads(json.dumps(value, default=str))


def is_complete(record: dict | None, fingerprint: dict, output: str) -> bool:
    if not record or any(record.get(k) != v for k, v in fingerprint.items()):
        return False
    if fingerprint["input_sha256"] is None:
        return False
    return record.get("output_sha256") is not None and record["output_sha256"] == hash_path(output)
