"""``qsa reproduce convergence``: the appendix's spatial convergence study (Table ap:t1).

CHA flow (beta = 1, rho = 1.5, eps = 0.1, A0 = 10, l* = 1/2, a = 1) from
r = 1 + 0.35 cos 3t (+ 0.05 sin 4t in x), resampled to equal chords, backward
Euler with step doubling at tol 1e-4, to physical time t = 0.2; the max-norm
difference of the node positions of N and 2N at common nodes (node j of N is
node 2j of 2N), componentwise as the paper's code measures position errors.

Findings printed with the table:

* time. The table's "t = 0.1" is physical time 0.2 (Conventions and errata, section 7): the
  paper's code advances its clock by k per accepted pass of two steps of k.
* discretization. The code behind the paper evaluates the adhesion force
  along the centred-difference normal ``(X_{j+1} - X_{j-1})^perp / (2 h L)``,
  not normalized; its length is ``1 - O(h^2)``. qsa's default uses the unit
  normal. Both are second order (ratios ~4) but the error constants differ:
  with the unit normal the differences are ~1.3-1.5x the paper's, with the
  paper's centred normal (``CHA(force_normal="centred")``) they match the
  table. Neither the norm (componentwise vs Euclidean, < 10% here) nor the
  time error of backward Euler explains the gap: with BDF2 at tol 1e-7 the
  unit-normal differences are 0.2576 (N = 50) and 0.0599 (N = 100), the same
  as backward Euler's at tol 1e-4 (0.2565, 0.0604).
"""

from __future__ import annotations

import json
import os

import numpy as np

HELP = "appendix Table ap:t1: max |X(2N) - X(N)| at t = 0.2 for N = 50 ... 400 (800)"


def __getattr__(name):
    """``PAPER`` (Table ap:t1), ``PARAMS`` and ``paper_initial_curve``: aliases of
    ``qsa.paper.CONVERGENCE`` (loaded on use, so ``qsa --help`` stays quick)."""
    from qsa.paper import CONVERGENCE

    aliases = {"PAPER": CONVERGENCE.paper_differences, "PARAMS": CONVERGENCE.model_params(),
               "paper_initial_curve": CONVERGENCE.samples}
    if name in aliases:
        return aliases[name]
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def add_arguments(p):
    from qsa.commands._options import int_at_least, positive_float
    from qsa.paper.scenarios import ConvergenceScenario

    sc = ConvergenceScenario()
    p.add_argument("--Ns", type=int_at_least(8), nargs="+", default=None,
                   help=f"resolutions (default {' '.join(str(n) for n in sc.Ns)})")
    p.add_argument("--tol", type=positive_float, default=None,
                   help=f"local error tolerance (default {sc.tol:g})")
    p.add_argument("--t-final", type=positive_float, default=None,
                   help=f"physical time (default {sc.t_final:g} = the paper's printed "
                        f"{sc.t_final / 2:g})")
    p.add_argument("--normal", choices=["centred", "unit", "both"], default="both",
                   help="adhesion-force normal: the paper code's centred difference, the unit "
                        "normal, or both (default)")
    p.add_argument("--method", choices=["be", "bdf2"], default="be",
                   help="backward Euler with step doubling (the paper's; default) or BDF2")
    p.add_argument("--json", action="store_true", help="JSON summary on stdout")
    p.add_argument("--out", default=None, metavar="DIR",
                   help="folder for positions.npz and the figure")
    p.add_argument("--plot", metavar="FILE", help="write the convergence figure to FILE")


def run(args):
    from qsa.paper import CONVERGENCE, run_convergence
    from qsa.paper.appendix import NORMALS

    paper = CONVERGENCE.paper_differences
    normals = ["centred", "unit"] if args.normal == "both" else [args.normal]
    study = run_convergence(CONVERGENCE, args.Ns, tol=args.tol, t_final=args.t_final,
                            normals=normals, method=args.method, verbose=not args.json)
    rows = study.rows
    summary = study.summary()
    if args.out:
        from qsa.io import save_npz

        os.makedirs(args.out, exist_ok=True)
        save_npz(os.path.join(args.out, "positions.npz"), study.arrays(), summary)
    figure = args.plot or (os.path.join(args.out, "convergence.png") if args.out else None)
    if figure and rows:
        from qsa.plotting import new_figure, plot_convergence, save

        fig, ax = new_figure()
        for n, s in study.studies.items():
            plot_convergence(rows, [s.differences[N] for N in rows],
                             paper=paper if n == normals[0] else None, ax=ax,
                             label=f"qsa, {NORMALS[n]}")
        save(fig, figure)
        summary["figure"] = figure
    if args.json:
        print(json.dumps(summary, indent=2))
        return 0
    print(f"\nTable ap:t1: max |X(2N) - X(N)| at common nodes, tol {study.tol:g}, "
          f"physical t = {study.t_final:g}, method {study.method}")
    head = f"{'N':>5} | {'paper':>8} {'ratio':>5}"
    for n in normals:
        head += f" | {n + ' normal':>15} {'ratio':>5} {'/paper':>6}"
    print(head)
    for N in rows:
        p = paper.get(N)
        pr = paper.get(N // 2, np.nan) / p if p and N // 2 in paper else np.nan
        line = f"{N:>5} | {p if p else np.nan:>8.4f} {pr:>5.2f}"
        for n in normals:
            s = study.studies[n]
            d = s.differences[N]
            r = s.ratios().get(N, np.nan)
            line += f" | {d:>15.4f} {r:>5.2f} {d / p if p else np.nan:>6.2f}"
        print(line)
    print("\nWhy t = 0.2: the paper's code advances its clock by k per accepted pass of two "
          "steps of k,\nso its 't = 0.1' is physical time 0.2 (Conventions and errata, section 7).")
    print("Why two columns: the code behind the paper projects the adhesion force on the "
          "centred-difference\nnormal (X_{j+1} - X_{j-1})^perp / (2hL), whose length is "
          "1 - O(h^2); qsa's default is the unit\nnormal. Both converge at second order; "
          "only the error constant differs, and the paper's\nnumbers are reproduced with "
          "CHA(force_normal='centred'). The norm (componentwise vs Euclidean)\nand the "
          "time error of backward Euler are not the cause (BDF2 at tol 1e-7 gives the same "
          "unit-normal\ndifferences; see qsa/commands/reproduce_convergence.py).")
    return 0
