"""A plain (non-editable) install carries the OpenCL kernels and works from outside the repo.

The wheel is built from a copy of the sources (so the checkout gets no build/ folder) with
the installed setuptools and no build isolation, hence no network.
"""

import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]


def _pip(*args, cwd):
    run = subprocess.run(
        [
            sys.executable,
            "-m",
            "pip",
            *args,
            "--no-deps",
            "--no-input",
            "--no-index",
            "--disable-pip-version-check",
            "-q",
        ],
        cwd=cwd,
        capture_output=True,
        text=True,
        stdin=subprocess.DEVNULL,
        timeout=180,
        check=False,
    )
    assert run.returncode == 0, f"pip {' '.join(args)} failed:\n{run.stdout}\n{run.stderr}"


def _source_files() -> list[str]:
    """The files of clpde/ and kernels/ that git tracks (untracked work in progress is not
    part of the project yet); every file there when the sources are not a git checkout."""
    run = subprocess.run(
        ["git", "ls-files", "-z", "--", "clpde", "kernels"],
        cwd=REPO,
        capture_output=True,
        text=True,
        check=False,
    )
    if run.returncode == 0 and run.stdout:
        return [name for name in run.stdout.split("\0") if name]
    return [
        p.relative_to(REPO).as_posix()
        for folder in ("clpde", "kernels")
        for p in (REPO / folder).rglob("*")
        if p.is_file() and "__pycache__" not in p.parts
    ]


def _copy_sources(dest: Path) -> None:
    for name in ("pyproject.toml", "README.md", *_source_files()):
        target = dest / name
        target.parent.mkdir(parents=True, exist_ok=True)
        # clpde/kernels is a link to kernels/ (how a checkout imports clpde.kernels): as a link
        shutil.copy2(REPO / name, target, follow_symlinks=False)


def test_wheel_ships_kernels_and_runs_outside_the_checkout(tmp_path):
    src, wheels, site, elsewhere = (tmp_path / n for n in ("src", "wheels", "site", "elsewhere"))
    for folder in (src, wheels, elsewhere):
        folder.mkdir()
    _copy_sources(src)
    _pip("wheel", "--no-build-isolation", "--wheel-dir", str(wheels), str(src), cwd=tmp_path)
    (wheel,) = wheels.glob("clpde-*.whl")

    names = set(zipfile.ZipFile(wheel).namelist())
    kernels = sorted(
        p.relative_to(src / "kernels").as_posix()
        for p in (src / "kernels").rglob("*")
        if p.is_file()
    )
    assert any(k.endswith(".cl") for k in kernels), "no kernels/*.cl in the checkout"
    missing = [k for k in kernels if f"clpde/kernels/{k}" not in names]
    assert not missing, (
        f"kernel files missing from the wheel: {missing}; add their pattern to "
        "[tool.setuptools.package-data] of pyproject.toml"
    )
    modules = sorted(
        p.relative_to(src).as_posix() for p in (src / "clpde").rglob("*") if p.is_file()
    )
    missing = [m for m in modules if m not in names]
    assert not missing, (
        f"files missing from the wheel: {missing}; list every package under clpde/ in "
        "[tool.setuptools] packages of pyproject.toml (and data files in package-data)"
    )
    assert any(n.endswith("entry_points.txt") for n in names)

    _pip("install", "--target", str(site), str(wheel), cwd=tmp_path)
    script = (
        "import sys, numpy as np, clpde, clpde.runtime as r\n"
        "from pathlib import Path\n"
        "site = Path(sys.argv[1]).resolve()\n"
        "assert Path(clpde.__file__).resolve().is_relative_to(site), clpde.__file__\n"
        "assert r.KERNEL_DIR.resolve().is_relative_to(site), r.KERNEL_DIR\n"
        "assert r.KERNEL_DIR == site / 'clpde' / 'kernels', r.KERNEL_DIR\n"
        "image = np.zeros((8, 8), np.float32); image[4, 4] = 1\n"
        "out = clpde.diffuse(image, 'heat', steps=3, device='cpu')\n"
        "assert out.dtype == np.float32 and abs(out.sum() - 1) < 1e-5 and out[4, 4] < 1\n"
        "print('ok', r.KERNEL_DIR)\n"
    )
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "CLPDE_DEVICE")}
    env["PYTHONPATH"] = str(site)
    run = subprocess.run(
        [sys.executable, "-c", script, str(site)],
        cwd=elsewhere,
        env=env,
        capture_output=True,
        text=True,
        stdin=subprocess.DEVNULL,
        timeout=180,
        check=False,
    )
    assert run.returncode == 0, run.stdout + run.stderr
    assert run.stdout.startswith("ok")


def test_ci_runs_the_readme_test_command_verbatim():
    readme = (REPO / "README.md").read_text()
    quickstart = readme.split("## Quickstart", 1)[1].split("```bash\n", 1)[1].split("```", 1)[0]
    commands = [line for line in quickstart.splitlines() if line.strip()]
    assert len(commands) == 2, commands
    assert "pytest" in commands[1] and "[pocl,test]" in commands[1]
    ci = (REPO / ".ci" / "run").read_text().splitlines()
    assert commands[1] in ci, f".ci/run must run the README's test command {commands[1]!r}"
    assert "set -euo pipefail" in ci
    assert os.access(REPO / ".ci" / "run", os.X_OK)


def test_the_readme_test_command_says_why_tests_skip():
    readme = (REPO / "README.md").read_text()
    quickstart = readme.split("## Quickstart", 1)[1].split("```bash\n", 1)[1].split("```", 1)[0]
    command = [line for line in quickstart.splitlines() if line.strip()][1]
    assert command.endswith("python -m pytest -q -rs"), command  # -rs: the skip reasons


def test_the_readme_says_where_the_kernel_cache_is_and_how_to_move_it(tmp_path):
    """The README's paragraph on the kernel cache names the folder clpde really uses, and
    the variable that moves it really moves it (in a fresh process: it is read at import)."""
    readme = (REPO / "README.md").read_text()
    assert "~/.cache/clpde/pocl" in readme and "POCL_CACHE_DIR=" in readme
    assert "rm -rf ~/.cache/clpde ~/.cache/pyopencl" in readme
    probe = "import os, clpde.runtime; print(os.environ['POCL_CACHE_DIR'])"
    env = {k: v for k, v in os.environ.items() if k != "POCL_CACHE_DIR"}
    for extra, expected in (
        ({"HOME": str(tmp_path)}, tmp_path / ".cache" / "clpde" / "pocl"),
        ({"POCL_CACHE_DIR": str(tmp_path / "moved")}, tmp_path / "moved"),
    ):
        run = subprocess.run(
            [sys.executable, "-c", probe],
            env={**env, **extra, "PYTHONPATH": str(REPO)},
            capture_output=True,
            text=True,
            timeout=120,
            check=True,
        )
        assert Path(run.stdout.strip()) == expected
        assert expected.is_dir()
