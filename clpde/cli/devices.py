"""`clpde devices`: list the OpenCL devices, their limits and the paths clpde takes on each,
and mark the one in use."""

from __future__ import annotations

import json
import os
from dataclasses import asdict, replace

import numpy as np
import pyopencl as cl

from ..errors import ClpdeError
from ..inpainting import spectral
from ..runtime import build_problem, devices, get_runtime
from ._common import add_device_argument


def add_devices_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "devices",
        help="list OpenCL platforms and devices",
        description=(
            "List every OpenCL device with its limits and the launch paths clpde takes on "
            "it; '*' marks the one clpde uses."
        ),
    )
    parser.add_argument("--json", action="store_true", help="print a JSON list instead")
    add_device_argument(parser)
    parser.set_defaults(run=run_devices)


def device_paths(index: int) -> list[str]:
    """How clpde launches its kernels on device `index`, one line per choice that depends on
    the device: where it runs at all, the launch geometry, and the spectral fill's windows
    (in local memory, or in global memory where the device has too little local memory)."""
    problem = build_problem(index)
    if problem is not None:
        return [f"none: {problem}"]
    rt = get_runtime(index)
    lines = [
        "grids: one row per work-item"
        if rt.is_cpu
        else "grids: work-groups of 64 x 4 cells; band bricks: one work-group per brick, "
        "its tile in local memory",
    ]
    for dtype in (np.float32, np.float64):
        if dtype == np.float64 and not rt.fp64:
            lines.append("float64: not supported (no cl_khr_fp64)")
            continue
        name = np.dtype(dtype).name
        try:
            kernel, spill, _ = spectral.fitting_kernel(rt, np.dtype(dtype))
        except ClpdeError as exc:
            lines.append(f"spectral ({name}): cannot run: {exc}")
            continue
        need = kernel.get_work_group_info(cl.kernel_work_group_info.LOCAL_MEM_SIZE, rt.device)
        have = rt.device.local_mem_size // 1024
        where = (
            f"windows in global memory, {need // 1024} KB local ({have} KB local memory)"
            if spill
            else f"windows in local memory, {need // 1024} KB ({have} KB local memory)"
        )
        lines.append(f"spectral ({name}): {where}")
    return lines


def run_devices(args) -> int:
    found = devices()
    problem = None
    if args.device is not None:
        chosen = get_runtime(args.device).index
        found = [replace(d, in_use=(d.index == chosen)) for d in found]
    else:
        try:  # a CLPDE_DEVICE that matches nothing would fail every other command
            get_runtime()
        except ClpdeError as exc:
            problem = exc
    paths = {d.index: device_paths(d.index) for d in found}
    if args.json:
        print(json.dumps([asdict(d) | {"paths": paths[d.index]} for d in found], indent=2))
    else:
        for info in found:
            print(info.describe())
            for line in paths[info.index]:
                print(f"      {line}")
        if problem is None:
            print(
                "(* = the device in use; choose with --device, CLPDE_DEVICE, PYOPENCL_CTX "
                "or clpde.use_device)"
            )
    if problem is not None:  # after the list, so that the fix can point at it
        env = os.environ.get("CLPDE_DEVICE")
        if env and "cannot compile" not in str(problem):
            raise ClpdeError(
                f"CLPDE_DEVICE={env!r} matches none of the devices listed above, "
                "so every command would fail; set it to one of them (its index, "
                "'cpu', or part of its name) or unset it"
            )
        raise problem
    return 0
