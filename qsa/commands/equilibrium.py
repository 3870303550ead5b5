"""``qsa equilibrium npulse|splice|circle``: build a faceted equilibrium and report it.

Examples
--------
``qsa equilibrium npulse --pulses 3 --alpha 0.1 --json``
``qsa equilibrium splice --angles 90 135 135 --facets 1 1.4 1 --alpha 0.1 --plot s.png``
``qsa equilibrium circle --radius 0.7 --alpha 0.1``
"""

from __future__ import annotations

import json

import numpy as np


def _grid(args):
    from qsa import FiniteDifference, Fourier

    if args.N is None:
        return None
    return FiniteDifference(args.N) if args.fd else Fourier(args.N)


def add_parser(sub):
    p = sub.add_parser("equilibrium", help="faceted equilibria: N-pulses, splices, circles",
                       description=__doc__.split("\n\n")[0])
    add_kinds(p, run)
    return p


def add_kinds(p, func, extra=None):
    """Add the ``npulse|splice|circle`` sub-parsers (with the shared options) to ``p``.

    ``extra(q)``, if given, adds more options to each of them (``qsa spectrum`` uses it).
    """
    kinds = p.add_subparsers(dest="kind", metavar="KIND", required=True)

    def common(q):
        q.add_argument("--alpha", type=float, required=True, help="surface-diffusion length")
        q.add_argument("--kstar", type=float, default=5.0, help="second well (default 5)")
        q.add_argument("--beta", type=float, default=5.0, help="perimeter penalty (default 5)")
        q.add_argument("--N", type=int, default=None,
                       help="grid nodes (default: a Fourier grid resolving the fronts)")
        q.add_argument("--fd", action="store_true", help="finite differences instead of Fourier")
        q.add_argument("--json", action="store_true", help="JSON summary on stdout")
        q.add_argument("--plot", metavar="FILE", help="write a figure to FILE")
        q.add_argument("--polish", action="store_true",
                       help="polish the state by Newton on V^n = 0 with closure (exact "
                            "discrete equilibrium of the reported energy)")
        q.add_argument("--tol", type=float, default=1e-10,
                       help="relative residual target of --polish (default 1e-10)")
        if extra is not None:
            extra(q)
        q.set_defaults(func=func)

    q = kinds.add_parser("npulse", help="N-fold symmetric faceted equilibrium")
    q.add_argument("--pulses", type=int, required=True, help="number of corners N >= 2")
    q.add_argument("--nu1", type=float, default=0.0, help="curvature multiplier (default 0)")
    common(q)
    q = kinds.add_parser("splice", help="heteroclinic splice shaped like a rounded polygon")
    q.add_argument("--angles", type=float, nargs="+", required=True,
                   help="exterior corner angles in degrees (sum 360)")
    q.add_argument("--facets", type=float, nargs="+", required=True, help="facet lengths")
    common(q)
    q = kinds.add_parser("circle", help="the circle as an equilibrium (L* balanced)")
    q.add_argument("--radius", type=float, required=True)
    common(q)
    return kinds


def build(args):
    from qsa import equilibria

    grid = _grid(args)
    if args.kind == "npulse":
        return equilibria.npulse(args.pulses, args.alpha, grid=grid, nu1=args.nu1,
                                 beta=args.beta, kstar=args.kstar)
    if args.kind == "splice":
        if len(args.angles) != len(args.facets):
            raise ValueError("--angles and --facets need the same number of values")
        return equilibria.splice_polygon(np.radians(args.angles), args.facets, args.alpha,
                                         grid=grid, kstar=args.kstar, beta=args.beta)
    return equilibria.circle(args.radius, args.alpha, grid=grid, beta=args.beta,
                             kstar=args.kstar)


def build_polished(args):
    """:func:`build`, then :func:`~qsa.equilibria.polish` if ``args.polish`` (keeping the
    construction parameters that polish does not report)."""
    eq = build(args)
    if getattr(args, "polish", False):
        from dataclasses import replace

        from qsa.equilibria.newton import polish

        constructed = eq
        eq = polish(eq.energy, eq.curve, tol=args.tol)
        kept = {k: v for k, v in constructed.params.items()
                if k not in eq.params and isinstance(v, (int, float))}
        eq = replace(eq, params={**eq.params, **kept})
    return eq


def run(args):
    eq = build_polished(args)
    summary = eq.summary()
    if args.plot:
        from qsa import plotting

        p = eq.params
        title = f"{eq.kind}: alpha={p['alpha']}, L={p['L']:.6g}, L*={p['L_star']:.6g}"
        plotting.save(plotting.plot_curve_and_curvature(eq.curve, title=title), args.plot)
        summary["plot"] = args.plot
    if args.json:
        print(json.dumps(summary, indent=2))
    else:
        print(eq.message)
        for k, v in summary["params"].items():
            print(f"  {k:>10} = {v}")
        print(f"  {'Lambda':>10} = {summary['multipliers']}")
        print(f"  {'energy':>10} = {summary['energy']:.12g}")
        if args.plot:
            print(f"  figure written to {args.plot}")
    return 0 if eq.success else 1
