"""Ctrl-C on the command line: one line, whatever the moment.

A terminal's Ctrl-C sends SIGINT to every process of the foreground group: clpde's own and
the Dask workers it spawns. Three moments need care, beyond the command's own handler
(clpde.cli.main prints one line and exits 130):

- while Python loads clpde and its libraries, before main() runs:
  `quiet_while_loading`, run when this module is imported (clpde/__init__.py imports it
  first), turns Ctrl-C into the line and exit status 130 when clpde runs as the command;
- while a local Dask cluster starts or stops: `held` notes Ctrl-C and raises it as
  KeyboardInterrupt once the block ends (a cluster stopped half-started cannot close
  cleanly: pages of tracebacks), and `children_stderr` gives the workers started in the
  block a stderr that drops their output once Ctrl-C was pressed (a worker interrupted
  while Python starts, before it can ignore SIGINT, prints a traceback; a process cannot
  be started with SIGINT ignored or blocked through multiprocessing, which resets both);
- after main() has returned, while Python exits: `ignore`.
"""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import threading
from collections.abc import Iterator

LINE = "clpde: interrupted; nothing was written"
EXIT_STATUS = 130  # 128 + SIGINT, as a shell reports a process that Ctrl-C stopped


def _exit_quietly(signum, frame) -> None:
    os.write(2, (LINE + "\n").encode())
    os._exit(EXIT_STATUS)  # nothing has been written yet: no cleanup to run


def is_command_line() -> bool:
    """True when this process is `python -m clpde ...` or the `clpde` program (while
    Python looks for the module that -m names, sys.argv[0] is "-m")."""
    first = sys.argv[0] if sys.argv else ""
    return first == "-m" or os.path.basename(first) == "clpde"


def quiet_while_loading() -> None:
    """Ctrl-C before main() runs: the one line, exit 130 (only as the command line, and
    only where Python's own handler is in place: a background job ignores SIGINT)."""
    if not is_command_line():
        return
    with contextlib.suppress(ValueError):  # not the main thread
        if signal.getsignal(signal.SIGINT) is signal.default_int_handler:
            signal.signal(signal.SIGINT, _exit_quietly)


def restore() -> None:
    """Back to Python's KeyboardInterrupt once main() can catch it."""
    with contextlib.suppress(ValueError):
        if signal.getsignal(signal.SIGINT) is _exit_quietly:
            signal.signal(signal.SIGINT, signal.default_int_handler)


def ignore() -> None:
    """Ctrl-C after the work is done, while Python exits: nothing left to stop."""
    with contextlib.suppress(ValueError):
        signal.signal(signal.SIGINT, signal.SIG_IGN)


class Held:
    """What `held` saw: `pressed` is set once Ctrl-C came during a block."""

    def __init__(self) -> None:
        self.pressed = threading.Event()


@contextlib.contextmanager
def held(state: Held | None = None) -> Iterator[Held]:
    """Hold Ctrl-C for the block: pressed meanwhile, it sets state.pressed and is raised as
    KeyboardInterrupt when the block ends. Only in the main thread with Python's own
    handler in place (elsewhere, or where SIGINT is ignored, the block runs as it is)."""
    state = state or Held()
    try:
        if signal.getsignal(signal.SIGINT) is not signal.default_int_handler:
            raise ValueError
        old = signal.signal(signal.SIGINT, lambda signum, frame: state.pressed.set())
    except ValueError:  # not the main thread, or not Python's handler
        yield state
        return
    try:
        yield state
    finally:
        signal.signal(signal.SIGINT, old)
    if state.pressed.is_set():
        raise KeyboardInterrupt


# How long a line of the workers' stderr waits before it is shown: long enough for the
# Ctrl-C that the whole process group got at once to reach this process's handler.
DELAY_S = 0.3


@contextlib.contextmanager
def children_stderr(state: Held) -> Iterator[None]:
    """Processes started in the block get a pipe as their stderr, whose output reaches this
    process's stderr DELAY_S later, unless Ctrl-C was pressed (state.pressed): a Python
    process interrupted while it starts (before it can ignore SIGINT) prints a traceback,
    which says nothing to the user, who asked to stop. This process's stderr is restored
    when the block ends; the children keep the pipe until they exit."""
    try:
        read_end, write_end = os.pipe()
        saved = os.dup(2)
    except OSError:
        yield
        return
    sys.stderr.flush()
    os.dup2(write_end, 2)
    os.close(write_end)
    threading.Thread(
        target=_forward, args=(read_end, saved, state), daemon=True, name="clpde-worker-stderr"
    ).start()
    try:
        yield
    finally:
        sys.stderr.flush()
        os.dup2(saved, 2)


def _forward(read_end: int, target: int, state: Held) -> None:
    import time

    try:
        while data := os.read(read_end, 1 << 16):
            time.sleep(DELAY_S)
            if not state.pressed.is_set():
                os.write(target, data)
    except OSError:
        pass
    finally:
        os.close(read_end)
        os.close(target)


quiet_while_loading()
