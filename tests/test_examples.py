"""The examples write into out/ (or a new folder given by --out, created), never into the
documentation's pictures unless asked with --docs."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
DOCS = EXAMPLES.parent / "docs" / "images"


def _run(args, cwd):
    env = dict(os.environ, PYTHONPATH=str(EXAMPLES.parent))
    return subprocess.run([sys.executable, *map(str, args)], cwd=cwd, env=env, capture_output=True,
                          text=True, timeout=300, stdin=subprocess.DEVNULL, check=False)


def test_an_example_creates_its_new_output_folder_and_leaves_the_docs_alone(tmp_path):
    docs_before = {p.name: p.stat().st_mtime_ns for p in DOCS.iterdir()}
    run = _run([EXAMPLES / "regions_figure27.py", "--spacing", "0.1", "--saves", "1",
                "--size", "32", "--out", "new/nested"], tmp_path)
    assert run.returncode == 0, run.stderr
    assert sorted(os.listdir(tmp_path / "new" / "nested")) == ["regions_merge.png",
                                                               "regions_split.png"]
    assert sorted(os.listdir(tmp_path / "out" / "regions_split")) == [
        "split.png", "split_0.ply", "split_1.ply"]
    # a second run replaces its mesh folders instead of failing on them
    assert _run([EXAMPLES / "regions_figure27.py", "--spacing", "0.1", "--saves", "1",
                 "--size", "32"], tmp_path).returncode == 0
    assert sorted(os.listdir(tmp_path / "out")) == ["regions_merge", "regions_merge.png",
                                                    "regions_split", "regions_split.png"]
    assert {p.name: p.stat().st_mtime_ns for p in DOCS.iterdir()} == docs_before


@pytest.mark.parametrize("script", sorted(p.name for p in EXAMPLES.glob("*.py")
                                          if not p.name.startswith("_")))
def test_no_example_writes_the_docs_by_default(script):
    """Every example's --help: out/ by default; docs/images only behind --docs or --figure."""
    run = _run([EXAMPLES / script, "--help"], EXAMPLES.parent)
    assert run.returncode == 0, run.stderr
    text = " ".join(run.stdout.split())
    assert "default: out" in text
    if "docs" in text:
        assert "--docs" in text or "--figure" in text
