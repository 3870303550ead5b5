"""Shared pieces of ``qsa reproduce facet|snowflake|folding`` (options, figures, JSON, text)."""

from __future__ import annotations

import argparse
import json
import os

from qsa.commands._options import int_at_least, nonnegative_float, positive_float


def check_resume(args, stems):
    """Warn when ``--resume`` finds no checkpoint for a run (it then starts afresh)."""
    from qsa.commands._errors import warn

    if not args.resume:
        return
    for stem in stems:
        path = os.path.join(args.out, f"{stem}_checkpoint.npz")
        if not os.path.isfile(path):
            warn(args, f"--resume: no checkpoint {path}; starting that run from t = 0")


def start_note(args, what):
    """Say on stderr what a long run does and where its checkpoint goes, before it starts."""
    from qsa.commands._errors import note

    bar = "" if args.progress is False else "; a progress bar on a terminal"
    note(args, f"{what}: checkpoints in {args.out}/ (Ctrl-C saves one; continue with "
               f"--resume){bar}")


def resume_hint(args, checkpoint):
    """How ``qsa reproduce`` continues an interrupted run (the checkpoint lives in --out)."""
    return f"{args.qsa_prog} --resume --out {args.out} (and the other options as before)"


def common_arguments(parser, default_out, t_final_help=None):
    """Options of the paper's simulations: output folder, final time, resume, progress.

    ``t_final_help`` states the default final time (e.g. ``"2.5, the paper's last
    figure time"``); give the number, so that ``--help`` says what the run does.
    """
    if t_final_help is None:
        t_final_help = "the scenario's t_final"
    parser.add_argument("--out", default=default_out, metavar="DIR",
                        help=f"output folder for data, figures and checkpoints "
                             f"(default ./{default_out})")
    parser.add_argument("--t-final", type=positive_float, default=None,
                        help=f"final time (default {t_final_help})")
    parser.add_argument("--resume", action="store_true",
                        help="continue an interrupted run from its checkpoint in --out")
    parser.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None,
                        help="progress bar (default: only on a terminal)")
    parser.add_argument("--no-plots", action="store_true", help="skip the figures")
    parser.add_argument("--plot", metavar="FILE", help="also write the main figure to FILE")
    parser.add_argument("--json", action="store_true", help="JSON summary on stdout")
    parser.set_defaults(resume_hint=resume_hint)


def cha_arguments(parser):
    """Options shared by ``qsa reproduce snowflake`` and ``folding``."""
    from qsa.paper.scenarios import CHAScenario

    sc = CHAScenario()
    lo, hi = sc.noise_modes
    parser.add_argument("--N", type=int_at_least(8), default=None,
                        help=f"nodes (default {sc.N} at l* = {sc.l_star:g}; for another l* "
                             "CHAScenario.nodes_for(l*) = max(600, 24/l*), e.g. "
                             f"{sc.nodes_for(0.01)} at 0.01)")
    parser.add_argument("--noise", type=nonnegative_float, default=sc.noise,
                        help=f"relative radial noise in modes {lo}-{hi} that breaks the "
                             f"{sc.lobes}-fold symmetry (default %(default)g: the exact "
                             "crenellated curve)")
    parser.add_argument("--seed", type=int, default=sc.seed,
                        help="noise seed (default %(default)s)")
    parser.add_argument("--kernel-length", "--l-star", dest="l_star", metavar="LENGTH",
                        type=positive_float, default=sc.l_star,
                        help="adhesion kernel length l* (default %(default)g: Table T1's "
                             "'0.01' is the reference code's parameter l*^2; --l-star 0.01 "
                             "is the literal reading, see CHAScenario)")


def cha_scenario(args, rho):
    """Table T1's :class:`qsa.paper.CHAScenario` with the command line's rho, noise, seed, l*.

    Without ``--N`` the nodes are ``CHAScenario.nodes_for(l*)`` (600 at the default l* = 0.1,
    2400 at the literal 0.01).
    """
    from qsa.paper import CHAScenario

    return CHAScenario.for_kernel(args.l_star, N=args.N, rho=rho, noise=args.noise,
                                  seed=args.seed)


def progress(args):
    """``--progress`` (default None: a bar only when stderr is a terminal)."""
    return args.progress


def save_figures(figures, out, stem, plot=None, main=None):
    """Write ``{key: Figure}`` as ``<out>/<stem>_<key>.png``; ``plot`` gets ``figures[main]``."""
    from qsa.plotting import save

    paths = []
    for key, fig in figures.items():
        paths.append(save(fig, os.path.join(out, f"{stem}_{key}.png")))
    if plot:
        save(figures[main or next(iter(figures))], plot)
        paths.append(plot)
    return paths


def emit(args, summary, lines):
    """JSON on stdout with ``--json``, else the text lines."""
    if args.json:
        print(json.dumps(summary, indent=2, default=float))
    else:
        print("\n".join(lines))


def fmt(value, spec=".3g"):
    return "-" if value is None else format(value, spec)


def _where(si):
    """The first crossing's points, e.g. ``13 points, (0.269, 0) ...``."""
    fc = si.first_crossing
    if fc is None or not len(fc.points):
        return "?"
    x, y = fc.points[0]
    n = len(fc.points)
    more = f"{n} points, " if n > 1 else ""
    return f"{more}({x:.3g}, {y:.3g}){' ...' if n > 1 else ''}"


def cha_lines(run):
    """The text report of a :class:`qsa.paper.CHARun`."""
    si = run.self_intersection
    return [
        f"rho={run.rho:g}, N={run.N}, t={run.t_reached:g}: {run.message}",
        f"  paired sheets {run.n_sheet_pairs}, separation {fmt(run.separation, '.4g')} "
        f"vs l* sqrt(a^2+1/2) = {run.separation_target:.4g} "
        f"(median ratio {fmt(run.separation_ratio, '.3f')}, closest-point ratio "
        f"{fmt(run.min_separation_ratio, '.3f')}; paper: within 10%)",
        f"  self-intersection: {'DETECTED' if si.detected else 'none'}"
        + (f" (t = {si.first_time:.4g} .. {si.last_time:.4g}, "
           f"{si.n_steps_crossing} steps; first at {_where(si)})" if si.detected else "")
        + f"; closest approach {fmt(si.closest_approach, '.3g')} at t = "
          f"{fmt(si.closest_approach_time, '.3g')}",
        f"  energy {run.energy_initial:.5g} -> {run.energy_final:.5g} (max step increase "
        f"{run.energy_max_increase:.2g}), length {run.final_length:.4f} "
        f"(rho L0 = {run.target_length:.4f}), L/N = {run.final_length / run.N:.4g}",
        f"  steps {run.n_steps} (+{run.n_rejected} rejected), wall {run.wall_seconds:.0f} s",
    ]
