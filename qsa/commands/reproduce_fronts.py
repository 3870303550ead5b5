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

import glob
import json
import os

from qsa.commands._errors import note
from qsa.commands._options import int_at_least, positive_float

HELP = "front-position ODE vs the DAE faceting flow (positions, collision times)"


def add_arguments(parser):
    import inspect

    from qsa.paper.fronts import compare_fronts
    from qsa.paper.scenarios import SCENARIOS

    defaults = {k: v.default for k, v in inspect.signature(compare_fronts).parameters.items()}
    sc = SCENARIOS["triangle"]
    parser.add_argument("--scenario", choices=sorted(SCENARIOS), default="triangle",
                        help="initial splice (default %(default)s)")
    parser.add_argument("--alpha", type=positive_float, default=None,
                        help=f"front width (default: the scenario's, {sc.alpha:g})")
    parser.add_argument("--kstar", type=positive_float, default=None,
                        help=f"corner curvature kappa* (default: the scenario's, {sc.kstar:g})")
    parser.add_argument("--beta", type=positive_float, default=None,
                        help=f"length penalty (default: the scenario's, {sc.beta:g})")
    parser.add_argument("--N", type=int_at_least(50), default=defaults["N"],
                        help="DAE nodes (default %(default)s; collision times converge like "
                             "N^-2)")
    parser.add_argument("--t-final", type=positive_float, default=None,
                        help="final time (default: the scenario's, a little after its "
                             "collision)")
    parser.add_argument("--tol", type=positive_float, default=defaults["tol"],
                        help="DAE local error tolerance (default %(default)g)")
    parser.add_argument("--progress", action=_bool_action(), default=None,
                        help="progress bar of the DAE runs (default: only on a terminal)")
    parser.add_argument("--correction", choices=("none", "newton", "profile", "profile-lag"),
                        default="none",
                        help="force of the reduction: the splice's (none, default), one "
                             "Newton step towards the slow manifold (newton; removes most "
                             "of the rate error of a closing facet; ~1.3x the uncorrected "
                             "ODE's CPU time), or the manifold of quasi-steady profiles "
                             "without or with the lag (profile, profile-lag; numpy; ~4x "
                             "and ~10x newton's CPU time)")
    parser.add_argument("--dae-check", type=int_at_least(50), metavar="N2", default=None,
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


def _bool_action():
    import argparse

    return argparse.BooleanOptionalAction


def numba_kernels_cached() -> bool:
    """Whether numba has compiled the front-ODE kernels before (its cache files exist)."""
    try:
        import numba
    except ImportError:
        return True  # the numpy backend: nothing to compile
    import qsa.reduction as reduction

    folders = [os.path.join(os.path.dirname(reduction.__file__), "__pycache__")]
    if numba.config.CACHE_DIR:
        folders.append(numba.config.CACHE_DIR)
    return any(glob.glob(os.path.join(f, "**", "_kernels.*.nbi"), recursive=True)
               for f in folders)


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

    sc = front_scenario(args.scenario, alpha=args.alpha, kstar=args.kstar, beta=args.beta)
    runs = f"N = {args.N}" + ("" if args.dae_check is None else f" and N = {args.dae_check}")
    note(args, f"running the DAE faceting flow ({runs}) to the first collision, then the "
               "front ODE")
    if not numba_kernels_cached():
        note(args, "the first run compiles the front ODE's numba kernels (about 30 s, once; "
                   "cached for later runs)")
    result = compare_fronts(sc, N=args.N, t_final=args.t_final, tol=args.tol,
                            correction=None if args.correction == "none" else args.correction,
                            reference_N=args.dae_check, progress=args.progress)
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
