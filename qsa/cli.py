"""The ``qsa`` command line.

Each subcommand lives in ``qsa/commands/<name>.py`` and provides
``add_parser(subparsers)`` (registering itself, with ``func=run``) and
``run(args) -> int``. Register a new one by adding its module name to
``SUBCOMMANDS``. Every subcommand accepts ``--json`` (a machine-readable
summary on stdout) and, where it draws, ``--plot FILE.png``.
"""

from __future__ import annotations

import argparse
import importlib
import sys

from qsa._version import __version__

#: Subcommand modules under ``qsa.commands``, in the order ``--help`` lists them.
SUBCOMMANDS = ["demo", "equilibrium", "spectrum", "bifurcate", "flow", "reproduce", "sweep"]


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="qsa",
        description="Quasi-steady and spectral analysis of closed planar interfaces.",
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


def main(argv=None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help()
        return 0
    try:
        return int(args.func(args) or 0)
    except ValueError as exc:  # bad input: one clear line, no traceback
        print(f"qsa {args.command}: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
