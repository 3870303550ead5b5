"""``qsa reproduce coarsening``: f:facet's coarsening by the DAE and by the front ODE.

Runs the DAE faceting flow from f:facet's start (:class:`qsa.paper.FacetScenario`,
resolved: N = 1200, BDF2, tol 1e-6 by default), hands its state over to the
front-position ODE once the fronts have formed, integrates the ODE through all its
collisions and prints both event sequences side by side: which pair annihilated
(fronts numbered at the hand-over), a corner or a facet, when, and the fronts left;
then the final corners and facets of both. The paper does not carry out the reduction,
so there is no published number; ``--polygon N:SEED`` runs a random polygon with three
short facets from its splice instead.

Examples
--------
``qsa reproduce coarsening --json``
``qsa reproduce coarsening --polygon 5:1 --plot coarsening.png``
"""

from __future__ import annotations

import json
import os

HELP = "f:facet's coarsening events, DAE vs front-position ODE, side by side"


def add_arguments(parser):
    parser.add_argument("--N", type=int, default=1200, help="DAE nodes (default 1200)")
    parser.add_argument("--method", choices=("bdf2", "be"), default="bdf2",
                        help="DAE time stepper (default bdf2)")
    parser.add_argument("--tol", type=float, default=1e-6,
                        help="DAE local error tolerance (default 1e-6)")
    parser.add_argument("--t-final", type=float, default=None,
                        help="final time (default 2.2 for f:facet: after its last event)")
    parser.add_argument("--handover", type=float, default=None, metavar="T",
                        help="hand-over time (default: the first quasi-steady state, "
                             "R_kappa <= 0.3 and all gaps >= 2 d_c, after the fronts formed)")
    parser.add_argument("--correction", choices=("none", "newton"), default="newton",
                        help="force of the ODE (default newton)")
    parser.add_argument("--polygon", metavar="N:SEED", default=None,
                        help="a random polygon with N corners and three short facets "
                             "(qsa.paper.random_polygon) instead of f:facet")
    parser.add_argument("--json", action="store_true", help="JSON summary on stdout")
    parser.add_argument("--plot", metavar="FILE", help="write the front histories to FILE")
    parser.add_argument("--out", metavar="DIR",
                        help="write coarsening.json and coarsening.png into DIR")
    parser.add_argument("--no-plots", action="store_true", help="no figure in --out")


def _scenario(args):
    from dataclasses import replace

    from qsa.paper import FacetScenario, random_polygon
    from qsa.reduction import FrontODE

    if args.polygon is None:
        return FacetScenario()
    try:
        n, seed = (int(v) for v in args.polygon.split(":"))
    except ValueError:
        raise ValueError(f"--polygon must be N:SEED (integers), got {args.polygon!r}") from None
    sc = random_polygon(n, seed, n_short=3, short=(0.25, 0.32))
    if args.t_final is not None:
        return replace(sc, t_final=args.t_final)
    # a little after the ODE's third collision
    eq = sc.splice()
    sol = FrontODE(sc.alpha, sc.kstar, eq.params["L"], beta=sc.beta).integrate(
        eq.params["positions"], 1e3, rtol=1e-5, max_collisions=3)
    times = [e.time for e in sol.events]
    return replace(sc, t_final=1.2 * times[min(2, len(times) - 1)] if times else 1.0)


def _pct(x):
    return "-" if x is None else f"{100 * x:.1f}%"


def report_lines(s):
    """The text report of a :class:`qsa.paper.CoarseningComparison` summary."""
    lines = [f"coarsening: {s['scenario']}, DAE N={s['N']} {s['method']} tol {s['tol']:g}, "
             f"ODE correction {s['correction']}, to t = {s['t_final']:g}"]
    if s["before_handover"]:
        lines.append("DAE before the hand-over (fronts still forming, not carried by the ODE): "
                     + ", ".join(f"{e['n_fronts'] + 2}->{e['n_fronts']} at {e['time']:.3g}"
                                 for e in s["before_handover"]))
    lines.append(f"hand-over at t = {s['handover_time']:.4g}: {s['handover_fronts']} fronts, "
                 f"R_kappa {s['handover_residual']:.2g}")
    lines.append(f"{'#':>2} {'fronts':>7}  {'DAE pair':>10} {'kind':>6} {'t DAE':>10}  "
                 f"{'ODE pair':>10} {'kind':>6} {'t ODE':>10} {'diff':>7}")
    rows = max(len(s["dae_events"]), len(s["ode_events"]))
    for k in range(rows):
        d = s["dae_events"][k] if k < len(s["dae_events"]) else None
        o = s["ode_events"][k] if k < len(s["ode_events"]) else None
        diff = s["event_rel_diff"][k] if k < len(s["event_rel_diff"]) else None
        n = (d or o)["n_fronts"]

        def cols(e):
            if e is None:
                return f"{'-':>10} {'':>6} {'-':>10}"
            return f"{str(tuple(e['fronts'])):>10} {e['kind']:>6} {e['time']:>10.4g}"

        lines.append(f"{k + 1:>2} {str(n + 2) + '->' + str(n):>7}  {cols(d)}  {cols(o)} "
                     f"{_pct(diff):>7}")
    lines.append(f"same events in the same order: {'yes' if s['same_sequence'] else 'NO'}; "
                 f"largest time difference {_pct(s['max_event_rel_diff'])} "
                 "(of the time since the hand-over)")
    for name in ("dae", "ode"):
        f = s[f"final_{name}"]
        lines.append(f"final {name.upper()} (t = {f['time']:.3g}): corners turn "
                     + ", ".join(f"{x:.3f}" for x in f["corner_turning"])
                     + "; facets " + ", ".join(f"{x:.3f}" for x in f["facet_lengths"])
                     + f"; L = {f['length']:.4f}")
    lines.append(f"CPU: DAE {s['time_dae']:.1f} s, ODE {s['time_ode']:.2f} s "
                 f"({s['n_rhs_ode']} evaluations)")
    lines.append("paper: no published numbers (the reduction is new in qsa)")
    return lines


def run(args):
    from qsa.paper import compare_coarsening

    if args.N < 100:
        raise ValueError(f"--N must be at least 100, got {args.N}")
    if not args.tol > 0:
        raise ValueError(f"--tol must be positive, got {args.tol}")
    sc = _scenario(args)
    result = compare_coarsening(sc, N=args.N, method=args.method, tol=args.tol,
                                t_final=args.t_final, handover=args.handover,
                                correction=None if args.correction == "none"
                                else args.correction)
    summary = result.summary()
    plots = [args.plot] if args.plot else []
    if args.out:
        os.makedirs(args.out, exist_ok=True)
        if not args.no_plots:
            plots.append(os.path.join(args.out, "coarsening.png"))
        with open(os.path.join(args.out, "coarsening.json"), "w") as fh:
            json.dump(summary, fh, indent=1, default=float)
    if plots:
        from qsa.plotting import save
        from qsa.plotting.fronts import plot_coarsening

        fig = plot_coarsening(result, title=f"coarsening: {summary['scenario']}, "
                                            f"DAE N={args.N} vs front ODE")
        for path in plots:
            save(fig, path)
    if args.json:
        print(json.dumps(summary, indent=1, default=float))
    else:
        print("\n".join(report_lines(summary)))
    return 0 if result.dae_success and result.ode_success else 1
