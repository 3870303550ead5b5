"""Shared pieces of ``qsa reproduce facet|snowflake|folding`` (options, figures, JSON)."""

from __future__ import annotations

import json
import os


def common_arguments(parser, default_out):
    parser.add_argument("--out", default=default_out,
                        help=f"output folder for data, figures and checkpoints "
                             f"(default ./{default_out})")
    parser.add_argument("--t-final", type=float, default=None,
                        help="final time (default: the paper's)")
    parser.add_argument("--resume", action="store_true",
                        help="continue an interrupted run from its checkpoint in --out")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    parser.add_argument("--no-plots", action="store_true", help="skip the figures")
    parser.add_argument("--plot", metavar="FILE", help="also write the main figure to FILE")
    parser.add_argument("--json", action="store_true", help="JSON summary on stdout")


def cha_arguments(parser):
    """Options shared by ``qsa reproduce snowflake`` and ``folding``."""
    parser.add_argument("--N", type=int, default=None, help="nodes (default 2400)")
    parser.add_argument("--noise", type=float, default=0.0,
                        help="relative radial noise in modes 1-30 that breaks the 13-fold "
                             "symmetry (default 0: the exact crenellated curve)")
    parser.add_argument("--seed", type=int, default=1, help="noise seed (default 1)")
    parser.add_argument("--l-star", type=float, default=0.01,
                        help="kernel length l* (default 0.01, Table T1 as printed; 0.1 "
                             "gives the paper's labyrinths and layers, see CHAScenario)")


def progress(args):
    return False if args.no_progress or args.json else None


def save_figures(figures, out, stem, plot=None, main=None):
    """Write ``{key: Figure}`` as ``<out>/<stem>_<key>.png``; ``plot`` gets ``figures[main]``."""
    from qsa.plotting import save

    paths = []
    for key, fig in figures.items():
        paths.append(save(fig, os.path.join(out, f"{stem}_{key}.png")))
    if plot:
        save(figures[main or next(iter(figures))], plot)
        paths.append(plot)
    return paths


def emit(args, summary, lines):
    """JSON on stdout with ``--json``, else the text lines."""
    if args.json:
        print(json.dumps(summary, indent=2, default=float))
    else:
        print("\n".join(lines))


def fmt(value, spec=".3g"):
    return "-" if value is None else format(value, spec)
