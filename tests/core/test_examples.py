"""The examples write into out/ (or a new folder given by --out, created), never into the
documentation's pictures unless asked with --docs."""

import os
import subprocess
import sys
from pathlib import Path

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
DOCS = EXAMPLES.parent / "docs" / "images"


def _run(args, cwd):
    env = dict(os.environ, PYTHONPATH=str(EXAMPLES.parent))
    return subprocess.run(
        [sys.executable, *map(str, args)],
        cwd=cwd,
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
        stdin=subprocess.DEVNULL,
        check=False,
    )


def test_an_example_creates_its_new_output_folder_and_leaves_the_docs_alone(tmp_path):
    docs_before = {p.name: p.stat().st_mtime_ns for p in DOCS.iterdir()}
    run = _run(
        [
            EXAMPLES / "regions_figure27.py",
            "--spacing",
            "0.1",
            "--saves",
            "1",
            "--size",
            "32",
            "--out",
            "new/nested",
        ],
        tmp_path,
    )
    assert run.returncode == 0, run.stderr
    assert sorted(os.listdir(tmp_path / "new" / "nested")) == [
        "regions_merge.png",
        "regions_split.png",
    ]
    assert sorted(os.listdir(tmp_path / "out" / "regions_split")) == [
        "split.png",
        "split_0.ply",
        "split_1.ply",
    ]
    # a second run replaces its mesh folders instead of failing on them
    assert (
        _run(
            [EXAMPLES / "regions_figure27.py", "--spacing", "0.1", "--saves", "1", "--size", "32"],
            tmp_path,
        ).returncode
        == 0
    )
    assert sorted(os.listdir(tmp_path / "out")) == [
        "regions_merge",
        "regions_merge.png",
        "regions_split",
        "regions_split.png",
    ]
    assert {p.name: p.stat().st_mtime_ns for p in DOCS.iterdir()} == docs_before


_HELPS = """
import contextlib, io, json, os, runpy, sys
out = {}
sys.path.insert(0, os.path.dirname(sys.argv[1]))  # as `python examples/x.py` has it
for path in sys.argv[1:]:
    sys.argv = [path, "--help"]
    text = io.StringIO()
    with contextlib.redirect_stdout(text), contextlib.suppress(SystemExit):
        runpy.run_path(path, run_name="__main__")
    out[path] = text.getvalue()
print(json.dumps(out))
"""


def test_no_example_writes_the_docs_by_default():
    """Every example's --help (all in one interpreter, to keep the test quick): out/ by
    default; docs/images only behind --docs or --figure."""
    import json

    scripts = sorted(str(p) for p in EXAMPLES.glob("*.py") if not p.name.startswith("_"))
    run = _run(["-c", _HELPS, *scripts], EXAMPLES.parent)
    assert run.returncode == 0, run.stderr
    helps = json.loads(run.stdout.strip().splitlines()[-1])
    assert sorted(helps) == scripts
    for script, text in helps.items():
        text = " ".join(text.split())
        assert "default: out" in text, script
        if "docs" in text:
            assert "--docs" in text or "--figure" in text, script
