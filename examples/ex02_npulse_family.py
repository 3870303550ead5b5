"""N-pulse equilibria and their unstable counts
=============================================

N-pulse faceted equilibria for N = 2..6 at alpha = 0.1 and their unstable counts.

Each N-pulse of ``Faceting(alpha, kstar=5) + Perimeter(beta=5, L*)`` (Conventions and errata,
section 5; exists iff ``N alpha < 1`` for the quartic well) is built from one periodic orbit of
``alpha^2 psi'' - W'(psi) = nu1`` on a Fourier grid resolving its fronts; ``L*`` is the
perimeter target that makes it an exact equilibrium. With ``nu1 = 0`` and the
symmetric well each pulse spends half its period ``T`` at ``kappa ~ kstar``, so the
turning ``kstar T / 2 = 2 pi / N`` fixes ``L = N T = 4 pi / kstar`` for every N; ``L*``
grows with N (``beta (L - L*) = nu2 < 0``). The spectrum of J (normal gauge,
``<f, h> = int f h dsigma``) counts the unstable directions: ``2 N - 4`` of them
(measured here; the 2-pulse is stable), besides the 3 rigid motions in its kernel.

Run: ``python examples/ex02_npulse_family.py [FIGURE.png]``.
"""

from __future__ import annotations

import sys

from matplotlib.ticker import MaxNLocator

from qsa import plotting
from qsa.equilibria import npulse
from qsa.spectra import spectrum

ALPHA = 0.1
PULSES = (2, 3, 4, 5, 6)


def row(n_pulses, alpha=ALPHA):
    """Headline numbers of one N-pulse: size, L, L*, residuals, spectrum counts."""
    eq = npulse(n_pulses, alpha)
    s = spectrum(eq.energy, eq.curve)
    return {"n_pulses": n_pulses, "success": bool(eq.success and s.success),
            "N": eq.curve.N, "L": float(eq.params["L"]), "L_star": float(eq.params["L_star"]),
            "residual": float(eq.residual), "relative_residual": float(eq.relative_residual),
            "closure": float(eq.closure), "n_unstable": int(s.n_unstable),
            "n_kernel": int(s.n_kernel)}


def main():
    """``{"alpha": ..., "rows": [row(N) for N in 2..6]}``."""
    return {"alpha": ALPHA, "rows": [row(n) for n in PULSES]}


def figure(out):
    """Unstable count against the number of pulses, with the line ``2 N - 4``."""
    fig, ax = plotting.new_figure(size=(5.5, 3.8))
    n = [r["n_pulses"] for r in out["rows"]]
    ax.plot(n, [r["n_unstable"] for r in out["rows"]], "o", ms=7, label="qsa.spectra")
    ax.plot(n, [2 * k - 4 for k in n], "--", color="0.4", label="2N - 4")
    ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax.yaxis.set_major_locator(MaxNLocator(integer=True))
    ax.set_xlabel("pulses N")
    ax.set_ylabel("unstable eigenvalues")
    ax.set_title(f"N-pulse equilibria, alpha = {out['alpha']}")
    ax.legend(fontsize="small")
    return fig


if __name__ == "__main__":
    out = main()
    print(f"N-pulse equilibria, alpha={ALPHA}, kstar=5, beta=5")
    print(f"{'pulses':>6}{'nodes':>7}{'L':>10}{'L*':>10}{'max|Vn|':>10}{'rel.':>10}"
          f"{'unstable':>10}{'kernel':>8}")
    for r in out["rows"]:
        print(f"{r['n_pulses']:>6}{r['N']:>7}{r['L']:>10.5f}{r['L_star']:>10.5f}"
              f"{r['residual']:>10.1e}{r['relative_residual']:>10.1e}{r['n_unstable']:>10}"
              f"{r['n_kernel']:>8}")
    fig = figure(out)
    if len(sys.argv) > 1:
        plotting.save(fig, sys.argv[1])
