"""``qsa reproduce snowflake``: CHA flow from the 13-fold crenellated start (f:Snowflake).

Table T1 (l* = 0.01, a = 1, A0 = 40, beta = 60, eps = 0.08), rho = 1.3, to
t = 2.5 at N = 2400 (override with --N). Prints the paired sheets and their
separation against l* sqrt(a^2 + 1/2), the self-intersection report and the
wall time; ``--check-resolution`` first compares N with 2N over a short time.
The run is stored as ``cha_rho1.3`` (as in ``qsa reproduce folding``), so
the two commands share it with the same ``--out`` and ``--resume``.

With Table T1 as printed (l* = 0.01) the curve forms 13 lobes and then a few
petals, not the paper's labyrinths and stacked layers; ``--l-star 0.1 --N 600``
gives those (``qsa.flows.scenarios.CHAScenario`` explains why and lists the
hypotheses tested).
"""

from __future__ import annotations

from qsa.commands._simulations import (
    cha_arguments,
    common_arguments,
    emit,
    fmt,
    progress,
    save_figures,
)

HELP = "CHA adhesion flow from the crenellated start, rho=1.3 (f:Snowflake, Table T1)"


def add_arguments(parser):
    common_arguments(parser, "qsa-snowflake")
    cha_arguments(parser)
    parser.add_argument("--rho", type=float, default=1.3, help="precompression (default 1.3)")
    parser.add_argument("--check-resolution", type=float, default=None, metavar="T",
                        help="first run N and 2N to time T and report the difference")


def _where(sh):
    """The first crossing's points, e.g. ``13 points, (0.269, 0) ...``."""
    pts = sh.get("first_crossing_points") or []
    if not pts:
        return "?"
    x, y = pts[0]
    more = f"{len(pts)} points, " if len(pts) > 1 else ""
    return f"{more}({x:.3g}, {y:.3g}){' ...' if len(pts) > 1 else ''}"


def cha_lines(s):
    sh = s["self_intersection"]
    return [
        f"rho={s['params']['rho']:g}, N={s['params']['N']}, t={s['t_reached']:g}: "
        f"{s['message']}",
        f"  paired sheets {s['n_sheet_pairs']}, separation {fmt(s['separation'], '.4g')} "
        f"vs l* sqrt(a^2+1/2) = {s['separation_target']:.4g} "
        f"(median ratio {fmt(s['separation_ratio'], '.3f')}, closest-point ratio "
        f"{fmt(s['min_separation_ratio'], '.3f')}; paper: within 10%)",
        f"  self-intersection: {'DETECTED' if sh['detected'] else 'none'}"
        + (f" (t = {sh['first_time']:.4g} .. {sh['last_time']:.4g}, "
           f"{sh['n_steps_crossing']} steps; first at {_where(sh)})" if sh["detected"] else "")
        + f"; closest approach {fmt(sh['closest_approach'], '.3g')} at t = "
          f"{fmt(sh['closest_approach_time'], '.3g')}",
        f"  energy {s['energy_initial']:.5g} -> {s['energy_final']:.5g} (max step increase "
        f"{s['energy_max_increase']:.2g}), length {s['final_length']:.4f} "
        f"(rho L0 = {s['target_length']:.4f}), L/N = {s['h_final']:.4g}",
        f"  steps {s['n_steps']} (+{s['n_rejected']} rejected), wall {s['wall_seconds']:.0f} s",
    ]


def run(args):
    from dataclasses import replace

    from qsa.flows.paper_runs import resolution_check, run_cha
    from qsa.flows.scenarios import CHAScenario

    sc = replace(CHAScenario(), rho=args.rho, noise=args.noise, seed=args.seed,
                 l_star=args.l_star)
    summary, lines = {}, []
    if args.check_resolution:
        rc = resolution_check(sc, args.N, args.check_resolution, progress=progress(args))
        summary["resolution_check"] = rc
        lines.append(f"resolution: N={rc['N']} vs 2N to t={rc['t_short']:g}: max position "
                     f"difference {rc['max_difference']:.3g} = "
                     f"{rc['max_difference_over_l_star']:.3g} l* "
                     f"(wall {rc['wall'][0]:.0f} s + {rc['wall'][1]:.0f} s)")
    out = run_cha(sc, args.out, t_final=args.t_final, N=args.N,
                  resume=args.resume, progress=progress(args))
    s = {**out.summary, **summary}
    if not args.no_plots:
        from qsa.plotting.simulations import cha_figures

        s["figures"] = save_figures(cha_figures(out.arrays, s), args.out, "snowflake",
                                    args.plot, "snapshots")
    emit(args, s, lines + cha_lines(s) + [f"data in {args.out}/"])
    return 0 if s["success"] else 1
