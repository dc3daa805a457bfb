"""The ``tailor`` command: a thin shell over the library.

Every :class:`~tailor.errors.TailorError` becomes one line on stderr and exit status 2; the
CLI is the only package that prints or reads ``argv``. One module per group of commands, each
adding its sub-commands to the parser.
"""

from __future__ import annotations

import argparse
import logging
import os
import sys

from ..errors import TailorError
from .body import add_body_commands
from .drape import add_drape_command
from .dxf import add_import_command
from .fabric import add_fabric_commands
from .fit import add_fit_command
from .output import add_output_commands
from .pattern import add_pattern_commands

__all__ = ["main", "build_parser"]


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``tailor`` command."""
    p = argparse.ArgumentParser(prog="tailor", description="Sewing patterns in, simulated garments out.")
    p.add_argument("-v", "--verbose", action="store_true", help="log progress details")
    p.add_argument("-q", "--quiet", action="store_true", help="only errors")
    sub = p.add_subparsers(dest="command", required=True, metavar="COMMAND")
    add_pattern_commands(sub)
    add_import_command(sub)
    add_body_commands(sub)
    add_drape_command(sub)
    add_fit_command(sub)
    add_fabric_commands(sub)
    add_output_commands(sub)
    return p


def main(argv=None) -> int:
    """Run the ``tailor`` command; returns the exit status (0 ok, 2 bad input or failure)."""
    args = build_parser().parse_args(argv)
    level = logging.ERROR if args.quiet else logging.DEBUG if args.verbose else logging.INFO
    logging.basicConfig(level=level, format="%(message)s")
    try:
        return args.func(args)
    except TailorError as exc:
        print(f"tailor: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("tailor: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # the reader went away (| head): nothing more to say, and no traceback
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0


if __name__ == "__main__":
    sys.exit(main())
