"""``qsa reproduce NAME``: re-run a result of the paper with its published parameters.

Each reproduction lives in ``qsa/commands/reproduce_<name>.py`` and provides
``HELP`` (one line), ``add_arguments(parser)`` and ``run(args) -> int``; add its
name to ``REPRODUCTIONS``. Every reproduction prints the paper's numbers next to
ours and accepts ``--json`` and ``--out``.
"""

from __future__ import annotations

import importlib

#: Reproductions, in the order ``qsa reproduce --help`` lists them.
REPRODUCTIONS = ["convergence", "timesteps", "facet", "snowflake", "folding", "folded", "spacing",
                 "fronts", "coarsening"]


def _modules():
    for name in REPRODUCTIONS:
        try:
            module = importlib.import_module(f"qsa.commands.reproduce_{name}")
        except ModuleNotFoundError as exc:
            if exc.name != f"qsa.commands.reproduce_{name}":
                raise
            continue
        yield name, module


def add_parser(sub):
    p = sub.add_parser("reproduce", help="re-run a result of the paper (prints paper vs ours)",
                       description=__doc__.split("\n\n")[0])
    inner = p.add_subparsers(dest="name", metavar="NAME")
    for name, module in _modules():
        q = inner.add_parser(name, help=module.HELP, description=module.HELP)
        module.add_arguments(q)
        q.set_defaults(func=module.run)
    p.set_defaults(func=_help(p))
    return p


def _help(parser):
    def run(args):
        parser.print_help()
        return 0

    return run
