"""Closed-form circle spectra (Conventions and errata, section 4) shared by the spectra tests."""

import numpy as np

from qsa import Curve
from qsa.energies import CanhamHelfrich, DoubleWell, Perimeter


def faceting_circle_eigenvalues(R, alpha, kstar, beta, kmax):
    """Exact eigenvalues of J on a faceting circle, modes k = 0..kmax (k >= 1 doubled).

    lambda_k = -((k^2 - 1)^2 / R^4)(alpha^2 k^2 / R^2 + W''(1/R)) - delta_k0 2 pi beta / R.
    """
    W2 = float(DoubleWell(kstar).d2W(1.0 / R))
    k = np.arange(kmax + 1)
    lam = -((k**2 - 1.0) ** 2 / R**4) * (alpha**2 * k**2 / R**2 + W2)
    lam[0] -= 2 * np.pi * beta / R
    return np.sort(np.concatenate([lam, lam[1:]]))[::-1], lam


def helfrich_circle(R, eps, beta, grid):
    """Circle equilibrium of CanhamHelfrich(eps) + Perimeter(beta, L*).

    beta (2 pi R - L*) = eps / (2 R^2) (Conventions and errata, section 4).
    """
    L_star = 2 * np.pi * R - eps / (2 * R**2 * beta)
    energy = CanhamHelfrich(eps) + Perimeter(beta, L_star)
    return energy, Curve.circle(R, grid)


def helfrich_circle_eigenvalues(R, eps, beta, kmax):
    k = np.arange(kmax + 1)
    lam = -eps * (k**2 - 1.0) ** 2 / R**4
    lam[0] -= 2 * np.pi * beta / R
    return np.sort(np.concatenate([lam, lam[1:]]))[::-1], lam
