"""The command line's argument parser, apart from _common.py so that `clpde --help` loads no
more than argparse (_common.py imports numpy and the image readers)."""

from __future__ import annotations

import argparse


class Parser(argparse.ArgumentParser):
    """argparse's parser with its usage errors on one line, as every other error of the
    command line: `clpde inpaint: error: ...; see `clpde inpaint --help``, exit status 2
    (argparse's own prints the whole usage first). Its subcommands' parsers are of this
    class too (argparse makes them of the parent's)."""

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {message}; see `{self.prog} --help`\n")
