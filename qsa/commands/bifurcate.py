"""``qsa bifurcate npulse|splice|circle|ring``: a branch, its bifurcations, the switched branches.

Builds the starting equilibrium exactly as ``qsa equilibrium`` does (same options),
follows it in ``--param`` (``L_star``, ``alpha`` or ``beta`` of Faceting + Perimeter) to
``--stop`` with stability at every point, locates every change of the unstable count
and, with ``--switch``, follows the bifurcating branches. Exit codes: 0 done, 1 a
branch ended in a solver failure (reported), 2 bad input, 130 interrupted.

Examples
--------
``qsa bifurcate circle --radius 1 --alpha 0.1 --N 33 --param L_star --stop 5.4 --step 0.05``
``qsa bifurcate circle --radius 0.95 --alpha 0.1 --N 33 --stop 5.45 --switch 1 --out ring/``
``qsa bifurcate npulse --pulses 3 --alpha 0.2 --param alpha --stop 0.3 --json --plot d.png``
``qsa bifurcate ring --eps 1 --N 65 --stop -10 --switch --switch-span -40 0 --out ring/``
(the pressurized inextensible ring: CanhamHelfrich + Pressure(p) at fixed length)
"""

from __future__ import annotations

import json
import sys

from qsa.commands import equilibrium

PARAMS = ("L_star", "alpha", "beta")


def _extra(q, faceting=True):
    if faceting:
        q.add_argument("--param", choices=PARAMS, default="L_star",
                       help="the continuation parameter of Faceting + Perimeter (default "
                            "L_star)")
    q.add_argument("--stop", type=float, required=True, help="end of the parameter range")
    q.add_argument("--step", type=float, default=None,
                   help="first arclength step (default 1/20 of the range)")
    q.add_argument("--max-steps", type=int, default=200, help="continuation steps (200)")
    q.add_argument("--switch", nargs="*", default=None, metavar="I",
                   help="follow the branches bifurcating at bifurcation(s) I (indices into "
                        "the list printed; no index: every branch point)")
    q.add_argument("--switch-span", type=float, nargs=2, default=None, metavar=("A", "B"),
                   help="parameter range of the switched branches (default the main range)")
    q.add_argument("--out", metavar="DIR", default=None,
                   help="write each branch as CSV + JSON + npz (curves) into DIR")


def add_parser(sub):
    p = sub.add_parser("bifurcate", help="continuation with stability, bifurcations, switching",
                       description=__doc__.split("\n\n")[0])
    kinds = equilibrium.add_kinds(p, run, extra=_extra)
    q = kinds.add_parser("ring", help="the pressurized inextensible ring: CanhamHelfrich(eps) "
                                      "+ Pressure(p) at fixed length, from the circle, in p")
    q.add_argument("--eps", type=float, default=1.0, help="bending rigidity (default 1)")
    q.add_argument("--radius", type=float, default=1.0, help="radius of the circle (default 1)")
    q.add_argument("--N", type=int, default=65, help="Fourier nodes (default 65)")
    q.add_argument("--json", action="store_true", help="JSON summary on stdout")
    q.add_argument("--plot", metavar="FILE", help="write the diagram to FILE")
    _extra(q, faceting=False)
    q.set_defaults(func=run, param="p")
    return p


def _family(eq, param):
    from qsa.energies import Faceting, Perimeter

    pr = eq.params
    alpha, kstar, beta, L_star = pr["alpha"], pr["kstar"], pr["beta"], pr["L_star"]
    if param == "L_star":
        return (lambda v: Faceting(alpha, kstar) + Perimeter(beta, v)), L_star
    if param == "alpha":
        return (lambda v: Faceting(v, kstar) + Perimeter(beta, L_star)), alpha
    return (lambda v: Faceting(alpha, kstar) + Perimeter(v, L_star)), beta


def _select(main, picks):
    points = [b for b in main.bifurcations if b.kind == "branch"]
    if picks == []:
        return points
    out = []
    for s in picks:
        try:
            i = int(s)
        except ValueError:
            raise ValueError(f"--switch takes bifurcation indices, got {s!r}") from None
        if not 0 <= i < len(main.bifurcations):
            raise ValueError(f"--switch {i}: there are {len(main.bifurcations)} bifurcations "
                             f"(0..{len(main.bifurcations) - 1})")
        if main.bifurcations[i].kind != "branch":
            raise ValueError(f"--switch {i}: bifurcation {i} is a fold (no branch to switch to)")
        out.append(main.bifurcations[i])
    return out


def _ring(args):
    from qsa import Curve, Fourier
    from qsa.constraints import FixedLength
    from qsa.energies import CanhamHelfrich, Pressure

    if not args.eps > 0 or not args.radius > 0:
        raise ValueError("--eps and --radius must be positive")
    eps = args.eps
    return Curve.circle(args.radius, Fourier(args.N)), (lambda p: CanhamHelfrich(eps)
                                                        + Pressure(p)), 0.0, [FixedLength()]


def run(args):
    from qsa.continuation import continuation, save_branches, switch_branch

    try:
        if args.kind == "ring":
            curve, factory, start, constraints = _ring(args)
            eq = None
        else:
            eq = equilibrium.build_polished(args)
            curve, constraints = eq.curve, None
            factory, start = _family(eq, args.param)
        if args.stop == start:
            raise ValueError(f"--stop equals the start value {args.param}={start:g}")
        step = args.step if args.step is not None else abs(args.stop - start) / 20
        step = abs(step) if args.stop > start else -abs(step)
        main = continuation(factory, curve, args.param, (start, args.stop, step),
                            constraints=constraints, max_steps=args.max_steps)
        branches = [main]
        if args.switch is not None:
            span = tuple(args.switch_span) if args.switch_span else (
                min(start, args.stop), max(start, args.stop))
            for bif in _select(main, args.switch):
                branches += switch_branch(main, bif, span=span + (abs(step),),
                                          max_steps=args.max_steps)
    except KeyboardInterrupt:
        print("qsa bifurcate: interrupted", file=sys.stderr)
        return 130
    summary = {"equilibrium": None if eq is None else eq.summary(),
               "branches": [b.summary() for b in branches]}
    if args.out:
        summary["files"] = save_branches(branches, args.out)
    if args.plot:
        from qsa import plotting

        ax = plotting.bifurcation_diagram(branches)
        plotting.save(ax.figure, args.plot)
        summary["plot"] = args.plot
    if args.json:
        print(json.dumps(summary, indent=2, default=float))
    else:
        for j, b in enumerate(branches):
            print(f"branch {j}: {len(b.points)} points; {b.message}")
        for i, bif in enumerate(main.bifurcations):
            lab = f" {bif.modes[0].label} {bif.sector}" if bif.modes else ""
            print(f"  [{i}] {bif.kind:6s} {args.param} = {bif.parameter:.12g}  "
                  f"multiplicity {bif.multiplicity}{lab}")
        if args.out:
            print(f"  branches written to {args.out}")
        if args.plot:
            print(f"  figure written to {args.plot}")
    return 0 if all(b.status >= 0 for b in branches) else 1
