"""``qsa reproduce timesteps``: steps of the adaptive backward Euler against the tolerance.

The appendix runs the convergence example (CHA, N = 100, to the table's time)
with local error tolerances 1e-3 ... 1e-6 and reports 65, 180, 571 and 1811
time steps: x sqrt(10) per decade, as a local error O(k^2) controlled per pass
implies. qsa counts accepted step-doubling passes (two backward Euler steps of k
plus the 2k step of the error estimate), like the paper's code, at physical
time t = 0.2 (Conventions and errata, section 7: the code's clock advances by k per pass of
2k). The BDF2 column shows what the second-order method needs for the same
local tolerance (its steps grow like tol^(-1/3)).
"""

from __future__ import annotations

import json
import os

import numpy as np

HELP = "appendix: time steps for tol 1e-3 ... 1e-6 at N = 100 (paper: 65, 180, 571, 1811)"


def __getattr__(name):
    """``PAPER``, the appendix's step counts at N = 100: an alias of
    ``qsa.paper.CONVERGENCE.paper_steps`` (loaded on use, so ``qsa --help`` stays quick)."""
    if name == "PAPER":
        from qsa.paper import CONVERGENCE

        return CONVERGENCE.paper_steps
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def add_arguments(p):
    from qsa.commands._options import int_at_least, positive_float
    from qsa.paper.scenarios import ConvergenceScenario

    sc = ConvergenceScenario()
    p.add_argument("--tols", type=positive_float, nargs="+", default=None,
                   help="tolerances (default "
                        + " ".join(f"{t:.0e}".replace("e-0", "e-")
                                   for t in sorted(sc.paper_steps, reverse=True)) + ")")
    p.add_argument("--N", type=int_at_least(8), default=None,
                   help=f"nodes (default {sc.N_steps})")
    p.add_argument("--t-final", type=positive_float, default=None,
                   help=f"physical time (default {sc.t_final:g})")
    p.add_argument("--normal", choices=["centred", "unit"], default="centred",
                   help="adhesion-force normal (default: the paper code's centred normal)")
    p.add_argument("--no-bdf2", action="store_true", help="skip the BDF2 column")
    p.add_argument("--json", action="store_true", help="JSON summary on stdout")
    p.add_argument("--out", default=None, metavar="DIR",
                   help="folder for summary.json and the figure")
    p.add_argument("--plot", metavar="FILE", help="write the steps-vs-tol figure to FILE")


def run(args):
    from qsa.commands._errors import note
    from qsa.paper import CONVERGENCE, run_timesteps

    paper_steps = CONVERGENCE.paper_steps
    n_tols = len(args.tols) if args.tols else len(paper_steps)
    note(args, f"running the appendix example for {n_tols} tolerances with backward Euler"
               + ("" if args.no_bdf2 else " and BDF2") + " (the smallest takes longest)")
    steps = run_timesteps(CONVERGENCE, args.tols, N=args.N, t_final=args.t_final,
                          force_normal=args.normal, bdf2=not args.no_bdf2)
    tols, be, bdf = steps.tols, steps.be, steps.bdf2
    summary = steps.summary()
    if args.out:
        os.makedirs(args.out, exist_ok=True)
        with open(os.path.join(args.out, "summary.json"), "w") as fh:
            json.dump(summary, fh, indent=2)
    figure = args.plot or (os.path.join(args.out, "timesteps.png") if args.out else None)
    if figure:
        from qsa.plotting import plot_timesteps, save

        series = {"qsa backward Euler": [be[t].steps for t in tols]}
        if bdf:
            series["qsa BDF2"] = [bdf[t].steps for t in tols]
        paper = [paper_steps.get(t, np.nan) for t in tols]
        ax = plot_timesteps(tols, series, paper=paper)
        save(ax.figure, figure)
        summary["figure"] = figure
    if args.json:
        print(json.dumps(summary, indent=2))
        return 0
    print(f"\nTime steps of the appendix example, N = {steps.N}, physical t = {steps.t_final:g} "
          f"({args.normal} adhesion normal)")
    print(f"{'tol':>7} | {'paper':>6} | {'qsa BE':>7} {'/paper':>7} {'rejected':>8} "
          f"{'cpu [s]':>8}" + ("" if not bdf else f" | {'qsa BDF2':>8} {'cpu [s]':>8}"))
    for t in tols:
        p = paper_steps.get(t)
        b = be[t]
        line = (f"{t:>7.0e} | {p if p else '':>6} | {b.steps:>7} "
                f"{b.steps / p if p else np.nan:>7.3f} {b.rejected:>8} "
                f"{b.cpu_seconds:>8.2f}")
        if bdf:
            line += f" | {bdf[t].steps:>8} {bdf[t].cpu_seconds:>8.2f}"
        print(line)
    g = steps.growth_per_decade()
    if g is not None:
        print(f"growth per decade: qsa BE {g['be']:.3f}, paper {g['paper']:.3f}, "
              f"sqrt(10) = {g['sqrt10']:.3f}" + (f"; BDF2 {g['bdf2']:.3f} (10^(1/3) = "
                                                   f"{10 ** (1 / 3):.3f})" if bdf else ""))
    print("A step is one accepted step-doubling pass (two backward Euler steps of k, time 2k), "
          "as the paper's\ncode counts them; the paper's clock advances by k per pass, so its "
          "table time 0.1 is physical 0.2.")
    return 0
