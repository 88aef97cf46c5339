import os
import subprocess
import sys
import textwrap
import warnings

import numpy as np
import pyopencl as cl
import pytest

import clpde
from clpde import runtime as rt_mod
from clpde.errors import ClpdeError, KernelBuildError, NoDeviceError
from clpde.fields import Field, Grid


def test_devices_lists_every_device_and_marks_the_one_in_use():
    found = clpde.devices()
    assert found, "PoCL should provide at least one device"
    assert sum(d.in_use for d in found) == 1
    for d in found:
        assert d.compute_units >= 1 and d.global_mem_bytes > 0 and d.max_alloc_bytes > 0
        assert d.type in ("cpu", "gpu", "accelerator", "other")
        assert d.name in d.describe()


@pytest.fixture
def fresh_choice(monkeypatch):
    monkeypatch.setattr(rt_mod, "_chosen_spec", None)
    monkeypatch.delenv("CLPDE_DEVICE", raising=False)


@pytest.mark.parametrize("spec", ["cpu", 0, "0", "pthread", "portable"])
def test_device_specs_resolve(fresh_choice, spec):
    runtime = rt_mod.get_runtime(spec)
    assert runtime.type == "cpu"


def test_explicit_argument_beats_use_device_beats_environment(fresh_choice, monkeypatch):
    monkeypatch.setenv("CLPDE_DEVICE", "no-such-device")
    with pytest.raises(ClpdeError, match="CLPDE_DEVICE='no-such-device'"):
        rt_mod.get_runtime()
    clpde.use_device("cpu")
    assert rt_mod.get_runtime().type == "cpu"  # use_device wins over the variable
    monkeypatch.setattr(rt_mod, "_chosen_spec", "no-such-device")
    assert rt_mod.get_runtime("cpu").type == "cpu"  # an explicit argument wins over both


def test_environment_variable_picks_the_device(fresh_choice, monkeypatch):
    monkeypatch.setenv("CLPDE_DEVICE", "cpu")
    assert rt_mod.get_runtime().type == "cpu"


@pytest.mark.parametrize("spec", ["no-such-device", 99, ""])
def test_unknown_device_is_a_clear_error(fresh_choice, spec):
    with pytest.raises(ClpdeError, match="device"):
        rt_mod.get_runtime(spec)


def test_unknown_device_through_the_api(fresh_choice):
    with pytest.raises(ClpdeError, match="clpde devices"):
        clpde.diffuse(np.zeros((8, 8)), device="no-such-device")


def test_no_platform_names_the_fix(monkeypatch):
    def no_platforms():
        raise cl.LogicError("clGetPlatformIDs failed: PLATFORM_NOT_FOUND_KHR")

    monkeypatch.setattr(cl, "get_platforms", no_platforms)
    monkeypatch.setattr(rt_mod, "_found", [])  # as in a process that has not listed them yet
    with pytest.raises(NoDeviceError, match=r'pip install "clpde\[pocl\]"'):
        rt_mod.get_runtime("cpu")


def test_kernels_are_built_once_and_reused(runtime):
    k1 = runtime.kernel("planar/planar.cl", "planar_heat_step")
    k2 = runtime.kernel("planar/planar.cl", "planar_heat_step")
    assert k1 is k2
    assert runtime.program("planar/planar.cl") is runtime.program("planar/planar.cl")
    plain = runtime.program("planar/planar.cl")
    assert runtime.program("planar/planar.cl", EDGE_STOP=1) is not plain


def test_build_failure_names_file_and_line(runtime, tmp_path, monkeypatch):
    (tmp_path / "common").mkdir()
    (tmp_path / "common" / "common.h").write_text(
        (rt_mod.KERNEL_DIR / "common" / "common.h").read_text()
    )
    (tmp_path / "broken.cl").write_text(
        '#include "common.h"\n\n'
        "__kernel void k(__global REAL* u)\n{\n    u[0] = undefined_name;\n}\n"
    )
    monkeypatch.setattr(rt_mod, "KERNEL_DIR", tmp_path)
    with pytest.raises(KernelBuildError) as info:
        runtime.program("broken.cl")
    message = str(info.value)
    assert "broken.cl" in message and ":5:" in message and "undefined_name" in message


def test_a_compiler_that_builds_nothing_is_one_line_at_the_first_build(
    runtime, tmp_path, monkeypatch
):
    """A failing build asks the probe (skipped when there was no other device to choose):
    a compiler that builds nothing at all is NoDeviceError's one line, not a compiler log."""
    (tmp_path / "broken.cl").write_text("__kernel void k(__global float* u) { u[0] = nope; }\n")
    monkeypatch.setattr(rt_mod, "KERNEL_DIR", tmp_path)
    problem = "Some CPU (PoCL) cannot compile kernels: unknown target CPU 'generic'"
    monkeypatch.setattr(rt_mod, "build_problem", lambda index: problem)
    with pytest.raises(NoDeviceError, match="cannot compile kernels"):
        runtime.program("broken.cl")


def test_one_device_is_chosen_without_probing_its_compiler(monkeypatch):
    """The probe builds a program (0.6 s of a cold start with PoCL) only to skip a device
    whose compiler fails when another one may work: with one device there is none."""
    found = rt_mod._all_devices()[:1]
    monkeypatch.setattr(rt_mod, "_all_devices", lambda: found)
    monkeypatch.delenv("CLPDE_DEVICE", raising=False)
    monkeypatch.delenv("PYOPENCL_CTX", raising=False)

    def probe(index):
        raise AssertionError("the only device was probed")

    monkeypatch.setattr(rt_mod, "build_problem", probe)
    assert rt_mod._default_index() == 0


def test_missing_kernel_file(runtime):
    with pytest.raises(KernelBuildError, match="does not exist"):
        runtime.program("no_such_file.cl")


def test_a_kernel_the_program_lacks_is_one_clear_line(runtime):
    # the program builds; the name is not in it (as when a killed build left PoCL's cache
    # entry without its kernels): clpde's own error, naming the file and the kernel
    with pytest.raises(KernelBuildError, match="no kernel 'no_such_kernel'") as info:
        runtime.kernel("planar/planar.cl", "no_such_kernel")
    assert "planar/planar.cl" in str(info.value) and "\n" not in str(info.value)


def test_oversized_field_is_refused_before_allocation(runtime):
    side = int(np.sqrt(runtime.device.max_mem_alloc_size / 4)) + 16
    grid = Grid(runtime, side, side)
    with pytest.raises(ClpdeError, match="largest allocation|at most"):
        Field.empty(grid)


def test_unwritable_pocl_cache_dir_falls_back_to_a_writable_one(tmp_path):
    blocker = tmp_path / "a-file"
    blocker.write_text("not a directory")
    code = textwrap.dedent(
        """
        import os, warnings
        warnings.simplefilter("always")
        with warnings.catch_warnings(record=True) as caught:
            import clpde
            count = len(clpde.devices())  # clpde.runtime loads (lazily) here
        print(count, os.environ["POCL_CACHE_DIR"], len(caught))
        """
    )
    env = {k: v for k, v in __import__("os").environ.items() if k != "CLPDE_DEVICE"}
    env["POCL_CACHE_DIR"] = str(blocker / "cache")
    out = subprocess.run(
        [sys.executable, "-c", code],
        env=env,
        capture_output=True,
        text=True,
        check=True,
        cwd=tmp_path,
    )
    count, path, warned = out.stdout.split()
    assert int(count) >= 1 and path != str(blocker / "cache") and int(warned) >= 1


def test_float64_needs_fp64(runtime):
    if runtime.fp64:
        out = clpde.diffuse(np.random.default_rng(0).random((16, 16)), steps=3, dtype=np.float64)
        assert out.dtype == np.float64
    else:
        with pytest.raises(ClpdeError, match="fp64"):
            clpde.diffuse(np.zeros((16, 16)), steps=3, dtype=np.float64)


def test_warnings_are_not_raised_by_normal_use():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        clpde.diffuse(np.zeros((8, 8), np.uint8), steps=2)


def test_kernels_launch_under_the_runtime_lock_and_pickle_by_name():
    import pickle

    runtime = rt_mod.get_runtime("cpu")
    k = runtime.kernel("common/fields.cl", "fields_fill_ghost_rows")
    assert isinstance(k, rt_mod.Kernel) and k._lock is runtime.lock
    assert k.function_name == "fields_fill_ghost_rows"  # attributes reach pyopencl's kernel
    assert pickle.loads(pickle.dumps(k)) is k  # same process: the cached kernel
    assert pickle.loads(pickle.dumps(runtime)) is runtime


def test_device_arrays_pickle_as_their_values_keeping_shared_buffers_shared():
    import pickle

    import pyopencl.array as cla

    runtime = rt_mod.get_runtime("cpu")
    a = cla.to_device(runtime.queue, np.arange(12, dtype=np.float32).reshape(3, 4))
    b, c = pickle.loads(pickle.dumps((a, a.data)))
    assert np.array_equal(b.get(), a.get()) and b.data is c and b.data is not a.data


# ---- device memory ----------------------------------------------------------------------------
def _sphere_phi(n=28, r=4.0):
    ax = np.arange(n) - (n - 1) / 2
    z, y, x = np.meshgrid(ax, ax, ax, indexing="ij")
    return np.sqrt(x**2 + y**2 + z**2) - r, z


def _calls():
    """One small call of every public function that allocates on the device."""
    from clpde.surface import ImplicitSurface

    rng = np.random.default_rng(1)
    image = rng.random((24, 32)).astype(np.float32)
    mask = np.zeros(image.shape, bool)
    mask[8:14, 10:20] = True
    yy, xx = np.mgrid[:24, :24]
    frames = np.stack([((yy - 12) ** 2 + (xx - 9 - 2 * k) ** 2 < 25) for k in range(2)]).astype(
        np.uint8
    )
    phi, z = _sphere_phi()
    return {
        "diffuse": lambda: clpde.diffuse(image, "tv", steps=3),
        "denoise_tv": lambda: clpde.denoise_tv(image, 0.1, max_steps=6),
        "inpaint": lambda: clpde.inpaint(image, mask, max_steps=6),
        "track": lambda: clpde.track(frames, frames[0] > 0, max_iterations=3),
        "surface": lambda: ImplicitSurface(phi, 1.0).heat(z, 0.5),
        "track_region": lambda: clpde.track_region(phi, z, beta=0.5, t=0.2),
    }


@pytest.mark.parametrize("name", list(_calls()))
def test_requests_that_cannot_fit_are_refused_before_any_allocation(name, monkeypatch):
    call = _calls()[name]
    runtime = rt_mod.get_runtime()
    allocated = []
    real = cl.Buffer
    monkeypatch.setattr(cl, "Buffer", lambda *a, **k: allocated.append(a) or real(*a, **k))
    for limit in ("max_alloc", "global_mem"):
        with monkeypatch.context() as m:
            m.setattr(runtime, limit, 1024)
            with pytest.raises(rt_mod.DeviceMemoryError) as err:
                call()
        message = str(err.value)
        assert "MiB" in message and "tiles" in message and "smaller input" in message
        assert ("per allocation" if limit == "max_alloc" else "of device memory") in message
    assert allocated == []
    assert isinstance(err.value, MemoryError) and isinstance(err.value, ClpdeError)


def test_a_huge_image_is_refused_without_converting_it():
    # 10^10 pixels that take no memory: the refusal must come before any float copy
    huge = np.broadcast_to(np.uint8(7), (100_000, 100_000))
    with pytest.raises(
        rt_mod.DeviceMemoryError, match=r"the heat flow of 100000x100000 values needs"
    ):
        clpde.diffuse(huge, steps=1)


def _live_buffers() -> int:
    import gc

    gc.collect()
    return sum(isinstance(o, cl.MemoryObject) for o in gc.get_objects())


@pytest.mark.parametrize("name", list(_calls()))
def test_a_failed_allocation_leaks_no_buffers(name, monkeypatch):
    call = _calls()[name]
    call()  # kernels built, caches filled
    real = cl.Buffer
    count = [0, None]

    def buffer(*args, **kwargs):
        count[0] += 1
        if count[0] == count[1]:
            raise cl.MemoryError("simulated allocation failure")
        return real(*args, **kwargs)

    monkeypatch.setattr(cl, "Buffer", buffer)
    call()
    allocations = count[0]
    before = _live_buffers()
    for fail_at in sorted({1, allocations // 2, allocations}):
        count[:] = [0, fail_at]
        with pytest.raises(cl.MemoryError):
            call()
        assert _live_buffers() == before, f"buffers left after allocation {fail_at} failed"


def test_profile_prints_each_kernels_time_at_exit():
    """CLPDE_PROFILE=1: at exit, one line per kernel with its device time and launches."""
    code = (
        "import numpy as np, clpde\n"
        "clpde.diffuse(np.ones((16, 16), np.float32), 'heat', steps=7, device='cpu')\n"
        "hole = np.zeros((16, 16), bool); hole[6:9, 6:9] = True\n"
        "clpde.inpaint(np.ones((16, 16), np.float32), hole, method='transport', device='cpu')\n"
    )
    env = {**os.environ, "CLPDE_PROFILE": "1"}
    out = subprocess.run(
        [sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True
    )
    lines = out.stderr.splitlines()
    assert any(line.startswith("clpde profile: ") for line in lines), out.stderr
    heat = [line.split() for line in lines if line.endswith("planar/planar.cl:planar_heat_step")]
    assert len(heat) == 1 and heat[0][2] == "7" and float(heat[0][0]) >= 0, out.stderr
    # transport's kernels set their arguments once and are enqueued bare: counted too
    assert any(line.endswith("inpainting/transport.cl:transport_step") for line in lines)
    quiet = subprocess.run(
        [sys.executable, "-c", code],
        env={k: v for k, v in os.environ.items() if k != "CLPDE_PROFILE"},
        capture_output=True,
        text=True,
        check=True,
    )
    assert "clpde profile" not in quiet.stderr


def test_devices_are_listed_once(monkeypatch):
    """get_runtime() and devices() ask OpenCL for the platforms once per process."""
    rt_mod._all_devices()
    calls = []
    monkeypatch.setattr(rt_mod.cl, "get_platforms", lambda: calls.append(1) or [])
    rt_mod.get_runtime("cpu")
    rt_mod.devices()
    assert calls == []
