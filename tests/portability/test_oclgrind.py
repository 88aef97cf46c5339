"""clpde's kernels on a simulated OpenCL device: Oclgrind checks every memory access, and
with --data-races every local and global access of a work-group, which PoCL (one work-item
after another) cannot show. The device is a GPU to clpde (its launches take the GPU paths:
a brick per work-group, 64 x 4 groups), with the OpenCL 1.2 minimum limits (32 KB local
and 64 KB constant memory) and NVIDIA's 48 KB of local memory per kernel.

Every case of cases.py runs whole under Oclgrind, in one child process per limit set, and
must report no error and give PoCL's results within float tolerance. At 48 KB only the cases
whose kernels hold local memory run again (the limit changes nothing else). The region
trackers take minutes under the simulator: benchmarks/portability.py runs them, with every
case at both limits.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import cases  # noqa: E402

OCLGRIND = shutil.which("oclgrind")
pytestmark = pytest.mark.skipif(
    OCLGRIND is None,
    reason="oclgrind is not installed (apt-get install oclgrind; .ci/run installs it)",
)

SWEEP_ONLY = ("track_region_lists", "track_region_bricks")  # minutes each under Oclgrind
LOCAL_MEMORY_CASES = (
    "inpaint_spectral",
    "inpaint_spectral_f64",
    "track_bricks",
    "track_region_term",
    "surface_bricks",
)
LIMITS = {
    "opencl-minimum": (32768, [n for n in cases.CASES if n not in SWEEP_ONLY]),
    "nvidia-48k": (49152, list(LOCAL_MEMORY_CASES)),
}
TOLERANCE = 1e-4  # float32 rounding of a few hundred operations, in data scaled to [0, 1]


def oclgrind_command(local_mem: int, quick: bool = False) -> list[str]:
    """Oclgrind with its checks on, at `local_mem` bytes of local memory and the minimum
    64 KB of constant memory. Its --uninitialized plugin is left off: in Oclgrind 21.10 it
    stops on sincos ("work item needed to access private memory"), which the spectral
    kernel calls, and it takes buffers zeroed by clEnqueueFillBuffer (pyopencl's
    array.zeros) for uninitialised. --check-api is off too: it reports pyopencl's own
    probing (device queries, kernel names it tries). Every other check is on."""
    command = [OCLGRIND, "--data-races", "--max-errors", "20"]
    command += ["--local-mem-size", str(local_mem), "--constant-mem-size", "65536"]
    return command + (["--quick"] if quick else [])


def oclgrind_env() -> dict:
    """The environment of a run under Oclgrind: this tree first, and no device setting (a
    suite run with CLPDE_DEVICE naming another runtime would not find it there)."""
    env = dict(os.environ, PYTHONPATH=str(HERE.parents[1]))
    env.pop("CLPDE_DEVICE", None)
    env.pop("PYOPENCL_CTX", None)
    return env


def start_under_oclgrind(out: Path, local_mem: int, names: list[str]) -> subprocess.Popen:
    """Start the named cases under Oclgrind, writing into `out` (oclgrind.log, output.txt,
    the cases' results)."""
    env = oclgrind_env()
    command = oclgrind_command(local_mem) + ["--log", str(out / "oclgrind.log")]
    command += [sys.executable, str(HERE / "cases.py"), str(out), *names]
    with open(out / "output.txt", "w") as output:  # the child keeps its own handle
        return subprocess.Popen(command, env=env, stdout=output, stderr=subprocess.STDOUT)


def finish(process: subprocess.Popen, out: Path, timeout: float = 900):
    """(exit status, Oclgrind's log, the cases' output) once `process` ends."""
    try:
        status = process.wait(timeout)
    except subprocess.TimeoutExpired:
        process.kill()
        status = process.wait()
    log = out / "oclgrind.log"
    return status, log.read_text() if log.exists() else "", (out / "output.txt").read_text()


def run_under_oclgrind(out: Path, local_mem: int, names: list[str], timeout: float = 900):
    """Run the named cases under Oclgrind; (exit status, its log, their output)."""
    return finish(start_under_oclgrind(out, local_mem, names), out, timeout)


@pytest.fixture(scope="module")
def oclgrind_runs(tmp_path_factory):
    """Both limit sets' runs, started at once (each is one process: two cores, half the
    wall time)."""
    runs = {}
    for limits, (local_mem, names) in LIMITS.items():
        out = tmp_path_factory.mktemp(limits)
        runs[limits] = (start_under_oclgrind(out, local_mem, names), out)
    yield runs
    for process, _ in runs.values():
        if process.poll() is None:
            process.kill()
            process.wait()


@pytest.fixture(scope="module")
def pocl_results():
    results = {}

    def get(name):
        if name not in results:
            results[name] = {k: np.asarray(v) for k, v in cases.CASES[name]().items()}
        return results[name]

    return get


@pytest.mark.parametrize("limits", list(LIMITS))
def test_kernels_run_clean_under_oclgrind(limits, oclgrind_runs, pocl_results):
    names = LIMITS[limits][1]
    for name in names:  # PoCL's results, while Oclgrind runs
        pocl_results(name)
    process, tmp_path = oclgrind_runs[limits]
    status, log, output = finish(process, tmp_path)
    assert status == 0, f"cases failed under Oclgrind:\n{output[-3000:]}"
    assert log.strip() == "", f"Oclgrind reported:\n{log[:3000]}"
    launched = json.loads((tmp_path / "kernels.json").read_text())
    if limits == "opencl-minimum":  # the kernel Oclgrind could not find before
        assert "tracking/adaptive.cl:adaptive_morph_adaptive" in launched
    for name in names:
        got = np.load(tmp_path / f"{name}.npz")
        want = pocl_results(name)
        assert sorted(got.files) == sorted(want), name
        for key, value in want.items():
            if value.dtype == bool:
                # a mask: the level sets behind it agree to rounding, so a pixel exactly
                # on the contour may flip
                assert np.mean(got[key] != value) <= 0.01, f"{name}/{key}"
            else:
                np.testing.assert_allclose(
                    got[key], value, atol=TOLERANCE, err_msg=f"{name}/{key} differs from PoCL"
                )


def test_bricks_too_large_for_the_work_group_are_refused_with_the_way_out(tmp_path):
    # AMD's GPUs allow 256 work-items a group by default: a surface brick of 8x8x8 cells,
    # one work-item each, cannot run there, and says so before any work
    script = (
        "import sys; sys.path.insert(0, sys.argv[1]); import cases\n"
        "from clpde.errors import DeviceLimitError\n"
        "try:\n    cases.CASES['surface_bricks']()\n"
        "except DeviceLimitError as e:\n    print('refused:', e)\n"
    )
    env = oclgrind_env()
    command = [OCLGRIND, "--max-wgsize", "256", sys.executable, "-c", script, str(HERE)]
    done = subprocess.run(command, env=env, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    assert "refused: bricks of 8x8x8 cells run in work-groups of 512 items" in done.stdout
    assert "at most 256; use storage='lists'" in done.stdout
