"""Cost of bifurcation diagrams: continuation with stability, location, branch switching.

Rows: a branch (its points, steps, located bifurcations), wall time, time per point,
eigen-solves per point (one shift-invert factorization each; the count at every point
takes one, the location of each crossing a few more).

Diagrams:

* the faceting circle (alpha = 0.1, kstar = 5, beta = 5, Fourier(33)) from R = 0.95 in
  ``L_star`` through its mode-2 and mode-3 double crossings, both switched;
* the pressurized inextensible ring (CanhamHelfrich(1) + Pressure(p), FixedLength, R = 1,
  Fourier(65)) from p = 0 past Levy's p_2 = -3 and p_3 = -8, the n = 2 and n = 3 branches
  switched and followed to self-contact (when the constrained spectra are available).

Run: ``python benchmarks/bench_bifurcation.py`` (timings on a loaded machine are noisy).
"""

from __future__ import annotations

import time

from qsa import Curve, Fourier
from qsa.continuation import continuation, switch_branch
from qsa.energies import CanhamHelfrich, Faceting, Perimeter
from qsa.equilibria import circle


def faceting():
    eq = circle(0.95, 0.1, grid=Fourier(33))
    fam = lambda Ls: Faceting(0.1, 5.0) + Perimeter(5.0, Ls)  # noqa: E731
    main = continuation(fam, eq.curve, "L_star", (eq.params["L_star"], 5.45, -0.02))
    out = [("circle", main)]
    for bif in main.bifurcations[:2]:
        for b in switch_branch(main, bif, span=(5.3, 5.7, 0.01), max_steps=60):
            out.append((f"mode {bif.sector}", b))
    return out


def ring(N=65, eps=1.0):
    from qsa.constraints import FixedLength
    from qsa.energies import Pressure

    fam = lambda p: CanhamHelfrich(eps) + Pressure(p)  # noqa: E731
    main = continuation(fam, Curve.circle(1.0, Fourier(N)), "p", (0.0, -10.0, -0.5),
                        constraints=[FixedLength()])
    out = [("circle", main)]
    for bif in [b for b in main.bifurcations if b.sector in (2, 3)]:
        for b in switch_branch(main, bif, span=(-40.0, 0.0, 0.25), ds_max=0.5, max_steps=400):
            out.append((f"n = {bif.sector}", b))
    return out


def report(name, build):
    t0 = time.perf_counter()
    try:
        rows = build()
    except (ImportError, ValueError) as exc:
        print(f"{name}: skipped ({exc})")
        return
    total = time.perf_counter() - t0
    print(f"\n{name}: {total:.2f} s for the diagram")
    print(f"{'branch':<10}{'points':>8}{'count solves/pt':>16}{'bifs':>6}"
          f"{'locate solves/bif':>19}  status")
    for label, b in rows:
        n = len(b.points)
        count = (b.n_eigensolves - b.n_locate_solves) / max(n, 1)
        per_bif = b.n_locate_solves / len(b.bifurcations) if b.bifurcations else 0.0
        print(f"{label:<10}{n:>8}{count:>16.2f}{len(b.bifurcations):>6}{per_bif:>19.2f}  "
              f"{b.message[:56]}")


def main():
    report("faceting circle, Fourier(33)", faceting)
    report("Levy ring, Fourier(65)", ring)


if __name__ == "__main__":
    main()
