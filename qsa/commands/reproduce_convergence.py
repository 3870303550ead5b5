"""``qsa reproduce convergence``: the appendix's spatial convergence study (Table ap:t1).

CHA flow (beta = 1, rho = 1.5, eps = 0.1, A0 = 10, l* = 1/2, a = 1) from
r = 1 + 0.35 cos 3t (+ 0.05 sin 4t in x), resampled to equal chords, backward
Euler with step doubling at tol 1e-4, to physical time t = 0.2; the max-norm
difference of the node positions of N and 2N at common nodes (node j of N is
node 2j of 2N), componentwise as the paper's code measures position errors.

Findings printed with the table:

* time. The table's "t = 0.1" is physical time 0.2 (MATH.md section 7): the
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
import time

import numpy as np

HELP = "appendix Table ap:t1: max |X(2N) - X(N)| at t = 0.2 for N = 50 ... 400 (800)"

#: Table ap:t1 of the paper (differences between N and 2N, tol 1e-4).
PAPER = {50: 0.1909, 100: 0.0397, 200: 0.0101, 400: 0.0024}
PARAMS = dict(eps=0.1, beta=1.0, rho=1.5, A0=10.0, l_star=0.5, a=1.0)
NORMALS = {"centred": "paper's centred normal", "unit": "unit normal (qsa default)"}


def add_arguments(p):
    p.add_argument("--Ns", type=int, nargs="+", default=[50, 100, 200, 400, 800],
                   help="resolutions (default 50 100 200 400 800)")
    p.add_argument("--tol", type=float, default=1e-4, help="local error tolerance (1e-4)")
    p.add_argument("--t-final", type=float, default=0.2,
                   help="physical time (default 0.2 = the paper's printed 0.1)")
    p.add_argument("--normal", choices=["centred", "unit", "both"], default="both",
                   help="adhesion-force normal: the paper code's centred difference, the unit "
                        "normal, or both (default)")
    p.add_argument("--method", choices=["be", "bdf2"], default="be")
    p.add_argument("--json", action="store_true", help="JSON summary on stdout")
    p.add_argument("--out", default=None, help="folder for positions.npz and the figure")
    p.add_argument("--plot", metavar="FILE", help="write the convergence figure to FILE")


def paper_initial_curve(M=4000):
    """The appendix's initial curve (samples at equal theta; 0.05 sin 4 theta added to x)."""
    th = 2 * np.pi * np.arange(M) / M
    r = 1 + 0.35 * np.cos(3 * th)
    return r * np.cos(th) + 0.05 * np.sin(4 * th), r * np.sin(th)


def run_study(Ns, tol=1e-4, t_final=0.2, force_normal="centred", method="be", verbose=False):
    """Final node positions for each N and the differences between successive N.

    Returns
    -------
    dict
        ``positions`` {N: (x, y)}, ``steps`` {N: int}, ``seconds`` {N: float},
        ``differences`` {N: max |X(2N) - X(N)|, componentwise},
        ``euclidean`` {N: max_j |X_j(2N) - X_j(N)|}.
    """
    from qsa.flows import CHA, solve_flow

    model = CHA(**PARAMS, force_normal=force_normal)
    initial = paper_initial_curve()
    out = {"positions": {}, "steps": {}, "seconds": {}, "differences": {}, "euclidean": {}}
    for N in sorted(Ns):
        t0 = time.perf_counter()
        res = solve_flow(model, initial, t_final, N=N, tol=tol, method=method,
                         t_eval=[t_final], progress=False, newton_tol=1e-3 * tol)
        if not res.success:
            raise RuntimeError(f"N={N}: {res.message}")
        out["positions"][N] = np.array(res.positions(-1))
        out["steps"][N] = res.n_steps
        out["seconds"][N] = time.perf_counter() - t0
        if verbose:
            print(f"  [{force_normal}] N={N}: {res.n_steps} steps, "
                  f"{out['seconds'][N]:.1f} s", flush=True)
    for N in sorted(Ns):
        if 2 * N in out["positions"]:
            d = out["positions"][N] - out["positions"][2 * N][:, ::2]
            out["differences"][N] = float(np.max(np.abs(d)))
            out["euclidean"][N] = float(np.max(np.hypot(d[0], d[1])))
    return out


def _ratios(diff):
    Ns = sorted(diff)
    return {N: diff[Np] / diff[N] for Np, N in zip(Ns, Ns[1:], strict=False)}


def run(args):
    normals = ["centred", "unit"] if args.normal == "both" else [args.normal]
    studies = {n: run_study(args.Ns, args.tol, args.t_final, n, args.method,
                            verbose=not args.json) for n in normals}
    rows = sorted({N for s in studies.values() for N in s["differences"]})
    summary = {"t_final": args.t_final, "tol": args.tol, "method": args.method,
               "paper": {str(k): v for k, v in PAPER.items()}, "results": {}}
    for n, s in studies.items():
        summary["results"][n] = {
            "differences": {str(k): v for k, v in s["differences"].items()},
            "euclidean": {str(k): v for k, v in s["euclidean"].items()},
            "ratios": {str(k): v for k, v in _ratios(s["differences"]).items()},
            "relative_to_paper": {str(k): s["differences"][k] / PAPER[k]
                                  for k in s["differences"] if k in PAPER},
            "steps": {str(k): v for k, v in s["steps"].items()},
            "seconds": {str(k): v for k, v in s["seconds"].items()}}
    if args.out:
        from qsa.io import save_npz

        os.makedirs(args.out, exist_ok=True)
        arrays = {f"{n}_N{N}": p for n, s in studies.items() for N, p in s["positions"].items()}
        save_npz(os.path.join(args.out, "positions.npz"), arrays, summary)
    figure = args.plot or (os.path.join(args.out, "convergence.png") if args.out else None)
    if figure and rows:
        from qsa.plotting import new_figure, plot_convergence, save

        fig, ax = new_figure()
        for n, s in studies.items():
            plot_convergence(rows, [s["differences"][N] for N in rows],
                             paper=PAPER if n == normals[0] else None, ax=ax,
                             label=f"qsa, {NORMALS[n]}")
        save(fig, figure)
        summary["figure"] = figure
    if args.json:
        print(json.dumps(summary, indent=2))
        return 0
    print(f"\nTable ap:t1: max |X(2N) - X(N)| at common nodes, tol {args.tol:g}, "
          f"physical t = {args.t_final:g}, method {args.method}")
    head = f"{'N':>5} | {'paper':>8} {'ratio':>5}"
    for n in normals:
        head += f" | {n + ' normal':>15} {'ratio':>5} {'/paper':>6}"
    print(head)
    for N in rows:
        p = PAPER.get(N)
        pr = PAPER.get(N // 2, np.nan) / p if p and N // 2 in PAPER else np.nan
        line = f"{N:>5} | {p if p else np.nan:>8.4f} {pr:>5.2f}"
        for n in normals:
            d = studies[n]["differences"][N]
            r = _ratios(studies[n]["differences"]).get(N, np.nan)
            line += f" | {d:>15.4f} {r:>5.2f} {d / p if p else np.nan:>6.2f}"
        print(line)
    print("\nWhy t = 0.2: the paper's code advances its clock by k per accepted pass of two "
          "steps of k,\nso its 't = 0.1' is physical time 0.2 (MATH.md section 7).")
    print("Why two columns: the code behind the paper projects the adhesion force on the "
          "centred-difference\nnormal (X_{j+1} - X_{j-1})^perp / (2hL), whose length is "
          "1 - O(h^2); qsa's default is the unit\nnormal. Both converge at second order; "
          "only the error constant differs, and the paper's\nnumbers are reproduced with "
          "CHA(force_normal='centred'). The norm (componentwise vs Euclidean)\nand the "
          "time error of backward Euler are not the cause (BDF2 at tol 1e-7 gives the same "
          "unit-normal\ndifferences; see qsa/commands/reproduce_convergence.py).")
    return 0
