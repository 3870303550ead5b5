"""Folded-state analysis (qsa.paper.folded): polish, spectrum with its kernel, DAE rate.

The state is the reference CHA equilibrium (appendix parameters, l* = 0.5) sampled at
160 nodes, as a flow's final nodes would be.
"""

import json
from pathlib import Path

import numpy as np
import pytest

from qsa import Curve, Fourier
from qsa.paper.folded import folded_equilibrium

REF = json.loads((Path(__file__).parents[1] / "reference"
                  / "cha_trillium_equilibrium.json").read_text())

RHO = 1.5


def nodes(N=160, noise=0.0):
    c = Curve(REF["kappa"], REF["L"], Fourier(REF["N"]), REF["theta0"], tuple(REF["origin"]))
    x, y = c.on_grid(Fourier(N + 1)).positions()
    x, y = x[:N], y[:N]          # N nodes, not quite at equal spacing: a flow's last state
    if noise:
        nx, ny = c.on_grid(Fourier(N + 1)).normal()
        bump = noise * np.cos(5 * np.arange(N) * 2 * np.pi / N)
        x, y = x + bump * nx[:N], y + bump * ny[:N]
    return x, y


def analyse(x, y, **options):
    return folded_equilibrium(x, y, eps=REF["eps"], beta=REF["beta"], rho=RHO,
                              L0=REF["L_star"] / RHO, A0=REF["A0"], l_star=REF["l_star"],
                              a=REF["a"], **options)


def test_polish_spectrum_and_flow_rate():
    fe = analyse(*nodes(noise=2e-3))
    assert fe.polished.success and fe.relative_residual <= 1e-9
    assert fe.N == 161
    sp = fe.spectrum
    assert sp.n_kernel == 3                       # the rigid motions, recognised
    assert np.all(np.abs(sp.eigenvalues[sp.is_kernel]) <= sp.kernel_tol)
    assert fe.n_unstable == int(np.sum(sp.eigenvalues[~sp.is_kernel] > 0))
    assert not np.any(sp.is_kernel[fe.slowest])
    # the DAE decays along the slowest decaying mode at its eigenvalue, within 1%
    assert fe.rate["success"]
    assert fe.rate["eigenvalue"] == max(v for v in sp.eigenvalues[~sp.is_kernel] if v < 0)
    assert fe.rate["relative_error"] <= 0.01
    s = json.loads(json.dumps(fe.summary()))
    assert s["n_kernel"] == 3 and s["rate"]["relative_error"] <= 0.01
    assert s["params"]["L_star"] == pytest.approx(REF["L_star"], rel=1e-14)


def test_failed_polish_reported_without_spectrum():
    fe = analyse(*nodes(noise=2e-3), maxiter=1, rate_check=False)
    assert not fe.polished.success and fe.spectrum is None and not fe.success
    s = json.loads(json.dumps(fe.summary()))
    assert s["polish_success"] is False and "n_unstable" not in s
    assert np.all(np.isfinite(fe.curve.kappa))


def test_bad_nodes():
    with pytest.raises(ValueError, match="x, y"):
        analyse(np.zeros(10), np.zeros(11))
