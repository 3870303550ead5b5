"""``qsa reproduce snowflake``: CHA flow from the 13-fold crenellated start (f:Snowflake).

Table T1 (l* = 0.1, a = 1, A0 = 40, beta = 60, eps = 0.08), rho = 1.3, to
t = 2.5 at N = 600 (override with --N). Prints the paired sheets and their
separation against l* sqrt(a^2 + 1/2), the self-intersection report and the
wall time; ``--check-resolution`` first compares N with 2N over a short time.
The run is stored as ``cha_rho1.3`` (as in ``qsa reproduce folding``), so
the two commands share it with the same ``--out`` and ``--resume``.

Table T1's "l* = 0.01" is the reference code's kernel parameter l*^2, so
l* = 0.1 (``qsa.paper.CHAScenario``); ``--l-star 0.01`` (N = 2400) is the
literal reading: 13 lobes and then a few petals, not the paper's labyrinths.
"""

from __future__ import annotations

from qsa.commands._options import positive_float
from qsa.commands._simulations import (
    cha_arguments,
    cha_lines,
    cha_scenario,
    check_resume,
    common_arguments,
    emit,
    progress,
    save_figures,
    start_note,
)

HELP = "CHA adhesion flow from the crenellated start, rho=1.3 (f:Snowflake, Table T1)"


def add_arguments(parser):
    from qsa.paper.scenarios import CHAScenario

    common_arguments(parser, "qsa-snowflake",
                     f"{CHAScenario().t_final:g}, the paper's last figure time")
    cha_arguments(parser)
    parser.add_argument("--rho", type=positive_float, default=CHAScenario().rho,
                        help="precompression (default %(default)g)")
    parser.add_argument("--check-resolution", type=positive_float, default=None, metavar="T",
                        help="first run N and 2N to time T and report the difference")


def run(args):
    from qsa.paper import resolution_check, run_cha
    from qsa.paper.runs import cha_run_name

    sc = cha_scenario(args, args.rho)
    check_resume(args, [cha_run_name(sc)])
    start_note(args, f"CHA flow, rho = {sc.rho:g}, N = {args.N or sc.N}, to t = "
                     f"{sc.t_final if args.t_final is None else args.t_final:g}")
    summary, lines = {}, []
    if args.check_resolution:
        rc = resolution_check(sc, args.N, args.check_resolution, progress=progress(args))
        summary["resolution_check"] = rc.summary()
        lines.append(f"resolution: N={rc.N} vs 2N to t={rc.t_short:g}: max position "
                     f"difference {rc.max_difference:.3g} = "
                     f"{rc.max_difference_over_l_star:.3g} l* "
                     f"(wall {rc.wall[0]:.0f} s + {rc.wall[1]:.0f} s)")
    result = run_cha(sc, args.out, t_final=args.t_final, N=args.N, resume=args.resume,
                     progress=progress(args))
    s = {**result.summary(), **summary}
    if not args.no_plots:
        from qsa.plotting.simulations import cha_figures

        s["figures"] = save_figures(cha_figures(result), args.out, "snowflake", args.plot,
                                    "snapshots")
    emit(args, s, lines + cha_lines(result) + [f"data in {args.out}/"])
    return 0 if result.success else 1
