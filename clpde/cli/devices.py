"""`clpde devices`: list the OpenCL devices and mark the one in use."""

from __future__ import annotations

import json
import os
from dataclasses import asdict, replace

from ..errors import ClpdeError
from ..runtime import devices, get_runtime
from ._common import add_device_argument


def add_devices_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "devices",
        help="list OpenCL platforms and devices",
        description="List every OpenCL device; '*' marks the one clpde uses.",
    )
    parser.add_argument("--json", action="store_true", help="print a JSON list instead")
    add_device_argument(parser)
    parser.set_defaults(run=run_devices)


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
    if args.json:
        print(json.dumps([asdict(d) for d in found], indent=2))
    else:
        for info in found:
            print(info.describe())
        if problem is None:
            print("(* = the device in use; choose with --device, CLPDE_DEVICE or clpde.use_device)")
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
