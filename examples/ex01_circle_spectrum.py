"""Circle spectrum against the closed form
=========================================

The spectrum of J on a faceting circle against its closed form (Conventions and errata,
section 4). The circle of radius R is an equilibrium of ``Faceting(alpha, kstar) + Perimeter(beta,
L*)`` for ``beta (2 pi R - L*) = W'(1/R)/R - W(1/R)``. For the normal mode ``cos k theta``
the eigenvalue of J (normal gauge, self-adjoint in ``<f, h> = int f h dsigma``) is ::

    lambda_k = -((k^2 - 1)^2 / R^4) (alpha^2 k^2 / R^2 + W''(1/R)) - delta_k0 2 pi beta / R,

double for k >= 2, zero for k = 1 (translations). This script measures

* the largest relative error of the ``Fourier(N)`` spectrum against all N exact
  eigenvalues (round-off level: the discretization is exact for the circle's
  band-limited modes), and
* the fitted convergence order of ``FiniteDifference(N)`` on the low modes
  ``k = 0, 2..5`` (2: the paper's second-order stencils).

Run: ``python examples/ex01_circle_spectrum.py [FIGURE.png]``.
"""

from __future__ import annotations

import sys

import numpy as np

from qsa import FiniteDifference, Fourier, plotting
from qsa.energies import DoubleWell
from qsa.equilibria import circle
from qsa.spectra import spectrum

R, ALPHA, KSTAR, BETA = 1.0, 0.1, 5.0, 5.0
FOURIER_SIZES = (17, 33)
FD_SIZES = (32, 64, 128)
FD_MODES = (0, 2, 3, 4, 5)


def exact_modes(kmax, R=R, alpha=ALPHA, kstar=KSTAR, beta=BETA):
    """``lambda_k`` for ``k = 0..kmax``, shape ``(kmax + 1,)`` (Conventions and errata, sec. 4)."""
    W2 = float(DoubleWell(kstar).d2W(1.0 / R))
    k = np.arange(kmax + 1)
    lam = -((k**2 - 1.0) ** 2 / R**4) * (alpha**2 * k**2 / R**2 + W2)
    lam[0] -= 2 * np.pi * beta / R
    return lam


def exact_spectrum(N):
    """All N eigenvalues of J on an odd ``Fourier(N)`` grid, sorted descending."""
    lam = exact_modes((N - 1) // 2)
    return np.sort(np.concatenate([lam, lam[1:]]))[::-1]


def fourier_error(N):
    """``(max relative error over the nonzero exact eigenvalues, spectrum)``."""
    eq = circle(R, ALPHA, grid=Fourier(N), beta=BETA, kstar=KSTAR)
    s = spectrum(eq.energy, eq.curve)
    exact = exact_spectrum(N)
    nz = exact != 0
    err = np.max(np.abs(s.eigenvalues[nz] - exact[nz]) / np.abs(exact[nz]))
    return float(err), s


def fd_error(N):
    """Largest relative error of the modes ``FD_MODES`` on ``FiniteDifference(N)``."""
    eq = circle(R, ALPHA, grid=FiniteDifference(N), beta=BETA, kstar=KSTAR)
    ev = spectrum(eq.energy, eq.curve).eigenvalues
    lam = exact_modes(max(FD_MODES))
    return float(max(np.min(np.abs(ev - lam[k])) / abs(lam[k]) for k in FD_MODES))


def main():
    """Headline numbers: Fourier errors, FD errors and fitted order, counts."""
    f_err, spectra_ = zip(*(fourier_error(N) for N in FOURIER_SIZES), strict=True)
    fd_errs = [fd_error(N) for N in FD_SIZES]
    order = -np.polyfit(np.log(FD_SIZES), np.log(fd_errs), 1)[0]
    last = spectra_[-1]
    return {
        "R": R, "alpha": ALPHA, "kstar": KSTAR, "beta": BETA,
        "lambda_0": float(exact_modes(0)[0]), "lambda_2": float(exact_modes(2)[2]),
        "fourier_sizes": list(FOURIER_SIZES), "fourier_max_rel_error": list(f_err),
        "fourier_n_unstable": int(last.n_unstable), "fourier_n_kernel": int(last.n_kernel),
        "fd_sizes": list(FD_SIZES), "fd_max_rel_error": fd_errs, "fd_order": float(order),
    }


def figure(out):
    """Fourier and FD errors against N (log-log, with the slope of order 2)."""
    fig, ax = plotting.new_figure(size=(5.5, 3.8))
    ax.loglog(out["fd_sizes"], out["fd_max_rel_error"], "o-", label="FiniteDifference(N)")
    ax.loglog(out["fourier_sizes"], out["fourier_max_rel_error"], "s-", label="Fourier(N)")
    n = np.asarray(out["fd_sizes"], float)
    ax.loglog(n, out["fd_max_rel_error"][0] * (n[0] / n) ** 2, ":", color="0.4",
              label="slope -2")
    ax.set_xlabel("N")
    ax.set_ylabel("max relative eigenvalue error")
    ax.set_title("faceting circle: J against the closed form")
    ax.legend(fontsize="small")
    return fig


if __name__ == "__main__":
    out = main()
    print(f"circle R={R}, alpha={ALPHA}, kstar={KSTAR}, beta={BETA}: "
          f"lambda_0={out['lambda_0']:.4f}, lambda_2={out['lambda_2']:.4f}")
    print(f"{'grid':<22}{'max rel. error':>16}")
    for N, e in zip(FOURIER_SIZES, out["fourier_max_rel_error"], strict=True):
        print(f"{f'Fourier({N}) all':<22}{e:>16.2e}")
    for N, e in zip(FD_SIZES, out["fd_max_rel_error"], strict=True):
        print(f"{f'FD({N}) k=0,2..5':<22}{e:>16.2e}")
    print(f"FD fitted order: {out['fd_order']:.2f} (theory 2); unstable: "
          f"{out['fourier_n_unstable']}, kernel: {out['fourier_n_kernel']} (translations)")
    fig = figure(out)
    if len(sys.argv) > 1:
        plotting.save(fig, sys.argv[1])
