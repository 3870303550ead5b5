"""The pipeline on built-in defaults: what ``qsa demo`` runs.

Each stage returns a JSON-ready dict of its headline numbers; :func:`run_demo`
runs them in order, draws the figures, and writes ``summary.json`` to the
output folder. The stages are also the quickest tour of the API.
"""

from __future__ import annotations

import json
import time
import warnings
from pathlib import Path

import numpy as np

from qsa import Curve, FiniteDifference, Fourier, equilibria, geometry, plotting, spectra
from qsa.energies import CanhamHelfrich, DoubleWell, Faceting, Perimeter
from qsa.studies import mode_decay

__all__ = ["run_demo", "stage_curves", "stage_npulse", "stage_spectrum", "stage_splice",
           "stage_flow"]

ALPHA, KSTAR, BETA = 0.1, 5.0, 5.0


def _derivative_checks(E, c, rng):
    """Relative errors of the gradient and Hessian against central differences."""
    w = np.concatenate([c.dsigma, c.dsigma])
    U1 = rng.standard_normal(2 * c.N)
    d = 1e-6 * np.linalg.norm(c.U) / np.linalg.norm(U1)
    f = lambda t: E.energy(c.with_U(c.U + t * U1))
    num1 = (f(d) - f(-d)) / (2 * d)
    grad = E.gradient(c)
    ana1 = grad @ (U1 * w)
    d2 = 1e2 * d
    num2 = (f(d2) - 2 * f(0) + f(-d2)) / d2**2
    ana2 = (E.hessian(c) @ U1) @ (U1 * w)
    return {"gradient_rel_error": abs(num1 - ana1) / max(abs(ana1), 1e-300),
            "hessian_rel_error": abs(num2 - ana2) / max(abs(ana2), 1e-300)}


def stage_curves(rng=None) -> dict:
    """A circle and a trillium: closure, kernels, energies, V^n, derivative checks."""
    rng = rng or np.random.default_rng(0)
    out = {}
    grid = Fourier(257)
    R = 0.8
    k0 = 1 / R
    well = DoubleWell(KSTAR)
    L_star = 2 * np.pi * R - (k0 * well.dW(k0) - well.W(k0)) / BETA
    circle = Curve.circle(R, grid)
    E_circ = Faceting(ALPHA, KSTAR) + Perimeter(BETA, L_star)
    out["circle"] = {
        "R": R, "L_star_equilibrium": L_star,
        "closure": float(np.linalg.norm(circle.closure())),
        "max_abs_normal_velocity": float(np.abs(E_circ.normal_velocity(circle)).max()),
        "energy": E_circ.energy(circle),
    }
    trillium = Curve.polar(lambda t: 1 + 0.2 * np.cos(3 * t), grid)
    energies = {"faceting": Faceting(ALPHA, KSTAR) + Perimeter(BETA, 6.0),
                "canham_helfrich": CanhamHelfrich(0.1) + Perimeter(1.0, 6.0)}
    M, Md = geometry.M(trillium), geometry.M_adjoint(trillium)
    t = {
        "N": grid.N, "length": trillium.length(),
        "closure": float(np.linalg.norm(trillium.closure())),
        "max_M_rigid": float(max(np.abs(M @ r).max() for r in geometry.rigid_motions(trillium))),
        "max_Mdagger_Psi": float(max(np.abs(Md @ p).max()
                                     for p in geometry.constraint_gradients(trillium))),
    }
    for name, E in energies.items():
        V = E.normal_velocity(trillium)
        t[name] = {"energy": E.energy(trillium), "max_abs_normal_velocity": float(np.abs(V).max()),
                   "dissipation_rate": float(-np.sum(V**2 * trillium.dsigma)),
                   **_derivative_checks(E, trillium, rng)}
    # the same curve on finite differences (sparse operators)
    fd = Curve.polar(lambda t: 1 + 0.2 * np.cos(3 * t), FiniteDifference(512))
    t["fd512_max_M_rigid"] = float(max(np.abs(geometry.M(fd) @ r).max()
                                       for r in geometry.rigid_motions(fd)))
    out["trillium"] = t
    out["_curves"] = {"circle": circle, "trillium": trillium}
    return out


def stage_npulse() -> dict:
    """A 3-pulse faceted equilibrium (equilateral triangle with rounded corners)."""
    eq = equilibria.npulse(3, ALPHA, kstar=KSTAR, beta=BETA)
    out = eq.summary()
    out["_equilibrium"] = eq
    return out


def stage_spectrum(eq) -> dict:
    """Spectrum of the normal-gauge linearization J at the 3-pulse, with its kernel report."""
    sp = spectra.spectrum(eq.energy, eq.curve)
    out = sp.summary(max_eigenvalues=8)
    out["_spectrum"] = sp
    return out


def stage_splice() -> dict:
    """A heteroclinic splice (rounded triangle, unequal facets) and its small eigenvalues.

    The corner angles 121, 109.5 and 129.5 degrees are those of a triangle with
    sides 0.9, 1.0, 1.1, so the closing facets are close to these (the summary
    reports the ones used). The 2N - 1 = 5 small eigenvalues (front motions on the
    splice manifold that keep the closure) are separated from the O(1) negative
    ones: the spectral dichotomy behind the front-position ODE.
    """
    requested = [0.9, 1.0, 1.1]
    eq = equilibria.splice_polygon(np.radians([121.0, 109.5, 129.5]), requested, ALPHA,
                                   kstar=KSTAR, grid=255)
    with warnings.catch_warnings():  # a splice is a quasi-equilibrium: said in the summary
        warnings.simplefilter("ignore", spectra.NotEquilibriumWarning)
        sp = spectra.spectrum(eq.energy, eq.curve, reject_spurious=False)
    lam = sp.eigenvalues
    n_small = sp.n_small
    out = {"N": eq.curve.N, "alpha": ALPHA, "angles_degrees": [121.0, 109.5, 129.5],
           "facets": [float(f) for f in eq.params["facets"]], "facets_requested": requested,
           "closure": eq.closure, "residual": eq.residual, "d_min": eq.params["d_min"],
           "n_small": n_small, "n_small_expected": 2 * 3 - 1,
           "small_eigenvalues": lam[:n_small].tolist(),
           "first_fast_eigenvalue": float(lam[n_small]) if n_small < len(lam) else None,
           "separation": float(sp.gap_ratio),
           "message": sp.message}
    out["_splice"] = eq
    return out


def stage_flow(eq) -> dict:
    """A short DAE flow from the perturbed 3-pulse: decay rate against J's eigenvalue."""
    return mode_decay(eq)


def _decay_figure(plotting, info, res, V):
    fig, ax = plotting.new_figure()
    ax.semilogy(res.t, V, "o", label="DAE flow: RMS $V^n$")
    ax.semilogy(res.t, V[-1] * np.exp(info["eigenvalue"] * (res.t - res.t[-1])), "-",
                label=rf"$e^{{\lambda t}}$, $\lambda$ = {info['eigenvalue']:.4g}")
    ax.set_xlabel("t")
    ax.set_ylabel("RMS normal velocity")
    ax.legend()
    return fig


def run_demo(outdir="qsa-demo", plots=True, verbose=True) -> dict:
    """Run the pipeline on built-in defaults; write figures and ``summary.json`` to ``outdir``.

    Returns
    -------
    dict
        The summary (also written as JSON).
    """
    outdir = Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    say = print if verbose else (lambda *a, **k: None)
    summary = {"qsa_demo": {"alpha": ALPHA, "kstar": KSTAR, "beta": BETA}}
    timings = {}
    objects = {}
    stages = [("curves", stage_curves), ("npulse", stage_npulse),
              ("spectrum", lambda: stage_spectrum(objects["_equilibrium"])),
              ("splice", stage_splice),
              ("flow", lambda: stage_flow(objects["_equilibrium"]))]
    for name, stage in stages:
        t0 = time.perf_counter()
        res = stage()
        timings[name] = time.perf_counter() - t0
        objects.update({k: v for k, v in res.items() if k.startswith("_")})
        summary[name] = {k: v for k, v in res.items() if not k.startswith("_")}
        say(f"[qsa demo] {name:<8} done in {timings[name]:.2f} s")
    summary["timings_s"] = timings
    if plots:
        figs = {
            "trillium.png": plotting.plot_curve_and_curvature(
                objects["_curves"]["trillium"], title="trillium r = 1 + 0.2 cos 3θ"),
            "npulse3.png": plotting.plot_curve_and_curvature(
                objects["_equilibrium"].curve, title="3-pulse faceted equilibrium, α = 0.1"),
            "spectrum_npulse3.png": plotting.plot_spectrum(
                objects["_spectrum"], title="spectrum of J at the 3-pulse").figure,
            "splice.png": plotting.plot_curve_and_curvature(
                objects["_splice"].curve, title="heteroclinic splice, facets "
                + ", ".join(f"{f:.3g}" for f in summary["splice"]["facets"])),
            "flow_decay.png": _decay_figure(plotting, summary["flow"], *objects["_flow"]),
        }
        for fname, fig in figs.items():
            plotting.save(fig, outdir / fname)
        summary["figures"] = sorted(figs)
    with open(outdir / "summary.json", "w") as fh:
        json.dump(summary, fh, indent=2, default=float)
    return summary
