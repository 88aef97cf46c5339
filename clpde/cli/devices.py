"""`clpde devices`: list the OpenCL devices and mark the one in use."""

from __future__ import annotations

import json
from dataclasses import asdict, replace

from ..runtime import devices, get_runtime
from ._common import add_device_argument


def add_devices_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "devices", help="list OpenCL platforms and devices",
        description="List every OpenCL device; '*' marks the one clpde uses.",
    )
    parser.add_argument("--json", action="store_true", help="print a JSON list instead")
    add_device_argument(parser)
    parser.set_defaults(run=run_devices)


def run_devices(args) -> int:
    found = devices()
    if args.device is not None:
        chosen = get_runtime(args.device).index
        found = [replace(d, in_use=(d.index == chosen)) for d in found]
    if args.json:
        print(json.dumps([asdict(d) for d in found], indent=2))
        return 0
    for info in found:
        print(info.describe())
    print("(* = the device in use; choose with --device, CLPDE_DEVICE or clpde.use_device)")
    return 0
