"""Kernels that fit the device, device choice, and the compiler kept quiet (on PoCL; the
simulated small devices are test_oclgrind.py's)."""

from __future__ import annotations

import warnings

import numpy as np
import pyopencl as cl
import pytest

import clpde
from clpde import runtime as rt_mod
from clpde.errors import ClpdeError, DeviceLimitError, KernelBuildError
from clpde.inpainting import spectral


def _refuse_local_memory(monkeypatch):
    """Make every kernel that declares local memory too large for the device, as on a GPU
    with 32 KB (the real limit is PoCL's 1.25 MB)."""
    real = rt_mod.Runtime.group_problem

    def group_problem(self, kernel, group):
        k = kernel.cl_kernel if isinstance(kernel, rt_mod.Kernel) else kernel
        used = k.get_work_group_info(cl.kernel_work_group_info.LOCAL_MEM_SIZE, self.device)
        if used > 32768:
            return f"kernel {k.function_name} needs {used // 1024} KB of local memory, but 32 KB"
        return real(self, kernel, group)

    monkeypatch.setattr(rt_mod.Runtime, "group_problem", group_problem)


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_spectral_spills_its_windows_where_local_memory_is_small(monkeypatch, dtype):
    rng = np.random.default_rng(3)
    image = rng.random((20, 22, 3)).astype(dtype)
    mask = np.zeros((20, 22), bool)
    mask[6:10, 4:15] = True
    want = clpde.inpaint(image, mask, channel_axis=-1, method="spectral", iterations=20)
    runtime = rt_mod.get_runtime()
    assert spectral.fitting_kernel(runtime, np.dtype(dtype))[1] is False  # PoCL: local
    _refuse_local_memory(monkeypatch)
    assert spectral.fitting_kernel(runtime, np.dtype(dtype))[1] is True
    got = clpde.inpaint(image, mask, channel_axis=-1, method="spectral", iterations=20)
    np.testing.assert_allclose(got, want, atol=1e-5 if dtype == np.float32 else 1e-12)


def test_spectral_spill_runs_a_wide_wave_in_several_launches(monkeypatch):
    image = np.random.default_rng(4).random((40, 120)).astype(np.float32)
    mask = np.zeros(image.shape, bool)
    mask[10:30:4, 8:112] = True
    want = clpde.inpaint(image, mask, method="spectral", iterations=10)
    _refuse_local_memory(monkeypatch)
    # scratch for 3 work-groups: every wave of more blocks is cut into launches
    monkeypatch.setattr(spectral, "SCRATCH_BYTES", 3 * spectral.SCRATCH * 4)
    got = clpde.inpaint(image, mask, method="spectral", iterations=10)
    np.testing.assert_allclose(got, want, atol=1e-5)


def test_a_kernel_that_fits_nowhere_is_refused_before_any_work(monkeypatch):
    monkeypatch.setattr(
        rt_mod.Runtime, "group_problem", lambda self, k, g: "kernel x needs 40 KB of local memory"
    )
    image = np.zeros((16, 16), np.float32)
    mask = np.zeros(image.shape, bool)
    mask[5:8, 5:8] = True
    with pytest.raises(DeviceLimitError, match=r"local memory.*method='transport'"):
        clpde.inpaint(image, mask, method="spectral")


def test_a_launch_the_device_refuses_is_clpdes_error_not_pyopencls():
    runtime = rt_mod.get_runtime()
    kernel = runtime.kernel("planar/planar.cl", "planar_heat_step")
    u = cl.Buffer(runtime.ctx, cl.mem_flags.READ_WRITE, 4 * 64)
    too_many = 2 * runtime.device.max_work_group_size
    args = (np.float32(0.1), *(np.int32(a) for a in (4, 4, 6, 36, 1, 1)))
    with pytest.raises(DeviceLimitError, match=r"work-groups of \d+ items.*allows at most"):
        kernel(runtime.queue, (too_many,), (too_many,), u, u, *args)


def test_pyopencl_ctx_chooses_the_device(monkeypatch):
    monkeypatch.delenv("CLPDE_DEVICE", raising=False)
    monkeypatch.setenv("PYOPENCL_CTX", "0:0")
    assert rt_mod.get_runtime().index == 0
    monkeypatch.setenv("PYOPENCL_CTX", "nosuchplatform")
    with pytest.raises(ClpdeError, match=r"PYOPENCL_CTX='nosuchplatform'.*no platform matches"):
        rt_mod.get_runtime()
    # CLPDE_DEVICE, clpde's own setting, comes first
    monkeypatch.setenv("CLPDE_DEVICE", "cpu")
    assert rt_mod.get_runtime().type == "cpu"


def test_a_build_that_works_says_nothing(tmp_path, capfd):
    source = tmp_path / "warns.cl"
    # an unused variable: PoCL's compiler prints "1 warning generated." to the process's
    # stderr, and pyopencl warns of "Non-empty compiler output"
    source.write_text("__kernel void f(__global float* a) { int unused; a[0] = 1.0f; }\n")
    runtime = rt_mod.get_runtime()
    capfd.readouterr()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        # a define of its own: built afresh, not taken from PoCL's cache of an earlier run
        runtime.program(str(source), TAG=int(np.random.default_rng().integers(1 << 30)))
    assert [str(w.message) for w in caught] == []
    assert capfd.readouterr().err == ""


def test_a_build_that_fails_says_why_in_the_error_only(tmp_path, capfd):
    source = tmp_path / "broken.cl"
    source.write_text("__kernel void f(__global float* a) { a[0] = nosuch; }\n")
    runtime = rt_mod.get_runtime()
    capfd.readouterr()
    with pytest.raises(KernelBuildError, match="nosuch"):
        runtime.program(str(source), TAG=int(np.random.default_rng().integers(1 << 30)))
    assert capfd.readouterr().err == ""
