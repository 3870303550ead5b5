"""Spectral dichotomy of a heteroclinic splice
============================================

The small eigenvalues of a splice shrink like ``exp(-kstar d_min / (sqrt(2) alpha))``.

A splice (Conventions and errata, section 5) glues heteroclinic fronts into a rounded
triangle: three corners of turning ``2 pi / 3`` (arcs of curvature ``kstar``, length
``d_min = 2 pi / (3 kstar)``, the shortest distance between two fronts) joined by facets
of lengths close to ``1, 1.3, 1``. It is a quasi-equilibrium: its residual, and so the
``2 * 3 - 1 = 5`` small eigenvalues of J (front motions that keep the closure; J in
the normal gauge, ``<f, h> = int f h dsigma``), are set by the interaction of the
nearest fronts, ``~ exp(-kstar d_min / (sqrt(2) alpha))``, while the rest of the
spectrum stays O(1). The script fits the slope of ``log max|lambda_small|`` against
``1/alpha`` and compares it with ``-kstar d_min / sqrt(2)``.

Run: ``python examples/ex03_splice_dichotomy.py [FIGURE.png]``.
"""

from __future__ import annotations

import sys
import warnings

import numpy as np

from qsa import plotting
from qsa.equilibria import splice_polygon
from qsa.spectra import NotEquilibriumWarning, spectrum

KSTAR = 5.0
ALPHAS = (0.15, 0.13, 0.11, 0.1)
ANGLES = np.radians([120.0, 120.0, 120.0])
FACETS = (1.0, 1.3, 1.0)


def row(alpha):
    """Small-eigenvalue cluster of the splice triangle at one ``alpha``."""
    eq = splice_polygon(ANGLES, FACETS, alpha, kstar=KSTAR)
    with warnings.catch_warnings():  # a quasi-equilibrium: the projection residual is known
        warnings.simplefilter("ignore", NotEquilibriumWarning)
        s = spectrum(eq.energy, eq.curve, reject_spurious=False)
    order = np.argsort(np.abs(s.eigenvalues))
    small = s.eigenvalues[order[:s.n_small]]
    d_min = float(eq.params["d_min"])
    return {"alpha": alpha, "success": bool(eq.success), "N": eq.curve.N, "d_min": d_min,
            "n_small": int(s.n_small), "gap_ratio": float(s.gap_ratio),
            "max_small": float(np.max(np.abs(small))),
            "first_fast": float(s.eigenvalues[order[s.n_small]]),
            "prediction": float(np.exp(-KSTAR * d_min / (np.sqrt(2) * alpha)))}


def main():
    """Rows per alpha plus the fitted and predicted slopes of log|lambda| vs 1/alpha."""
    rows = [row(a) for a in ALPHAS]
    inv = 1.0 / np.array(ALPHAS)
    slope = np.polyfit(inv, np.log([r["max_small"] for r in rows]), 1)[0]
    return {"kstar": KSTAR, "rows": rows, "slope": float(slope),
            "predicted_slope": float(-KSTAR * rows[0]["d_min"] / np.sqrt(2))}


def figure(out):
    """``max |lambda_small|`` against ``1/alpha`` with the predicted exponential rate."""
    fig, ax = plotting.new_figure(size=(5.5, 3.8))
    inv = np.array([1.0 / r["alpha"] for r in out["rows"]])
    small = np.array([r["max_small"] for r in out["rows"]])
    ax.semilogy(inv, small, "o-", label=r"max $|\lambda|$ of the 5 small eigenvalues")
    ax.semilogy(inv, small[0] * np.exp(out["predicted_slope"] * (inv - inv[0])), "--",
                color="0.4", label=r"$\propto \exp(-\kappa_* d_{min} / (\sqrt{2}\alpha))$")
    ax.set_xlabel(r"$1/\alpha$")
    ax.set_ylabel(r"$|\lambda|$")
    ax.set_title("splice triangle: slow eigenvalues")
    ax.legend(fontsize="small")
    return fig


if __name__ == "__main__":
    out = main()
    print("splice triangle, corners 120 deg, facets ~ (1, 1.3, 1), kstar=5")
    print(f"{'alpha':>6}{'nodes':>7}{'n_small':>8}{'gap':>8}{'max|small|':>12}"
          f"{'exp(-k d/(r2 a))':>18}{'ratio':>10}{'1st fast':>10}")
    for r in out["rows"]:
        print(f"{r['alpha']:>6}{r['N']:>7}{r['n_small']:>8}{r['gap_ratio']:>8.0f}"
              f"{r['max_small']:>12.3e}{r['prediction']:>18.3e}"
              f"{r['max_small'] / r['prediction']:>10.3g}{r['first_fast']:>10.2f}")
    print(f"slope of log|lambda_small| vs 1/alpha: {out['slope']:.3f} "
          f"(predicted -kstar d_min/sqrt2 = {out['predicted_slope']:.3f})")
    fig = figure(out)
    if len(sys.argv) > 1:
        plotting.save(fig, sys.argv[1])
