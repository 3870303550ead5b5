"""``qsa reproduce folded``: the folded equilibria of f:fold, polished, with their stability.

Runs (or resumes, from the checkpoints of ``qsa reproduce folding --out DIR``) the
CHA folding flows of Table T1 (l* = 0.1, N = 600, to t = 2.5), then polishes each
final state by Newton's method (relative residual <= 1e-9), computes the spectrum
of the linearization with its rigid kernel, counts the unstable modes, and starts
the DAE from the polished state displaced along its slowest decaying mode: the
measured decay rate should match that eigenvalue within 1%. The grid is refined
while it does not resolve the state (``max|V^n|``, and the rigid motions' eigenvalues
against the slowest one), up to Fourier 4801 or the largest grid whose spectrum fits
in the available memory (:func:`refinement_limit`); a state unresolved there is
flagged (``resolved``, ``unresolved_reason`` in ``folded.json``). Writes
``folded.json`` (with the polished curves' sheet pairs against
``d* = l* sqrt(a^2 + 1/2)``), ``folded.npz`` (the polished nodes, ``<name>_x`` and
``<name>_y``) and the figure ``folded_modes.png`` (the slowest modes on the curves)
next to the folding figures.
"""

from __future__ import annotations

import os

from qsa.commands import _simulations as sim
from qsa.commands._options import positive_float

HELP = "folded equilibria of f:fold: Newton polish, spectrum, stability, DAE rate check"


def add_arguments(parser):
    from qsa.paper.scenarios import CHAScenario

    sim.common_arguments(parser, "qsa-folding",
                     f"{CHAScenario().t_final:g}, the paper's last figure time")
    sim.cha_arguments(parser)
    parser.add_argument("--rho", type=positive_float, nargs="+", default=[1.2, 1.3, 1.4],
                        help="precompression factors (default 1.2 1.3 1.4)")
    parser.add_argument("--no-rate", action="store_true",
                        help="skip the DAE relaxation-rate check")


def refinement_limit(largest=4801):
    """The largest grid of the refinements: ``largest``, or less if its spectrum would not fit.

    The spectrum of :func:`~qsa.paper.folded.folded_equilibrium` holds all eigenvalues
    with the two-resolution check (dense, quadratic in N): about 27 GB at N = 4801.
    A state that needs a larger grid is reported unresolved (``resolved`` false in
    ``folded.json``) instead of failing for memory.
    """
    from qsa.commands._memory import FOOTPRINTS, available_bytes

    return int(min(largest, FOOTPRINTS["spectrum-fourier"].largest_N(available_bytes())))


def run(args):
    from qsa.paper import run_folding
    from qsa.paper.folded import folded_equilibria
    from qsa.paper.runs import cha_run_name, write_output

    scenarios = [sim.cha_scenario(args, rho) for rho in args.rho]
    sim.check_resume(args, [cha_run_name(sc) for sc in scenarios])
    rhos = ", ".join(f"{r:g}" for r in args.rho)
    sim.start_note(args, f"{len(scenarios)} CHA flows (rho = {rhos}), N = "
                         f"{args.N or scenarios[0].N}, then their polished equilibria")
    folding = run_folding(scenarios, args.out, t_final=args.t_final, N=args.N,
                          resume=args.resume, progress=sim.progress(args))
    max_N = refinement_limit()
    results, failed = [], []
    for r in folding.runs:
        try:
            results += folded_equilibria([r], rate_check=not args.no_rate, max_N=max_N)
        except ValueError as exc:          # e.g. a final state that crosses itself
            failed.append({"name": r.name, "error": str(exc)})
    summary = {"equilibria": [r.summary() for r in results], "failed": failed,
               "max_N": max_N, "success": not failed and all(r.success for r in results)}
    if not args.no_plots:
        from qsa.plotting.simulations import folded_modes_figure

        summary["figures"] = sim.save_figures({"modes": folded_modes_figure(results)},
                                              args.out, "folded", args.plot)
    os.makedirs(args.out, exist_ok=True)
    arrays = {}
    for r in results:                   # the polished nodes, to restart or inspect
        arrays[f"{r.name}_x"], arrays[f"{r.name}_y"] = r.curve.positions()
    write_output(args.out, "folded", arrays, summary)
    lines = [summary_line(s) for s in summary["equilibria"]]
    lines += [f"{f['name']}: not analysed: {f['error']}" for f in failed]
    sim.emit(args, summary, lines)
    return 0 if summary["success"] else 1


def summary_line(s):
    """The printed line of one equilibrium's summary (:meth:`FoldedEquilibrium.summary`)."""
    line = (f"{s['name']}: polished to {s['relative_residual']:.2g} relative "
            f"({s['n_newton']} Newton steps, Fourier {s['N']})")
    if "n_unstable" in s:
        slow = ", ".join(f"{v:.4g}" for v in s["slowest_eigenvalues"][:4])
        line += (f"; kernel {s['n_kernel']}, unstable {s['n_unstable']} "
                 f"({'stable' if s['stable'] else 'unstable'}); slowest {slow}")
    sh = s["sheets"]
    line += f"; {sh['n_pairs']} sheet pairs"
    if sh["n_pairs"]:
        line += f", separation {sh['separation']:.4g} (d* = {sh['target']:.4g})"
    if "rate" in s:
        rt = s["rate"]
        line += (f"; DAE rate {rt['measured_rate']:.5g} vs eigenvalue "
                 f"{rt['eigenvalue']:.5g} ({100 * rt['relative_error']:.2f}%)")
    if s.get("resolved") is False:
        line += f"; NOT RESOLVED: {s['unresolved_reason']}"
    elif s.get("kernel_ratio") is not None:
        line += f"; rigid motions' eigenvalues {s['kernel_ratio']:.1e} of the slowest"
    return line
