"""``qsa reproduce spacing``: the near-contact spacing of paired sheets as l* -> 0 (s:NSI).

The paper's near-contact analysis puts two anti-parallel sheets paired by the
adhesion kernel at ``d* = l* sqrt(a^2 + 1/2)``, up to corrections that vanish as
``l* -> 0``. This polishes a folded CHA equilibrium with one long pair of sheets (a
dumbbell whose neck is zipped; Table T1's eps, beta, A0, a) at ``--start``, follows it
in ``l*`` by natural continuation with the perimeter target fixed, refining the Fourier
grid to ``--nodes-per-l-star``, and at each ``--l-star`` reports the relative residual,
the spacing in the middle of the pair against ``d*``, the same on ``Fourier(2N - 1)``,
and the order fitted to the relative errors (:mod:`qsa.paper.near_contact`).
"""

from __future__ import annotations

import json
import os

HELP = "s:NSI: spacing of the paired sheets of a polished fold -> l* sqrt(a^2 + 1/2) as l* -> 0"


def add_arguments(p):
    from qsa.commands._options import positive_float

    p.add_argument("--l-star", dest="l_stars", type=positive_float, nargs="+",
                   default=[0.2, 0.1, 0.05, 0.025], metavar="LENGTH",
                   help="screening lengths to measure, in the order visited "
                        "(default 0.2 0.1 0.05 0.025)")
    p.add_argument("--start", type=positive_float, default=0.05, metavar="LENGTH",
                   help="l* at which the dumbbell is relaxed and polished (default 0.05)")
    p.add_argument("--N", type=int, default=601,
                   help="nodes of the starting flow and polish (default 601)")
    p.add_argument("--t-flow", type=positive_float, default=1.0,
                   help="duration of the CHA flow that relaxes the dumbbell (default 1)")
    p.add_argument("--nodes-per-l-star", type=positive_float, default=10.0,
                   help="grid of the continuation: nodes per l* along the curve (default 10)")
    p.add_argument("--no-grid-check", action="store_true",
                   help="skip the second polish on Fourier(2N - 1)")
    p.add_argument("--json", action="store_true", help="JSON summary on stdout")
    p.add_argument("--out", default=None, metavar="DIR",
                   help="folder for spacing.json and the figure spacing.png")
    p.add_argument("--plot", metavar="FILE",
                   help="write the figure (the equilibria, the spacing along the pair) to FILE")


def run(args):
    from qsa.commands._errors import note
    from qsa.paper.near_contact import near_contact_study

    note(args, f"polishing a zipped dumbbell at l* = {args.start:g}, then following it to "
               f"l* = {' '.join(f'{v:g}' for v in args.l_stars)} (minutes: the smallest "
               "l* has the largest dense Newton systems)")
    sweep = near_contact_study(args.l_stars, start_l_star=args.start, N=args.N,
                               t_flow=args.t_flow,
                               nodes_per_l_star=args.nodes_per_l_star,
                               check_grid=not args.no_grid_check,
                               progress=lambda line: note(args, line))
    summary = sweep.summary()
    if args.out:
        os.makedirs(args.out, exist_ok=True)
    figures = [f for f in (args.plot, args.out and os.path.join(args.out, "spacing.png")) if f]
    if figures:
        from qsa.plotting import save
        from qsa.plotting.simulations import spacing_figure

        fig = spacing_figure(sweep)
        summary["figures"] = [save(fig, f) for f in figures]
    if args.out:
        with open(os.path.join(args.out, "spacing.json"), "w") as fh:
            json.dump(summary, fh, indent=2)
    if args.json:
        print(json.dumps(summary, indent=2))
    else:
        p = sweep.params
        print(f"Paired sheets of a polished CHA fold (eps = {p['eps']:g}, beta = {p['beta']:g}, "
              f"A0 = {p['A0']:g}, a = {p['a']:g}, perimeter target {p['L_star']:.4f}); "
              "spacing in the middle of the pair against d* = l* sqrt(a^2 + 1/2)")
        print(sweep.table())
        print(f"fitted order of |spacing/d* - 1| in l*: {sweep.order:.2f} (the middle of a pair "
              "sees the tails of its ends, not a power law)")
        print("decay length along the pair / sqrt(2) (eps / 2k)^(1/4) - 1: "
              + ", ".join(f"{pt.decay_error:+.2g}" for pt in sweep.points)
              + f" (fitted order {sweep.decay_order:.2f}); {sweep.message}")
    return 0 if sweep.success else 1
