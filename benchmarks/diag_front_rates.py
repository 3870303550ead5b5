"""Where the short-facet rate error of the front ODE comes from (diagnosis table).

Runs the DAE faceting flow (:func:`qsa.flows.solve_flow`, :class:`FacetingFlow`)
from the splice of a scenario of ``qsa reproduce fronts``, and at a few fractions
of its collision time ``t_c``:

* fits splice positions ``p`` whose ``kstar/2`` crossings equal the DAE's
  (fixed-point iteration on :meth:`FrontODE.crossings`);
* compares the closing rate of the shortest gap (facet or corner) measured on the
  DAE (local quadratic fit of the tracked crossings) with the ODE's at the same
  ``p`` (``d crossings / dp . F(p)``): ``eps_F``;
* projects the *DAE state's* own residual ``R[kappa] = -alpha^2 kappa'' + W'(kappa)``
  on the splice tangent space (same metric and constraints as ``F``): ``eps_R``
  -- if ``eps_R`` is small while ``eps_F`` is not, the error is the offset of
  the state from the splice (the true slow manifold), not the metric;
* the energy difference ``E(DAE) - E(splice)`` and where ``kappa_DAE - psi_N(p)``
  lives: within 3 front widths of the fronts bounding the closing gap, of the other
  fronts, or on the facets (where the cutoff acts);
* ``tail/k*``: the splice at the centre of the closing gap / kstar; ``dk_mid``:
  the DAE's excess over it there (relative); ``dN_mid``: the same predicted by one
  Newton step from the splice (:meth:`FrontODE.slow_correction`); ``eps_N``: the
  rate error of ``FrontODE(correction="newton")``.

``eps_*`` > 0: the ODE closes the gap faster than the DAE. ``-v`` adds per-front
norms of ``kappa_DAE - psi_N`` and the gap-centre values.

Run: ``OPENBLAS_NUM_THREADS=1 python benchmarks/diag_front_rates.py [scenario] [N] [beta] [-v]``
(default ``short-facet 1200 5``; ``beta = 500`` isolates the fixed-length
reduction from the perimeter mode; a few seconds at N = 1200).
"""

from __future__ import annotations

import sys

import numpy as np

from qsa import FiniteDifference
from qsa.flows import FacetingFlow, solve_flow
from qsa.paper import SCENARIOS, scenario_splice
from qsa.reduction.fronts import detect_fronts, track_flow
from qsa.reduction.manifold import closure, energy, energy_gradient
from qsa.reduction.ode import FrontODE


def _wrap(x, L):
    return (x + 0.5 * L) % L - 0.5 * L


def _aligned_crossings(ode, p, cut):
    """Crossings of the splice at ``p``, ordered like ``p`` (nearest, cyclic)."""
    c = ode.crossings(p, cut)
    L = ode.length
    d = _wrap(c[None, :] - p[:, None], L)
    j = np.argmin(np.abs(d), axis=1)
    return p + d[np.arange(p.size), j]


def fit_positions(ode, c, cut, iters=8):
    """Splice positions whose crossings are ``c`` (same order)."""
    p = c.copy()
    for _ in range(iters):
        p = p + (c - _aligned_crossings(ode, p, cut))
    return p


def _interp_periodic(values, length, s):
    """Trigonometric interpolation of equispaced periodic samples at ``s``."""
    n = values.size
    coef = np.fft.rfft(values) / n
    k = np.arange(coef.size)
    if n % 2 == 0:
        coef[-1] *= 0.5
    ph = np.exp(2j * np.pi * np.outer(s / length, k))
    out = ph @ coef
    return 2 * out.real - coef[0].real


def _spectral_derivs(f, length):
    n = f.size
    k = 2j * np.pi * np.fft.fftfreq(n, d=length / n)
    F = np.fft.fft(f)
    return np.fft.ifft(k * F).real, np.fft.ifft(k * k * F).real


def projected_velocity(ode, p, cut, R):
    """Saddle-point solve of the reduced flow with the force ``int R dpsi/dp_j``."""
    f = ode.fields(p, cut)
    phi, w = ode.normal_velocities(p, cut)
    G = phi.T @ (w[:, None] * phi)
    dE = energy_gradient(f, ode.front.alpha, ode.front.well, R)
    _, J = closure(f)
    n = p.size
    A = np.vstack([J, np.ones((1, n)) / np.sqrt(n)])
    K = np.block([[G, A.T], [A, np.zeros((4, 4))]])
    return np.linalg.solve(K, np.concatenate([-dE, np.zeros(4)]))[:n]


def diagnose(scenario="short-facet", N=1200, beta=5.0, alpha=0.1, kstar=5.0,
             fractions=(0.1, 0.3, 0.5, 0.7, 0.85, 0.95), verbose=False):
    sc = SCENARIOS[scenario]
    eq = scenario_splice(sc, alpha, kstar, grid=FiniteDifference(N))
    p0 = np.array(eq.params["positions"])
    L = eq.params["L"]
    ode = FrontODE(alpha, kstar, L)
    from qsa.equilibria import default_cutoff

    cut = default_cutoff(p0, L)
    nf = p0.size

    def stop(t, y, system):
        return detect_fronts(system.curvature(y), kstar, system.length(y)).n < nf

    res = solve_flow(FacetingFlow(alpha, kstar, beta, L), eq.curve.positions(), sc.t_final,
                     N=N, tol=1e-6, method="bdf2", callback=stop, progress=False)
    tr = track_flow(res, kstar)
    tc = tr.first_collision.time
    ok = np.all(np.isfinite(tr.positions), axis=1)
    t, P = res.t[ok], tr.positions[ok]
    P = P[0] + _wrap(P - P[0], L)
    # order the DAE tracks like p0
    c0 = _aligned_crossings(ode, p0, cut)
    order = [int(np.argmin(np.abs(_wrap(P[0] - c, L)))) for c in c0]
    P = P[:, order]
    W = ode.front.well
    lam_w = 3.0 * ode.front.width
    print(f"{scenario}: N={N} beta={beta} alpha={alpha} kstar={kstar}  DAE t_c={tc:.5f}")
    hdr = (" t/tc   gap    rate_DAE    eps_F    eps_R   |C(p)|   E_DAE-E_spl  "
           "|dk|_gap  |dk|_other |dk|_facet  tail/k*  dk_mid   dN_mid eps/tail  eps_N  max|dk| at")
    print(hdr)
    rows = []
    for fr in fractions:
        i = int(np.argmin(np.abs(t - fr * tc)))
        lo, hi = max(i - 3, 0), min(i + 4, t.size)
        y = res.states[i]
        Ld = res.system.length(y)
        c = P[i] * (L / Ld)  # the DAE's crossings, stretched to the splice length L
        # local quadratic fit for the DAE crossing velocities
        tt = t[lo:hi] - t[i]
        vd = np.array([np.polyfit(tt, P[lo:hi, j], 2)[1] for j in range(nf)])
        p = fit_positions(ode, c, cut)
        F = ode.velocity(p, cut)
        h = 1e-3 * ode.front.width / max(np.max(np.abs(F)), 1e-300)
        vo = (_aligned_crossings(ode, p + h * F, cut)
              - _aligned_crossings(ode, p - h * F, cut)) / (2 * h)
        gaps = np.diff(np.append(c, c[0] + L))
        g = int(np.argmin(gaps))
        j2 = (g + 1) % nf
        rate_d = vd[j2] - vd[g]
        rate_o = vo[j2] - vo[g]
        # DAE kappa on the ODE grid, in the splice's arc length (DAE base node drift
        # removed by matching the crossings; length rescaled to L)
        kap = res.system.curvature(y)
        cd = detect_fronts(kap, kstar, Ld).positions
        shift = np.mean(_wrap(np.sort(cd * L / Ld)[np.argmin(np.abs(_wrap(
            np.sort(cd * L / Ld)[:, None] - c[None, :], L)), axis=0)] - c, L))
        s = ode.sigma
        kd = _interp_periodic(kap, L, (s + shift) % L)
        d1, d2 = _spectral_derivs(kd, L)
        R = -(alpha**2) * d2 + W.dW(kd)
        vR = projected_velocity(ode, p, cut, R)
        vRc = (_aligned_crossings(ode, p + h * vR, cut)
               - _aligned_crossings(ode, p - h * vR, cut)) / (2 * h)
        rate_r = vRc[j2] - vRc[g]
        f = ode.fields(p, cut)
        w = f.weights
        E_d = float((0.5 * alpha**2 * d1**2 + W.W(kd)) @ w)
        E_s = energy(f, alpha, W)
        dk = kd - f.psi
        dist = np.abs(_wrap(s[:, None] - c[None, :], L))
        near = dist < lam_w
        near_gap = near[:, [g, j2]].any(axis=1)
        near_other = near.any(axis=1) & ~near_gap
        facet = ~near.any(axis=1)

        def nrm(mask, dk=dk, w=w):
            return float(np.sqrt((dk[mask] ** 2) @ w[mask]))

        C, _ = ode.constraints(p, cut)
        k = int(np.argmax(np.abs(dk)))
        jn = int(np.argmin(dist[k]))
        where = f"front {jn} ({_wrap(s[k] - c[jn], L) / ode.front.width:+.1f} w)" \
            if dist[k, jn] < 2 * lam_w else "facet"
        delta, RN = ode.slow_correction(p, cut)
        vN = projected_velocity(ode, p, cut, RN)
        vNc = (_aligned_crossings(ode, p + h * vN, cut)
               - _aligned_crossings(ode, p - h * vN, cut)) / (2 * h)
        eps_n = (vNc[j2] - vNc[g]) / rate_d - 1
        mids = []
        for j in range(nf):  # centre fifth of every gap: DAE kappa and splice psi
            a = _wrap(s - c[j], L) % L
            m = (a > 0.4 * gaps[j]) & (a < 0.6 * gaps[j])
            mids.append((float(np.mean(kd[m])), float(np.mean(f.psi[m])),
                         float(np.mean(delta[m]))))
        eps_f = rate_o / rate_d - 1
        tail = mids[g][1] / kstar
        row = (t[i] / tc, gaps[g], rate_d, eps_f, rate_r / rate_d - 1, np.linalg.norm(C),
               E_d - E_s, nrm(near_gap), nrm(near_other), nrm(facet), tail,
               mids[g][0] / mids[g][1] - 1, mids[g][2] / mids[g][1], eps_f / tail, eps_n)
        rows.append(row)
        print("{:5.2f} {:6.3f} {:+10.4e} {:+7.2%} {:+7.2%} {:8.1e} {:+11.3e} {:9.2e}"
              " {:9.2e} {:9.2e} {:7.4f} {:+7.2%} {:+7.2%} {:+6.2f} {:+7.2%}  {}"
              .format(*row, where))
        per = [nrm(near[:, j]) for j in range(nf)]
        if verbose:
            print("      gap centres kappa_DAE/psi_splice: " + " ".join(
                f"{a:.2e}/{b:.2e}" for a, b in mids))
        if verbose:
            print("      Ld/L-1={:+.1e} shift={:+.1e} gap={} |dk| per front: {}".format(
                Ld / L - 1, shift, g, " ".join(f"{v:.1e}" for v in per)))
    return rows


if __name__ == "__main__":
    verbose = "-v" in sys.argv[1:]
    args = [a for a in sys.argv[1:] if a != "-v"]
    diagnose(args[0] if args else "short-facet", int(args[1]) if len(args) > 1 else 1200,
             float(args[2]) if len(args) > 2 else 5.0, verbose=verbose)
