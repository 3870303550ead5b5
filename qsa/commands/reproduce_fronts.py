"""``qsa reproduce fronts``: the front-position ODE against the DAE faceting flow.

Starts the DAE faceting flow from a splice with unequal facets, tracks its
fronts, integrates the front-position ODE (:mod:`qsa.reduction.ode`) from the
same positions and reports the largest position error before the first
collision and the predicted against the observed collision time. The paper
motivates this reduction but does not carry it out, so there is no published
number to print next to ours; the targets are positions within 5% of the
smallest facet and collision times within 10%.

Examples
--------
``qsa reproduce fronts --scenario triangle --N 1200 --json``
``qsa reproduce fronts --scenario short-facet --plot fronts.png``
"""

from __future__ import annotations

import json
import os

HELP = "front-position ODE vs the DAE faceting flow (positions, collision times)"


def add_arguments(parser):
    from qsa.paper.scenarios import SCENARIOS

    parser.add_argument("--scenario", choices=sorted(SCENARIOS), default="triangle",
                        help="initial splice (default triangle)")
    parser.add_argument("--alpha", type=float, default=None,
                        help="front width (default: the scenario's, 0.1)")
    parser.add_argument("--kstar", type=float, default=None,
                        help="corner curvature (default: the scenario's, 5)")
    parser.add_argument("--beta", type=float, default=None,
                        help="perimeter penalty (default: the scenario's, 5)")
    parser.add_argument("--N", type=int, default=1200,
                        help="DAE nodes (default 1200; collision times converge like N^-2)")
    parser.add_argument("--t-final", type=float, default=None,
                        help="final time (default: a little after the scenario's collision)")
    parser.add_argument("--tol", type=float, default=1e-6, help="DAE local error tolerance")
    parser.add_argument("--correction", choices=("none", "newton"), default="none",
                        help="force of the reduction: the splice's (none, default) or one "
                             "Newton step towards the slow manifold (newton; removes most "
                             "of the rate error of a closing facet; ~1.3x the uncorrected "
                             "ODE's CPU time)")
    parser.add_argument("--dae-check", type=int, metavar="N2", default=None,
                        help="also run the DAE at N2 nodes (e.g. N/2) and report how far its "
                             "fronts are from the N run: the reference's own spread")
    parser.add_argument("--eigenvalues", action="store_true",
                        help="also compare the slow eigenvalues of the reduced Jacobian with "
                             "the full linearization (qsa.spectra) at polished regular "
                             "triangle and square splices")
    parser.add_argument("--json", action="store_true", help="JSON summary on stdout")
    parser.add_argument("--plot", metavar="FILE", help="write the front tracks to FILE")
    parser.add_argument("--out", metavar="DIR",
                        help="write fronts_<scenario>.png and .json into DIR")


def _errors_to(block):
    """``"0.03% to 0.50 t_c, ..."`` from a summary block's ``error_at``."""
    return ", ".join(f"{100 * e:.2f}% to {float(f):.2f} t_c" for f, e in block["error_at"].items())


def _report(s):
    lines = [
        f"scenario {s['scenario']}: {s['description']}",
        f"alpha={s['alpha']} kstar={s['kstar']} beta={s['beta']} N={s['N']} "
        f"L={s['L']:.6g}, smallest facet {s['facet_min']:.4g}, "
        f"force correction {s.get('correction') or 'none'}",
        f"first collision: DAE t={s['collision_dae']:.6g}  ODE t={s['collision_ode']:.6g}  "
        f"(relative difference {100 * s['collision_rel_diff']:.2f}%, target 10%)",
        "position error / smallest facet (target 5%):",
    ]
    for f, e in s["error_at"].items():
        lines.append(f"  up to {float(f):.2f} t_c: {100 * e:.2f}%")
    lines.append(f"  while all gaps >= 2 d_c (d_c = {s['collision_distance']:.4g}; until "
                 f"{s['separated_until']:.4f} t_c): {100 * s['max_error_separated']:.2f}%")
    lines.append(f"  up to the first collision: {100 * s['max_error']:.1f}% "
                 "(diverges like eps/(1 - t/t_c) for a rate error eps)")
    lines.append(f"  with the ODE time rescaled by t_c(ODE)/t_c(DAE): "
                 f"{100 * s['max_error_rescaled']:.2f}%")
    v = s.get("variable_length")
    if v:
        lines.append(f"with the length as an unknown (beta={v['beta']}): ODE t_c="
                     f"{v['collision_ode']:.6g} ({100 * v['collision_rel_diff']:.2f}%), "
                     f"positions {_errors_to(v)}, {100 * v['max_error_separated']:.2f}% while all "
                     f"gaps >= 2 d_c, {100 * v['max_error']:.1f}% up to the first "
                     f"collision; CPU {v['time_ode']:.2f} s ({v['speedup']:.0f}x)")
    d = s.get("dae_spread")
    if d:
        lines.append(f"the DAE itself, N={d['N']} vs N={s['N']}: t_c={d['collision']:.6g} "
                     f"({100 * d['collision_rel_diff']:.2f}%), positions {_errors_to(d)}, "
                     f"{100 * d['max_error']:.1f}% up to the first collision")
    lines.append(f"CPU time: DAE {s['time_dae']:.2f} s ({s['n_steps_dae']} steps), ODE "
                 f"{s['time_ode']:.3f} s ({s['n_rhs_ode']} evaluations): "
                 f"{s['speedup']:.0f}x")
    for name, e in s.get("eigenvalues", {}).items():
        pairs = zip(e["reduced"], e["full"], strict=True)
        lines.append(f"slow eigenvalues, regular {name} (reduced vs full): "
                     + ", ".join(f"{a:.4g}/{b:.4g}" for a, b in pairs)
                     + f"  (max difference {100 * e['max_rel_diff']:.2f}%, target 10%)")
    lines.append("paper: no published numbers (the reduction is new in qsa)")
    return "\n".join(lines)


def run(args):
    from qsa.paper import compare_eigenvalues, compare_fronts, front_scenario

    if args.N < 50:
        raise ValueError(f"--N must be at least 50, got {args.N}")
    sc = front_scenario(args.scenario, alpha=args.alpha, kstar=args.kstar, beta=args.beta)
    result = compare_fronts(sc, N=args.N, t_final=args.t_final, tol=args.tol,
                            correction=None if args.correction == "none" else args.correction,
                            reference_N=args.dae_check)
    summary = result.summary()
    if args.eigenvalues:
        summary["eigenvalues"] = {
            name: compare_eigenvalues(n, alpha=sc.alpha, kstar=sc.kstar).summary()
            for name, n in (("triangle", 3), ("square", 4))}
    plots = []
    if args.plot:
        plots.append(args.plot)
    if args.out:
        os.makedirs(args.out, exist_ok=True)
        plots.append(os.path.join(args.out, f"fronts_{args.scenario}.png"))
        with open(os.path.join(args.out, f"fronts_{args.scenario}.json"), "w") as fh:
            json.dump(summary, fh, indent=1)
    if plots:
        from qsa.plotting import save
        from qsa.plotting.fronts import plot_front_tracks

        fig = plot_front_tracks(result, title=f"fronts: {args.scenario}, N={args.N}")
        for path in plots:
            save(fig, path)
    if args.json:
        print(json.dumps(summary, indent=1))
    else:
        print(_report(summary))
    return 0
