"""``qsa reproduce facet``: faceting coarsening (f:facet, f:facet_energy).

alpha = 0.1, beta = 5, kappa* = 5, N = 600 from a perturbed circle in the
spinodal range (R = 0.44, L* = 4.045, noise 1e-5 in modes 2-15, seed 1; see
:class:`qsa.flows.scenarios.FacetScenario`). Prints the peak front count, the
coarsening events, the final 3-fold symmetry and the wall time next to the
paper's numbers; writes ``facet.npz``, ``facet.json`` and three figures.
"""

from __future__ import annotations

from qsa.commands._simulations import common_arguments, emit, fmt, progress, save_figures

HELP = "faceting coarsening: ~18 fronts -> 6 (rounded triangle), energy + R_kappa (f:facet)"


def add_arguments(parser):
    common_arguments(parser, "qsa-facet")
    parser.add_argument("--seed", type=int, default=1, help="noise seed (default 1)")


def run(args):
    from dataclasses import replace

    from qsa.flows.paper_runs import run_facet
    from qsa.flows.scenarios import FacetScenario

    sc = replace(FacetScenario(), seed=args.seed)
    out = run_facet(sc, args.out, t_final=args.t_final, resume=args.resume,
                    progress=progress(args))
    s = dict(out.summary)
    if not args.no_plots:
        from qsa.plotting.simulations import facet_figures

        s["figures"] = save_figures(facet_figures(out.arrays, s), args.out, "facet",
                                    args.plot, "panels")
    events = ", ".join(f"{e['from']}->{e['to']} at {e['t']:.3g}" for e in s["events"])
    lines = [
        f"faceting coarsening, N={sc.N}, t_final={s['t_final']:g}: {s['message']}",
        f"{'':28s}{'paper':>18s}{'qsa':>24s}",
        f"{'fronts (peak -> final)':28s}{'18 -> 6':>18s}"
        f"{str(s['peak_fronts']) + ' -> ' + str(s['final_fronts']):>24s}",
        f"{'coarsening events':28s}{'6':>18s}{s['n_events']:>24d}",
        f"{'3-fold rotation defect':28s}{'(target 1e-3)':>18s}"
        f"{fmt(s['final_rotation_defect']):>24s}",
        f"{'corner turning spread':28s}{'':>18s}{fmt(s['final_corner_spread']):>24s}",
        f"{'final R_kappa':28s}{'~1e-3':>18s}{fmt(s['final_R_kappa']):>24s}",
        f"{'energy: max step increase':28s}{'monotone':>18s}"
        f"{fmt(s['energy_max_increase']):>24s}",
        f"events: {events}",
        f"steps {s['n_steps']}, wall {s['wall_seconds']:.1f} s; data in {args.out}/",
    ]
    emit(args, s, lines)
    return 0 if s["success"] else 1
