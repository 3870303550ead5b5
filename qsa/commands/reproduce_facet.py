"""``qsa reproduce facet``: faceting coarsening (f:facet, f:facet_energy).

alpha = 0.1, beta = 5, kappa* = 5, N = 600 from a perturbed circle in the
spinodal range, chosen a priori from the paper's text (:class:`qsa.paper.FacetScenario`:
the circle whose fastest mode is k = 9, L* that balances it, noise 3e-5 in modes
2-15, seed 1). Prints qsa's front count, functional residual and energy at the
paper's figure times (on the physical clock: twice the printed times) next to what
the paper states there, the residual on every plateau between events, the events,
the final 3-fold symmetry and the wall time; writes ``facet.npz``, ``facet.json``
and three figures.
"""

from __future__ import annotations

from qsa.commands._simulations import (
    check_resume,
    common_arguments,
    emit,
    fmt,
    progress,
    save_figures,
    start_note,
)

HELP = "faceting coarsening: ~18 fronts -> 6 (rounded triangle), energy + R_kappa (f:facet)"


def add_arguments(parser):
    from qsa.paper.scenarios import FacetScenario

    sc = FacetScenario()
    common_arguments(parser, "qsa-facet",
                     f"{sc.t_final:g}: the paper's figure stops at t = {sc.figure_times[-1]:g}; "
                     "the run continues while the triangle's 3-fold symmetry defect decays "
                     "towards 1e-3")
    parser.add_argument("--seed", type=int, default=sc.seed,
                        help="noise seed (default %(default)s)")


def _paper(value, spec):
    return "-" if value is None else format(value, spec)


def figure_lines(run):
    """qsa's values at the paper's figure times and on every plateau (text rows)."""
    sc = run.scenario
    lines = [f"at the paper's figure times (its clock runs at 1/{sc.paper_clock:g} of the "
             "physical time):",
             f"{'t (paper)':>10s}{'t':>10s}{'fronts':>14s}{'R_kappa':>22s}{'energy':>10s}",
             f"{'':20s}{'paper':>7s}{'qsa':>7s}{'paper':>11s}{'qsa':>11s}"]
    for r in run.figure_rows:
        lines.append(f"{r.paper_t:>10.3g}{r.t:>10.3g}{_paper(r.paper_fronts, 'd'):>7s}"
                     f"{r.fronts:>7d}{_paper(r.paper_R_kappa, '.0e'):>11s}"
                     f"{r.R_kappa:>11.2e}{r.energy:>10.4g}")
    lines.append("R_kappa on the plateaus between events (paper: ~1e-3 on all of them):")
    lines += [f"  {p.fronts:2d} fronts, t = {p.t_start:.3g} .. {p.t_end:.3g}: median "
              f"{p.R_kappa:.2e} (min {p.R_kappa_min:.2e})" for p in run.plateaus]
    return lines


def facet_lines(run, out):
    """The text report of a :class:`qsa.paper.FacetRun` (``out``: its data folder)."""
    c, final = run.coarsening, run.final
    events = ", ".join(f"{e.before}->{e.after} at {e.t:.3g}" for e in c.events)
    sc = run.scenario
    return [
        f"faceting coarsening, N={sc.N}, t_final={run.t_final:g}: {run.message}",
        f"initial circle R = {sc.R:.4f} (fastest mode k = 9), L* = {sc.L_star:.4f} (the "
        f"circle in balance), noise {sc.noise:g}",
        *figure_lines(run),
        f"{'':28s}{'paper':>18s}{'qsa':>24s}",
        f"{'fronts (peak -> final)':28s}{'18 -> 6':>18s}"
        f"{str(c.peak) + ' -> ' + str(final.fronts):>24s}",
        f"{'coarsening events':28s}{'6':>18s}{len(c.events):>24d}",
        f"{'3-fold rotation defect':28s}{'(target 1e-3)':>18s}"
        f"{fmt(final.rotation_defect):>24s}",
        f"{'corner turning spread':28s}{'':>18s}{fmt(final.corner_spread):>24s}",
        f"{'final R_kappa':28s}{'~1e-3':>18s}{fmt(final.R_kappa):>24s}",
        f"{'final length':28s}{'':>18s}{final.length:>24.4f}",
        f"{'energy: max step increase':28s}{'monotone':>18s}"
        f"{fmt(run.energy_max_increase):>24s}",
        f"events: {events}",
        f"steps {run.n_steps}, wall {run.wall_seconds:.1f} s; data in {out}/",
    ]


def run(args):
    from dataclasses import replace

    from qsa.paper import FacetScenario, run_facet

    sc = replace(FacetScenario(), seed=args.seed)
    check_resume(args, ["facet"])
    start_note(args, f"faceting coarsening at N = {sc.N} to t = "
                     f"{sc.t_final if args.t_final is None else args.t_final:g}")
    result = run_facet(sc, args.out, t_final=args.t_final, resume=args.resume,
                       progress=progress(args))
    s = result.summary()
    if not args.no_plots:
        from qsa.plotting.simulations import facet_figures

        s["figures"] = save_figures(facet_figures(result), args.out, "facet", args.plot,
                                    "panels")
    emit(args, s, facet_lines(result, args.out))
    return 0 if result.success else 1
