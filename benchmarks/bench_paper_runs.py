"""Wall time of the paper's full-scale simulations (targets: facet <= 10 min,
each CHA run <= 20 min on 2 cores).

Prints one table row per run: final time, nodes, accepted steps, wall seconds
and the headline result (fronts / symmetry defect for the facet run; sheet
pairs / separation ratio for CHA). ``--quick`` runs only the faceting
coarsening to the paper's t = 2; ``--cha`` adds the three folding runs
(Table T1 with l* = 0.1, N = 600: about 1.5-2 minutes each; the literal l* = 0.01 at
N = 2400 took 4-7 minutes each on a loaded machine).

Run: ``OPENBLAS_NUM_THREADS=1 python benchmarks/bench_paper_runs.py [--quick] [--cha]``.
"""

from __future__ import annotations

import argparse
import tempfile

from qsa.paper import CHAScenario, FacetScenario, run_cha, run_facet


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="facet to t = 2 only")
    parser.add_argument("--cha", action="store_true", help="also the three CHA folding runs")
    args = parser.parse_args()
    print(f"{'run':14s}{'t_final':>9s}{'N':>6s}{'steps':>7s}{'wall s':>9s}  result")
    with tempfile.TemporaryDirectory() as out:
        for t_final in (2.0,) if args.quick else (2.0, 400.0):
            sc = FacetScenario()
            r = run_facet(sc, f"{out}/facet{t_final:g}", t_final=t_final, progress=False)
            c = r.coarsening
            print(f"{'facet':14s}{t_final:9g}{sc.N:6d}{r.n_steps:7d}{r.wall_seconds:9.1f}"
                  f"  fronts {c.peak}->{r.final.fronts} in {len(c.events)} events,"
                  f" 3-fold defect {r.final.rotation_defect:.2g}")
        if args.cha:
            for rho in (1.2, 1.3, 1.4):
                r = run_cha(CHAScenario(rho=rho), out, progress=False)
                ratio = r.separation_ratio
                print(f"{'cha rho=' + format(rho, 'g'):14s}{r.t_final:9g}{r.N:6d}"
                      f"{r.n_steps:7d}{r.wall_seconds:9.1f}  sheet pairs "
                      f"{r.n_sheet_pairs}, separation ratio "
                      f"{'-' if ratio is None else format(ratio, '.3f')}")


if __name__ == "__main__":
    main()
