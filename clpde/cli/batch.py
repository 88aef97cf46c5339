"""`clpde batch`: one command over many files on Dask workers (clpde.batch)."""

from __future__ import annotations

import argparse
import contextlib
import io
import os
import sys
import time

from ..errors import InputError
from ..scale.batch import batch, result_table
from ..scale.manifest import MANIFEST
from ..scale.plan import COMMANDS
from . import denoise, diffuse, inpaint, restore, surface, track
from ._parser import Parser

FAILED_STATUS = 1  # some inputs failed (the others were written); 2 stays usage errors


def add_batch_parser(subparsers) -> None:

    parser = subparsers.add_parser(
        "batch",
        help="run inpaint, denoise, diffuse, track, surface or restore over many files",
        description="Run COMMAND on every input over Dask workers, one output per input in "
        "OUTDIR (images under their own name; track and surface results in a "
        "folder named after the input). COMMAND's own options follow the inputs "
        "(see `clpde COMMAND --help`). By default a local cluster is started with "
        "workers x PoCL threads = the cores (one worker per GPU on GPU "
        f"machines). OUTDIR/{MANIFEST} records every output's input hash and "
        "options, so a rerun skips outputs that are complete. A failing input is "
        "reported at the end and the exit status is 1.",
        usage="clpde batch COMMAND INPUT... -o OUTDIR [--workers N | --scheduler ADDRESS] "
        "[--mask MASK | --masks DIR] [COMMAND's options]",
        allow_abbrev=False,  # COMMAND's options (surface's --t) are not abbreviations of ours
    )
    parser.__class__ = _BatchParser
    parser.add_argument(
        "batch_command", metavar="COMMAND", choices=COMMANDS, help=" | ".join(COMMANDS)
    )
    parser.add_argument(
        "inputs",
        metavar="INPUT",
        nargs="+",
        help="input files (images; track: videos, folders or TIFF stacks; "
        "surface: meshes; restore: films)",
    )
    parser.add_argument(
        "-o", "--output", metavar="OUTDIR", required=True, help="output folder (created if missing)"
    )
    cluster = parser.add_mutually_exclusive_group()
    cluster.add_argument(
        "--workers",
        type=int,
        default=None,
        metavar="N",
        help="local worker processes (default: the cores, or one per GPU)",
    )
    cluster.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        default=None,
        help="join a running Dask cluster, e.g. tcp://HOST:8786 "
        "(inputs and OUTDIR at the same paths on every machine)",
    )
    parser.add_argument(
        "--threads",
        type=int,
        default=None,
        metavar="N",
        help="PoCL threads per local worker (default: cores / workers)",
    )
    masks = parser.add_mutually_exclusive_group()
    masks.add_argument(
        "--mask",
        metavar="MASK",
        default=None,
        help="inpaint: one mask for every input; track: the first-frame mask; "
        "restore: masks to fill instead of detecting",
    )
    masks.add_argument(
        "--masks",
        metavar="DIR",
        default=None,
        help="a folder with one mask per input, named like it (restore: or a "
        "folder of per-frame masks named like the film's stem)",
    )
    parser.add_argument(
        "--flow", default=None, help="surface: the flow (heat, tv, ...); diffuse: passed to diffuse"
    )
    parser.add_argument(
        "--tile",
        action="store_true",
        help="diffuse, denoise: run in 256x256 tiles (bitwise equal; automatic "
        "when an image exceeds the device's largest allocation)",
    )
    parser.add_argument(
        "--force", action="store_true", help="redo outputs that the manifest shows complete"
    )
    parser.set_defaults(run=run_batch)


# COMMAND's positional arguments, as placeholders: only its options are read from the parse
_PLACEHOLDERS = {
    "inpaint": ["IN", "MASK", "-o", "OUT"],
    "track": ["IN", "--init", "MASK", "-o", "OUT"],
    "surface": ["heat", "MESH", "-o", "OUT"],
    "denoise": ["IN", "OUT"],
    "diffuse": ["IN", "OUT"],
    "restore": ["IN", "-o", "OUT"],
}


# each command's parser and the keywords of its task from the parsed flags
_COMMANDS = {
    "inpaint": (inpaint.add_inpaint_parser, inpaint.task_options),
    "denoise": (denoise.add_denoise_parser, denoise.task_options),
    "diffuse": (diffuse.add_diffuse_parser, diffuse.task_options),
    "track": (track.add_track_parser, track.task_options),
    "surface": (surface.add_surface_parser, surface.task_options),
    "restore": (restore.add_restore_parser, restore.task_options),
}


def command_options(command: str, argv: list[str]) -> dict:
    """COMMAND's own flags (`clpde COMMAND --help`), checked by its parser before any work,
    as the keywords of its task (clpde.scale.file_tasks.TASKS)."""
    add_parser, task_options = _COMMANDS[command]
    parser = argparse.ArgumentParser(prog="clpde")
    add_parser(parser.add_subparsers(dest="command"))
    err = io.StringIO()
    try:
        with contextlib.redirect_stderr(err):
            parsed = parser.parse_args([command, *_PLACEHOLDERS[command], *argv])
    except SystemExit:
        lines = [ln for ln in err.getvalue().splitlines() if ln.strip()]
        detail = lines[-1].split("error: ", 1)[-1] if lines else "invalid options"
        raise InputError(f"clpde {command}: {detail}") from None
    options = task_options(parsed)
    if command in ("surface", "diffuse"):  # the flow is batch's own --flow
        del options["flow"]
    if command in ("track", "surface"):  # each output folder is new: the batch replaces it
        del options["overwrite"]
    return options


def run_batch(args) -> int:

    options = command_options(args.batch_command, list(getattr(args, "extra", [])))
    try:
        result = batch(
            args.batch_command,
            args.inputs,
            args.output,
            mask=args.mask,
            masks=args.masks,
            workers=args.workers,
            threads=args.threads,
            scheduler=args.scheduler,
            flow=args.flow,
            tile=args.tile,
            force=args.force,
            **options,
        )
    except KeyboardInterrupt:
        print(
            f"clpde batch: interrupted; {args.output} holds complete outputs only (a rerun "
            "continues where this one stopped)",
            file=sys.stderr,
        )
        return 130
    print(result_table(result, _since_start()), file=sys.stderr)
    return FAILED_STATUS if result.failed else 0


def _since_start() -> float | None:
    """Seconds since this process started, Python's start and imports included: the time
    the user waited. On Linux from the kernel's own clock since boot: psutil's start time
    adds the boot time, which /proc gives in whole seconds and which a clock step moves
    (a 1.8 s command once reported 2.6 s)."""
    try:
        with open("/proc/self/stat") as stat:  # field 22: the start, in ticks since boot
            ticks = int(stat.read().rsplit(")", 1)[1].split()[19])
        return time.clock_gettime(time.CLOCK_BOOTTIME) - ticks / os.sysconf("SC_CLK_TCK")
    except (OSError, ValueError, IndexError, AttributeError):
        pass
    try:  # elsewhere psutil, which comes with Dask's distributed (batches need it)
        import psutil

        return time.time() - psutil.Process().create_time()
    except Exception:  # noqa: BLE001  (no psutil, or no process table: the call's own time)
        return None


class _BatchParser(Parser):
    """Keeps the options that `clpde batch` does not know as args.extra, for COMMAND's own
    parser (which checks them before any work), instead of refusing them."""

    def parse_known_args(self, args=None, namespace=None):
        namespace, extra = super().parse_known_args(args, namespace)
        namespace.extra = list(getattr(namespace, "extra", [])) + extra
        return namespace, []
