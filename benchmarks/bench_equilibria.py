"""Cost of the semi-analytic equilibria: N-pulse construction to the done-when tolerances.

Run: ``python benchmarks/bench_equilibria.py``. Prints, per (N, alpha), the Fourier size
chosen to resolve the fronts, the best-of-3 wall time of ``npulse`` (orbit solve, sampling,
curve, residual check), |C(U)| and max|V^n| relative to the largest term of V^n.
Target: every construction under 1 s.
"""

from __future__ import annotations

import time

import numpy as np

from qsa.equilibria import heteroclinic, npulse, splice, splice_polygon
from qsa.equilibria.orbit import orbit_with_turning
from qsa.equilibria.splice import polygon_positions


def best_of(f, *args, repeat=3, **kwargs):
    best = np.inf
    for _ in range(repeat):
        t = time.perf_counter()
        out = f(*args, **kwargs)
        best = min(best, time.perf_counter() - t)
    return best, out


def main():
    kstar = 5.0
    print(f"{'N':>3} {'alpha':>6} {'grid':>6} {'orbit [ms]':>11} {'npulse [ms]':>12} "
          f"{'|C(U)|':>9} {'rel. V^n':>9} {'ok':>3}")
    worst = 0.0
    for n in range(2, 9):
        for alpha in (0.05, 0.1, 0.2, 0.3):
            if n * alpha >= 1:
                continue
            t_orb, _ = best_of(orbit_with_turning, alpha, 2 * np.pi / n, kstar=kstar)
            t, eq = best_of(npulse, n, alpha, kstar=kstar)
            worst = max(worst, t)
            ok = "yes" if eq.success else "NO"
            print(f"{n:>3} {alpha:>6.2f} {eq.curve.N:>6} {1e3 * t_orb:>11.1f} {1e3 * t:>12.1f} "
                  f"{eq.closure:>9.1e} {eq.relative_residual:>9.1e} {ok:>3}")
    print(f"\nslowest N-pulse construction: {worst:.3f} s (target < 1 s)")

    class Sextic:
        kstar = 5.0

        def W(self, k):
            return 0.25 * k**2 * (k - 5) ** 2 * (1 + 0.3 * (k - 2.5) ** 2)

        def dW(self, k):
            h = 1e-6
            return (self.W(k + h) - self.W(k - h)) / (2 * h)

        def d2W(self, k):
            h = 1e-4
            return (self.W(k + h) - 2 * self.W(k) + self.W(k - h)) / h**2

    print("\nsplices (closure tol 1e-12):")
    print(f"{'shape':>22} {'alpha':>6} {'grid':>6} {'time [ms]':>10} {'steps':>6} {'|C|':>9} "
          f"{'max|R_k|':>9}")
    rng = np.random.default_rng(0)
    for name, n, alpha in [("triangle", 3, 0.1), ("square", 4, 0.05), ("hexagon", 6, 0.05)]:
        angles, facets = [2 * np.pi / n] * n, list(1.0 + 0.2 * rng.random(n))
        t, eq = best_of(splice_polygon, angles, facets, alpha, kstar=kstar)
        print(f"{name + ' (polygon)':>22} {alpha:>6.2f} {eq.curve.N:>6} {1e3 * t:>10.1f} "
              f"{eq.extra['iterations']:>6} {eq.closure:>9.1e} "
              f"{np.max(np.abs(eq.extra['R_kappa'])):>9.1e}")
        p, L = polygon_positions(angles, facets, kstar)
        p = p + 0.02 * rng.standard_normal(p.size)
        t, eq = best_of(splice, p, alpha, length=L, kstar=kstar)
        print(f"{name + ' (perturbed p)':>22} {alpha:>6.2f} {eq.curve.N:>6} {1e3 * t:>10.1f} "
              f"{eq.extra['iterations']:>6} {eq.closure:>9.1e} "
              f"{np.max(np.abs(eq.extra['R_kappa'])):>9.1e}")

    s = np.linspace(-1, 1, 10_000)
    t_build, front = best_of(heteroclinic, 0.1, Sextic())
    t_eval, _ = best_of(front, s)
    print(f"heteroclinic, non-quartic well: build {1e3 * t_build:.1f} ms, "
          f"10^4 evaluations {1e3 * t_eval:.1f} ms")


if __name__ == "__main__":
    main()
