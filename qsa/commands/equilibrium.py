"""``qsa equilibrium npulse|splice|circle|cha``: build a faceted equilibrium, or read a
folded CHA state, and report it.

Examples
--------
``qsa equilibrium npulse --pulses 3 --alpha 0.1 --json``
``qsa equilibrium splice --angles 90 135 135 --facets 1 1.4 1 --alpha 0.1 --plot s.png``
``qsa equilibrium circle --radius 0.7 --alpha 0.1``
``qsa equilibrium npulse --pulses 3 --alpha 0.1 --polish --save eq.npz``  (then
``qsa spectrum``, ``qsa flow facet --init eq.npz`` or ``qsa.io.load("eq.npz")``)
``qsa equilibrium cha --from run-cha/result.npz --polish --save cha.npz``  (the final state
of ``qsa flow cha --out run-cha`` polished; then ``qsa spectrum cha --from cha.npz``)
``qsa equilibrium cha --from qsa-folding/cha_rho1.3.npz --polish --rho 1.35 --json``

A splice keeps the corner angles and changes the facet lengths by the least
amount that closes the curve; when they change, a warning gives both lists.
"""

from __future__ import annotations

import json

import numpy as np

from qsa.commands._errors import note, warn
from qsa.commands._options import finite_float, int_at_least, positive_float


def _grid(args):
    from qsa import FiniteDifference, Fourier

    if args.N is None:
        return None
    return FiniteDifference(args.N) if args.fd else Fourier(args.N)


def add_parser(sub):
    p = sub.add_parser("equilibrium", help="faceted equilibria: N-pulses, splices, circles; "
                                           "folded CHA states",
                       description=__doc__.split("\n\n")[0])
    add_kinds(p, run, save="write the equilibrium to FILE (.npz; read it back with "
                           "qsa.io.load, start a flow from it with qsa flow ... --init FILE)",
              cha=run_cha)
    return p


def add_kinds(p, func, extra=None, save=None, cha=None):
    """Add the ``npulse|splice|circle`` sub-parsers (with the shared options) to ``p``.

    ``extra(q)``, if given, adds more options to each of them (``qsa spectrum`` uses it);
    ``save``, if given, is the help of a ``--save FILE`` option; ``cha``, if given, is
    the ``run`` of a ``cha`` kind (a folded CHA state read from a file, with options of
    its own: :mod:`qsa.commands._folded`), which gets ``extra`` and ``save`` too.
    """
    kinds = p.add_subparsers(dest="kind", metavar="KIND", required=True)

    def common(q):
        q.add_argument("--alpha", type=positive_float, required=True,
                       help="front width alpha (surface-diffusion length)")
        q.add_argument("--kstar", type=positive_float, default=5.0,
                       help="second well kappa* (default %(default)g)")
        q.add_argument("--beta", type=positive_float, default=5.0,
                       help="length penalty (default %(default)g)")
        q.add_argument("--N", type=int_at_least(8), default=None,
                       help="grid nodes (default: the odd Fourier size resolving the fronts, "
                            "at most 20001)")
        q.add_argument("--fd", action="store_true", help="finite differences instead of Fourier")
        q.add_argument("--json", action="store_true", help="JSON summary on stdout")
        q.add_argument("--plot", metavar="FILE", help="write a figure to FILE")
        if save is not None:
            q.add_argument("--save", metavar="FILE", help=save)
        q.add_argument("--polish", action="store_true",
                       help="polish the state by Newton on V^n = 0 with closure (exact "
                            "discrete equilibrium of the reported energy)")
        q.add_argument("--tol", type=positive_float, default=1e-10,
                       help="relative residual target of --polish (default %(default)g)")
        if extra is not None:
            extra(q)
        q.set_defaults(func=func)

    q = kinds.add_parser("npulse", help="N-fold symmetric faceted equilibrium")
    q.add_argument("--pulses", type=int_at_least(2), required=True,
                   help="number of corners (>= 2)")
    q.add_argument("--nu1", type=finite_float, default=0.0,
                   help="curvature multiplier (default %(default)g)")
    common(q)
    q = kinds.add_parser("splice", help="heteroclinic splice shaped like a rounded polygon")
    q.add_argument("--angles", type=positive_float, nargs="+", required=True,
                   help="exterior corner angles in degrees (sum 360)")
    q.add_argument("--facets", type=positive_float, nargs="+", required=True,
                   help="facet lengths (changed by the least amount that closes the curve, "
                        "with a warning)")
    common(q)
    q = kinds.add_parser("circle", help="the circle as an equilibrium (L* balanced)")
    q.add_argument("--radius", type=positive_float, required=True, help="circle radius")
    common(q)
    if cha is not None:
        from qsa.commands._folded import add_cha_kind

        add_cha_kind(kinds, cha, extra=extra, save=save)
    return kinds


def build(args):
    """The equilibrium of the command line (memory checked first when ``--N`` is given)."""
    from qsa import equilibria
    from qsa.commands._memory import equilibrium_bytes, require

    if args.N is not None:
        require(args, f"the equilibrium at N = {args.N}",
                equilibrium_bytes(args.N, fourier=not args.fd), _smaller_N(args))
    grid = _grid(args)
    if args.kind == "npulse":
        return equilibria.npulse(args.pulses, args.alpha, grid=grid, nu1=args.nu1,
                                 beta=args.beta, kstar=args.kstar)
    if args.kind == "splice":
        if len(args.angles) != len(args.facets):
            raise ValueError("--angles and --facets need the same number of values")
        eq = equilibria.splice_polygon(np.radians(args.angles), args.facets, args.alpha,
                                       grid=grid, kstar=args.kstar, beta=args.beta)
        warn_changed_facets(args, args.facets, eq.params["facets"])
        return eq
    return equilibria.circle(args.radius, args.alpha, grid=grid, beta=args.beta,
                             kstar=args.kstar)


def _smaller_N(args):
    return "use a smaller --N" + ("" if args.fd else ", or --fd (sparse finite differences)")


def warn_changed_facets(args, requested, used):
    """Warn, with both lists, when a splice's facets are not the requested ones."""
    requested = [float(f) for f in requested]
    used = [float(f) for f in used]
    if not np.allclose(used, requested, rtol=1e-9, atol=0.0):
        warn(args, f"--facets {' '.join(f'{f:g}' for f in requested)} do not close with "
                   f"these --angles; using the nearest facets that do: "
                   f"{' '.join(f'{f:.6g}' for f in used)}")


def build_polished(args):
    """:func:`build`, then :func:`~qsa.equilibria.polish` if ``args.polish`` (keeping the
    construction parameters that polish does not report)."""
    eq = build(args)
    if getattr(args, "polish", False):
        from dataclasses import replace

        from qsa.commands._memory import polish_bytes, require
        from qsa.equilibria.newton import polish

        require(args, f"polishing at N = {eq.curve.N}",
                polish_bytes(eq.curve.N, fourier=not eq.curve.grid.sparse), _smaller_N(args))
        constructed = eq
        eq = polish(eq.energy, eq.curve, tol=args.tol)
        kept = {k: v for k, v in constructed.params.items()
                if k not in eq.params and isinstance(v, (int, float))}
        eq = replace(eq, params={**eq.params, **kept})
    return eq


def run(args):
    eq = build_polished(args)
    summary = eq.summary()
    if getattr(args, "save", None):
        from qsa.io import save_equilibrium

        summary["file"] = save_equilibrium(args.save, eq)
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
        if getattr(args, "save", None):
            print(f"  equilibrium written to {args.save}")
    return 0 if eq.success else 1


def run_cha(args):
    """``qsa equilibrium cha``: the CHA state of ``--from``, polished with ``--polish``."""
    from qsa.commands import _folded

    fe, state = _folded.build(args)
    summary = _folded.summary(fe, state, args)
    if args.save:
        from qsa.io import save_equilibrium

        summary["file"] = save_equilibrium(args.save, _folded.equilibrium_of(fe, args.polish))
    if args.plot:
        from qsa import plotting

        p = fe.params
        title = (f"{fe.name}: rho={p['rho']:g}, A0={p['A0']:g}, l*={p['l_star']:g}, "
                 f"E={summary['energy']:.6g}")
        plotting.save(plotting.plot_curve_and_curvature(fe.curve, title=title), args.plot)
        summary["plot"] = args.plot
    if args.json:
        print(json.dumps(summary, indent=2))
    else:
        print("\n".join(_folded.text_lines(summary)))
        if args.plot:
            print(f"  figure written to {args.plot}")
        if args.save:
            print(f"  equilibrium written to {args.save}")
    if not summary["success"]:
        note(args, f"the polish failed: {fe.polished.message}")
    return 0 if summary["success"] else 1
