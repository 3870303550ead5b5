"""``qsa demo``: the toolkit's pipeline on built-in defaults (the README's main job).

Writes figures and ``summary.json`` to ``./qsa-demo/`` (or ``--out``).
"""

from __future__ import annotations

import json


def add_parser(sub):
    p = sub.add_parser("demo", help="run the pipeline on built-in defaults (figures + JSON)",
                       description=__doc__.split("\n\n")[0])
    p.add_argument("--out", default="qsa-demo", help="output folder (default ./qsa-demo)")
    p.add_argument("--no-plots", action="store_true", help="skip the figures")
    p.add_argument("--json", action="store_true", help="print the JSON summary on stdout")
    p.set_defaults(func=run)
    return p


def run(args):
    from qsa.demo import run_demo

    summary = run_demo(args.out, plots=not args.no_plots, verbose=not args.json)
    if args.json:
        print(json.dumps(summary, indent=2, default=float))
    else:
        c, t = summary["curves"]["circle"], summary["curves"]["trillium"]
        print(f"circle R={c['R']}: |C(U)| = {c['closure']:.1e}, max|V^n| at L* = "
              f"{c['max_abs_normal_velocity']:.1e}")
        print(f"trillium N={t['N']}: |C(U)| = {t['closure']:.1e}, max|M rigid| = "
              f"{t['max_M_rigid']:.1e}, max|M†Ψ| = {t['max_Mdagger_Psi']:.1e}")
        for name in ("faceting", "canham_helfrich"):
            e = t[name]
            print(f"  {name}: E = {e['energy']:.6g}, dE/dt = {e['dissipation_rate']:.6g}, "
                  f"gradient check {e['gradient_rel_error']:.1e}, Hessian check "
                  f"{e['hessian_rel_error']:.1e}")
        n = summary["npulse"]
        print(f"3-pulse equilibrium: L = {n['params']['L']:.6g}, L* = {n['params']['L_star']:.6g}, "
              f"max|V^n| = {n['residual']:.1e}, |C(U)| = {n['closure']:.1e}")
        s = summary["spectrum"]
        print(f"  spectrum of J: {s['n_unstable']} unstable, kernel dimension {s['n_kernel']} "
              f"(expected {s['kernel']['expected_kernel_dimension']}), "
              f"|L_Lambda (d_s kappa, 0)| = {s['kernel']['lagrange_kernel']:.1e}")
        sp = summary["splice"]
        facets = ", ".join(f"{f:.4g}" for f in sp["facets"])
        print(f"splice (facets {facets}): |C(U)| = {sp['closure']:.1e}, "
              f"{sp['n_small']} small eigenvalues (expected {sp['n_small_expected']}), |largest| = "
              f"{max(abs(v) for v in sp['small_eigenvalues']):.2e}, first fast = "
              f"{sp['first_fast_eigenvalue']:.4g}")
        f = summary["flow"]
        print(f"flow from the perturbed 3-pulse (N={f['N']}): decay rate {f['measured_rate']:.5g} "
              f"vs eigenvalue {f['eigenvalue']:.5g} (relative error {f['relative_error']:.1e})")
        print(f"figures and summary.json written to {args.out}/")
    return 0
