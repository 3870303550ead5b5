"""The ``qsa`` command line.

Each subcommand lives in ``qsa/commands/<name>.py`` and provides
``add_parser(subparsers)`` (registering itself, with ``func=run``) and
``run(args) -> int``. Register a new one by adding its module name to
``SUBCOMMANDS``. Every subcommand accepts ``--json`` (a machine-readable
summary on stdout) and, where it draws, ``--plot FILE.png``.

:func:`main` checks the path options before a subcommand starts
(:func:`qsa.commands._options.check_paths`) and turns what the subcommand
raises into one line on stderr and an exit code
(:func:`qsa.commands._errors.run_command`: 0 done, 1 failure reported, 2 bad
input, 70 internal error, 130 interrupted, 141 output pipe closed), so every
subcommand gets the same behaviour without code of its own.
"""

from __future__ import annotations

import argparse
import importlib
import sys

from qsa._version import __version__
from qsa.commands._errors import (
    EXIT_BAD_INPUT,
    EXIT_BROKEN_PIPE,
    epilog,
    run_command,
    silence_stdout,
)
from qsa.commands._options import CommandParser, check_paths

#: Subcommand modules under ``qsa.commands``, in the order ``--help`` lists them.
SUBCOMMANDS = ["demo", "equilibrium", "spectrum", "bifurcate", "flow", "reproduce", "sweep"]


def build_parser() -> argparse.ArgumentParser:
    parser = CommandParser(
        prog="qsa",
        description="Quasi-steady and spectral analysis of closed planar interfaces.",
        epilog=epilog(),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--version", action="version", version=f"qsa {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in SUBCOMMANDS:
        try:
            module = importlib.import_module(f"qsa.commands.{name}")
        except ModuleNotFoundError as exc:  # a subcommand not installed in this build
            if exc.name != f"qsa.commands.{name}":
                raise
            continue
        module.add_parser(sub)
    return parser


def _run(args):
    check_paths(args)
    return args.func(args)


def main(argv=None) -> int:
    """Parse ``argv`` (default ``sys.argv[1:]``), run the subcommand, return the exit code."""
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
        if not getattr(args, "func", None):
            parser.print_help()
            return 0
    except BrokenPipeError:  # qsa --help | head
        silence_stdout()
        return EXIT_BROKEN_PIPE
    except SystemExit as exc:  # a usage error (exit 2) is returned; --help, --version exit
        if exc.code in (0, None):
            raise
        return exc.code if isinstance(exc.code, int) else EXIT_BAD_INPUT
    return run_command(_run, args)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
