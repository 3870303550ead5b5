"""Folded equilibria of the CHA flow (f:fold): polish, spectrum, stability, relaxation rate.

:func:`folded_equilibrium` takes the final nodes of a CHA flow (a :class:`CHARun`
of :func:`qsa.paper.run_cha` / :func:`qsa.paper.run_folding`, or any nodes and
their CHA parameters), polishes them by Newton's method on the flow's own
Fourier grid (``Fourier(N)``, ``N`` made odd; the energy
``CanhamHelfrich(eps) + Perimeter(beta, rho L0) + Adhesion(A0, l*, a)``),
computes the spectrum of the linearization ``J`` (normal gauge) with its kernel
(the rigid motions) recognised, counts the unstable modes outside the kernel, and
checks the spectrum against the DAE: the CHA flow started from the polished state
displaced along its slowest decaying mode relaxes at a rate measured from the
projection of ``V^n`` on that mode's eigenspace, to compare with the eigenvalue.

The grid is refined (``Fourier(2N - 1)``) while it does not resolve the state: while
``max|V^n|`` is above ``resolve`` of its scale, or the rigid motions' eigenvalues are
above ``kernel_resolve`` of the slowest other ``|lambda|``; a state still unresolved at
``max_N`` is flagged (``resolved = False``, :class:`UnderResolvedWarning`).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING

import numpy as np
from scipy.optimize import minimize_scalar

from qsa import Curve, Fourier
from qsa._checks import real_number
from qsa.energies import Adhesion, CanhamHelfrich, Perimeter
from qsa.equilibria import polish
from qsa.flows import CHA, solve_flow
from qsa.flows.analysis import paired_sheets
from qsa.spectra import spectrum
from qsa.spectra.kernel import rigid_normal_basis

if TYPE_CHECKING:
    from qsa.energies.base import Energy
    from qsa.equilibria.newton import PolishResult
    from qsa.spectra.result import Spectrum

__all__ = ["FoldedEquilibrium", "UnderResolvedWarning", "folded_energy", "folded_equilibrium",
           "folded_equilibria", "kernel_resolution", "relaxation_rate"]


class UnderResolvedWarning(UserWarning):
    """The largest grid allowed does not resolve a folded state (see ``resolved``).

    Issued by :func:`folded_equilibrium` when the refinements stop at ``max_N`` (or a
    refined polish fails) with ``max|V^n|`` or the rigid motions' eigenvalues above
    their tests: the slow eigenvalues on that grid are not to be trusted.
    """


def folded_energy(eps, beta, L_star, A0, l_star, a):
    """``CanhamHelfrich(eps) + Perimeter(beta, L_star) + Adhesion(A0, l_star, a)``."""
    return CanhamHelfrich(eps) + Perimeter(beta, L_star) + Adhesion(A0, l_star, a)


@dataclass
class FoldedEquilibrium:
    """A polished folded CHA state with its spectrum, stability and flow-rate check.

    Attributes
    ----------
    name : str
    params : dict
        ``eps, beta, rho, L0, L_star, A0, l_star, a`` (``L_star = rho L0``).
    N : int
        Nodes of the polished state (odd: the flow's ``N`` rounded up, then refined
        while the grid does not resolve the state; see ``refinements``).
    energy : Energy
    guess : Curve
        The flow's final state on ``Fourier(N)``.
    polished : PolishResult
    spectrum : Spectrum or None
        ``None`` when the polish failed.
    n_slow : int
        Number of slowest non-kernel eigenvalues reported.
    rate : dict or None
        :func:`relaxation_rate` (without its ``"_flow"`` entry), ``None`` when not run.
    flow : tuple or None
        ``(FlowResult, times, projected amplitude)`` of the rate check.
    refinements : list of dict
        Spectral refinements of the polish (``N, success, relative_V, energy_change,
        n_newton`` of the finer grid, and ``reason``: ``"residual"`` or ``"kernel"``,
        the test the coarser grid failed; for ``"kernel"`` also that grid's
        ``kernel_ratio, kernel_eigenvalues, slowest``, see :func:`kernel_resolution`;
        see ``resolve`` and ``kernel_resolve`` of :func:`folded_equilibrium`).
    resolved : bool or None
        Whether the grid ``N`` resolves the state: ``max|V^n|`` within ``resolve`` of
        its scale and the rigid motions' eigenvalues within ``kernel_resolve`` of the
        slowest other ``|lambda|`` (``None``: neither test was run, e.g. a failed polish).
    unresolved_reason : str or None
        Why not, and why the grid was not refined further (``max_N``, a failed polish).
    """

    name: str
    params: dict
    N: int
    energy: Energy
    guess: Curve
    polished: PolishResult
    spectrum: Spectrum | None = None
    n_slow: int = 6
    rate: dict | None = None
    flow: tuple | None = field(default=None, repr=False)
    refinements: list = field(default_factory=list)
    resolved: bool | None = None
    unresolved_reason: str | None = None

    @property
    def curve(self):
        """The polished curve (the last iterate when the polish failed)."""
        return self.polished.curve

    @property
    def relative_residual(self) -> float:
        """Last relative residual of the Newton polish."""
        h = self.polished.history
        return float(h[-1]) if len(h) else float("inf")

    @property
    def slowest(self) -> np.ndarray:
        """Indices (into the spectrum) of the ``n_slow`` non-kernel eigenvalues nearest 0.

        Empty without a spectrum (the polish failed).
        """
        sp = self.spectrum
        if sp is None:
            return np.zeros(0, dtype=int)
        idx = np.flatnonzero(~sp.is_kernel)
        return idx[np.argsort(np.abs(sp.eigenvalues[idx]))][: self.n_slow]

    @property
    def separation_target(self) -> float:
        """The sheets' optimal separation ``d* = l* sqrt(a^2 + 1/2)``."""
        return self.params["l_star"] * float(np.hypot(self.params["a"], np.sqrt(0.5)))

    def sheets(self):
        """The polished curve's paired sheets against ``d*``."""
        return paired_sheets(*self.curve.positions(), self.separation_target)

    @property
    def n_unstable(self) -> int | None:
        """Positive eigenvalues of ``J`` outside the kernel (``None`` without a spectrum)."""
        return None if self.spectrum is None else int(self.spectrum.n_unstable)

    @property
    def stable(self) -> bool | None:
        """No unstable mode besides the kernel."""
        return None if self.spectrum is None else self.n_unstable == 0

    @property
    def success(self) -> bool:
        """Polished, spectrum computed, not flagged unresolved and (if run) the rate within 1%."""
        ok = (bool(self.polished.success) and self.spectrum is not None
              and self.resolved is not False)
        if self.rate is not None:
            ok = ok and self.rate["success"] and self.rate["relative_error"] <= 0.01
        return ok

    def summary(self) -> dict:
        """JSON-able summary."""
        out = {"name": self.name, "N": self.N, "params": dict(self.params),
               "polish_success": bool(self.polished.success),
               "relative_residual": self.relative_residual,
               "residual": float(self.polished.residual),
               "relative_V": float(self.polished.residual / self.polished.residual_scale),
               "refinements": [dict(r) for r in self.refinements],
               "closure": float(self.polished.closure),
               "n_newton": int(self.polished.n_newton),
               "length": float(self.curve.length()),
               "energy": float(self.energy.energy(self.curve)),
               "sheets": self.sheets().to_dict(),
               "resolved": self.resolved, "unresolved_reason": self.unresolved_reason,
               "success": self.success}
        sp = self.spectrum
        if sp is not None:
            kr = kernel_resolution(sp)
            out["kernel_ratio"] = None if kr is None else kr["ratio"]
            lam = sp.eigenvalues
            out.update(n_unstable=self.n_unstable, stable=self.stable,
                       n_kernel=int(sp.n_kernel), kernel_tol=float(sp.kernel_tol),
                       kernel_eigenvalues=[float(v) for v in lam[sp.is_kernel]],
                       slowest_eigenvalues=[float(lam[i]) for i in self.slowest],
                       unstable_eigenvalues=[float(v) for v in lam[sp._unstable_mask()]],
                       spectrum_message=sp.message)
        if self.rate is not None:
            out["rate"] = dict(self.rate)
        return out


def relaxation_rate(fe: FoldedEquilibrium, mode=None, amplitude=1e-3, efolds=3.0, tol=1e-7,
                    snapshots=25, max_time=None, richardson=True, symmetric=True):
    """Perturb a polished folded state along an eigenmode; fit the CHA flow's decay rate.

    The nodes are displaced normally by ``amplitude`` (max norm) times the eigenvector
    ``phi`` (normal gauge); the CHA DAE (finite differences, BDF2) runs for ``efolds``
    e-folding times (at most ``max_time``), with ``rho`` rescaled so that its length
    target ``rho L0`` is the equilibrium's ``L_star`` (the flow binds ``L0`` to its
    initial length).

    Three effects of the finite-difference DAE are removed before the fit:

    * it has no exact equilibrium (the rigid-motion identities of the two-point
      ``V^n`` hold only to the grid's order), so from the Fourier equilibrium it drifts
      rigidly and relaxes to a nearby state of its own. With ``symmetric`` it runs from
      ``+amplitude`` and from ``-amplitude`` and half the difference of the two ``V^n``
      is taken: what the runs share cancels, and so does the quadratic part of the
      response;
    * the rigid drift is carried by normal velocities, so the nodes slide along the
      shape (the parametrization's origin moves by a fraction of a node per unit time,
      at slightly different speeds in the two runs), and comparing ``V^n`` node by node
      would mix in the drift's gradient times that difference, which does not decay.
      Each snapshot is registered on the equilibrium -- the parameter shift (Fourier
      interpolation) and rigid motion that best match its nodes to the equilibrium's
      -- and its ``V^n`` shifted back before the difference;
    * the difference is projected (least squares) onto the eigenspace of the eigenvalue
      (eigenvectors within ``1e-6`` relative, with the rigid motions' normal
      velocities); its other components decay faster, so the fit (the slope of the log
      of the projection's norm) starts after one e-folding time. ``window`` is the
      spread of the rates fitted on the two halves of that window.

    The DAE's rate differs from the eigenvalue of the (Fourier) equilibrium by its
    finite-difference error, ``O(h^2)``. With ``richardson`` the flow runs on
    ``N1 = fe.N`` and ``N2 = 2 N1 - 1`` nodes (the state and the eigenspace resampled
    spectrally) and the rate is extrapolated, ``r = (q^2 r2 - r1) / (q^2 - 1)`` with
    ``q = N2 / N1``; ``rate_error`` is ``|r - r2|`` plus the finer grid's window
    spread.

    Parameters
    ----------
    fe : FoldedEquilibrium
        With a spectrum.
    mode : int, optional
        Index into the spectrum; default the slowest decaying non-kernel mode.
    richardson : bool
        Extrapolate from two grids (default) or measure on ``fe.N`` nodes only.
    symmetric : bool
        Difference of the runs from ``+amplitude`` and ``-amplitude`` (default), or the
        run from ``+amplitude`` alone.

    Returns
    -------
    dict
        ``mode, eigenvalue, multiplicity, measured_rate, relative_error, rate_error,
        rates`` (per grid: ``N, rate, window, n_steps``)``, t_final, success, n_steps``,
        and ``"_flow"`` = (FlowResult, times, projected amplitude) of the finest run.
    """

    sp = fe.spectrum
    if sp is None:
        raise ValueError("fe: no spectrum (the polish failed); polish before the rate check")
    lam = sp.eigenvalues
    if mode is None:
        decaying = np.flatnonzero((lam < 0) & ~sp.is_kernel)
        if decaying.size == 0:
            raise ValueError("fe: no decaying mode outside the kernel")
        i = int(decaying[np.argmax(lam[decaying])])
    else:
        i = int(mode)
    lam1 = float(lam[i])
    if not lam1 < 0:
        raise ValueError(f"mode: eigenvalue {lam1:.3g} of mode {i} is >= 0, it does not decay")
    if not efolds > 1:
        raise ValueError(f"efolds: need more than one e-folding time to fit after the "
                         f"first, got {efolds}")
    same = np.flatnonzero((np.abs(lam - lam1) <= 1e-6 * abs(lam1)) & ~sp.is_kernel)
    T = efolds / abs(lam1)
    if max_time is not None:
        T = min(T, float(max_time))
    sizes = [fe.N, 2 * fe.N - 1] if richardson else [fe.N]
    runs = [_decay_rate(fe, i, same, N, amplitude, T, tol, snapshots, symmetric)
            for N in sizes]
    rates = [r[0] for r in runs]
    window = runs[-1][3]
    if richardson:
        q2 = (sizes[1] / sizes[0]) ** 2
        rate = (q2 * rates[1] - rates[0]) / (q2 - 1)
        err = abs(rate - rates[1]) + window
    else:
        rate, err = rates[0], window
    res = runs[-1][1]
    return {"mode": i, "eigenvalue": lam1, "multiplicity": int(same.size),
            "measured_rate": float(rate), "relative_error": abs(rate - lam1) / abs(lam1),
            "rate_error": float(err),
            "rates": [{"N": int(N), "rate": float(r[0]), "window": float(r[3]),
                       "n_steps": int(r[1].n_steps)}
                      for N, r in zip(sizes, runs, strict=True)],
            "t_final": float(T), "amplitude": float(amplitude), "symmetric": bool(symmetric),
            "success": all(bool(r[1].success) for r in runs),
            "n_steps": int(sum(r[1].n_steps for r in runs)),
            "_flow": (res, np.asarray(res.t), runs[-1][2])}


def _shift(f, sigma):
    """``f(s + sigma h)`` of periodic nodal values (Fourier interpolation; last axis)."""
    n = f.shape[-1]
    k = np.fft.rfftfreq(n, 1.0 / n)
    return np.fft.irfft(np.fft.rfft(f) * np.exp(2j * np.pi * k * sigma / n), n)


def _registration(x, y, X, Y, guess=0.0, reach=3):
    """The parameter shift (in nodes) that best matches nodes ``(x, y)`` to ``(X, Y)``.

    Minimises, over the shift ``sigma`` and a rigid motion, the sum of squared
    distances between the shifted nodes and the reference ones (for each shift the
    rigid motion is the closed-form Procrustes fit); integer shifts within ``reach`` of
    ``guess`` bracket the minimum, which is then refined by Brent's method.
    """
    Z = (X - X.mean()) + 1j * (Y - Y.mean())

    def cost(sigma):
        xs, ys = _shift(np.vstack([x, y]), sigma)
        a = (xs - xs.mean()) + 1j * (ys - ys.mean())
        return float(np.sum(np.abs(a) ** 2) + np.sum(np.abs(Z) ** 2)
                     - 2 * abs(np.vdot(a, Z)))

    grid = np.round(guess) + np.arange(-reach, reach + 1)
    best = grid[int(np.argmin([cost(g) for g in grid]))]
    return float(minimize_scalar(cost, bracket=(best - 1, best, best + 1)).x)


def _decay_rate(fe, i, same, N, amplitude, T, tol, snapshots, symmetric=True):
    """The DAE's decay rate along eigenvector ``i`` on ``N`` finite-difference nodes.

    Returns ``(rate, FlowResult of the + run, projected amplitude, window spread)``; the
    result's ``n_steps`` counts the steps of both runs when ``symmetric``.
    """
    sp = fe.spectrum
    grid = Fourier(N)
    c = fe.curve.on_grid(grid) if N != fe.N else fe.curve
    vecs = sp.eigenvectors[:, same]
    if N != fe.N:
        vecs = np.column_stack([fe.curve.grid.resample(v, grid) for v in vecs.T])
    phi = vecs[:, list(same).index(i)]
    x, y = c.positions()
    nx, ny = c.normal()
    d = amplitude / np.abs(phi).max()
    p = fe.params
    t_eval = np.linspace(0, T, snapshots)

    def run(sign):
        x1, y1 = x + sign * d * phi * nx, y + sign * d * phi * ny
        L1 = float(np.sum(np.hypot(np.roll(x1, -1) - x1, np.roll(y1, -1) - y1)))
        model = CHA(eps=p["eps"], beta=p["beta"], rho=p["L_star"] / L1, A0=p["A0"],
                    l_star=p["l_star"], a=p["a"])
        res = solve_flow(model, (x1, y1), T, N=N, tol=tol, method="bdf2", t_eval=t_eval,
                         progress=False)
        V, shift = [], 0.0
        for state in res.states:
            shift = _registration(*res.system.positions(state), x, y, guess=shift)
            V.append(_shift(res.system.normal_velocity(state), shift))
        return res, np.array(V)

    res, Vn = run(1.0)
    if symmetric:
        res_m, Vm = run(-1.0)
        n = min(len(Vm), len(Vn))  # a failed run stops early: compare what both reached
        Vn = 0.5 * (Vn[:n] - Vm[:n])
        res = replace(res, n_steps=res.n_steps + res_m.n_steps,
                      success=bool(res.success and res_m.success))
    basis = np.column_stack([vecs, rigid_normal_basis(c).T])
    coef = np.linalg.lstsq(basis, Vn.T, rcond=None)[0][: same.size]
    projected = np.linalg.norm(vecs @ coef, axis=0) / np.sqrt(N)
    t = t_eval[: projected.size]
    if t.size < 4:  # a run stopped before the fit window: no rate
        return float("nan"), replace(res, success=False), projected, float("nan")
    fit = np.flatnonzero(t >= 1.0 / abs(float(sp.eigenvalues[i])))
    if fit.size < 4:
        fit = np.arange(max(0, t.size - 4), t.size)
    logp = np.log(projected)
    rate = float(np.polyfit(t[fit], logp[fit], 1)[0])
    half = fit.size // 2
    sub = [float(np.polyfit(t[f], logp[f], 1)[0]) for f in (fit[: half + 1], fit[half:])]
    return rate, res, projected, abs(sub[1] - sub[0])


def kernel_resolution(sp: Spectrum) -> dict | None:
    """How far the rigid motions' eigenvalues are from 0, against the slowest other ``|lambda|``.

    In the continuum the normal components of the rigid motions span the kernel of
    ``J`` exactly; on a grid their Ritz values (the spectrum's kernel eigenvalues)
    differ from 0 by the grid's error in the rigid-motion identities of the
    linearization (for the two-point adhesion: its quadrature, at a few nodes per
    ``l*``), and the eigenvalues near 0 are off by about as much. So ``kernel_level``,
    the largest ``|lambda| + error`` over the kernel (``Spectrum.kernel_tol``), is an
    estimate of the absolute error of the slow eigenvalues, and ``ratio`` that of the
    slowest one's relative error.

    ``slowest`` is the smallest ``|lambda|`` outside the kernel among the eigenvalues
    the grid has: those reported and those the two-resolution check rejected as
    spurious (a slow mode that drifts between the resolutions is the symptom of an
    under-resolved state, and the check rejects it), less the rejected values within
    ``kernel_level`` (rigid modes among them).

    Parameters
    ----------
    sp : Spectrum

    Returns
    -------
    dict or None
        ``kernel_level, kernel_eigenvalues, slowest, ratio`` (``ratio = kernel_level /
        slowest``); None when the spectrum failed, or has no kernel or no other
        eigenvalue.

    Examples
    --------
    >>> from qsa import Fourier
    >>> from qsa.equilibria import npulse
    >>> from qsa.spectra import spectrum
    >>> eq = npulse(3, 0.3)
    >>> kr = kernel_resolution(spectrum(eq.energy, eq.curve))
    >>> bool(kr["ratio"] < 1e-3), len(kr["kernel_eigenvalues"])
    (True, 3)
    """
    if not sp.success or sp.n_kernel == 0:
        return None
    lam = np.real(sp.eigenvalues)
    level = float(sp.kernel_tol)
    spurious = np.abs(np.real(sp.spurious))
    others = np.concatenate([np.abs(lam[~sp.is_kernel]), spurious[spurious > level]])
    if others.size == 0:
        return None
    slowest = float(np.min(others))
    ratio = level / slowest if slowest > 0 else np.inf
    return {"kernel_level": level, "kernel_eigenvalues": [float(v) for v in lam[sp.is_kernel]],
            "slowest": slowest, "ratio": float(ratio)}


def folded_equilibrium(x, y, *, eps, beta, rho, L0, A0, l_star, a, name="folded", tol=1e-10,
                       maxiter=40, n_slow=6, rate_check=True, rate_options=None,
                       with_spectrum=True, resolve=1e-9, max_N=4801, kernel_resolve=1e-3,
                       spectrum_options=None):
    """Polish the final state of a CHA flow; spectrum, stability and relaxation rate.

    Parameters
    ----------
    x, y : array_like, shape (N,)
        Final nodes of the flow (counter-clockwise). Or ``x`` a :class:`~qsa.Curve`
        on a Fourier grid and ``y`` None: the guess itself, taken as it is (e.g. a
        saved equilibrium, which resampling its nodes would perturb).
    eps, beta, rho, A0, l_star, a : float
        The CHA parameters (:class:`qsa.flows.CHA`).
    L0 : float
        The flow's reference (initial) length: the perimeter target is ``rho L0``.
    tol, maxiter : float, int
        Newton target (relative residual) and step limit (:func:`qsa.equilibria.polish`);
        ``maxiter=0`` evaluates the state as given (on ``Fourier(N)``, at equal arc
        length), with ``success`` whether it is an equilibrium to ``tol`` already, and
        no refinement (the tests below still flag an unresolved state).
    n_slow : int
        Number of slowest modes reported.
    rate_check : bool
        Run :func:`relaxation_rate` on the slowest decaying mode.
    rate_options : dict, optional
        Keywords of :func:`relaxation_rate`.
    with_spectrum : bool
        Compute the spectrum (and run the rate check) after a successful polish; False:
        the polish only (``spectrum`` stays ``None``, and so ``success`` False; no
        kernel test).
    resolve : float or None
        Resolution test of the polished state: on a grid too coarse for the state,
        the rigid-motion identities of the two-point ``V^n`` hold only to the grid's
        accuracy, and the equilibrium is ``V^n = -a.phi`` with unfolding parameters
        ``a != 0`` (:func:`qsa.equilibria.polish`). While ``max|V^n|`` exceeds
        ``resolve`` of the residual scale, the state is resampled spectrally to
        ``Fourier(2N - 1)`` and polished again (up to ``max_N`` nodes); the
        refinements are listed in ``refinements`` with the energy change of each
        (``None``: no test).
    max_N : int
        Largest grid of the refinements.
    kernel_resolve : float or None
        Resolution test of the spectrum (after the ``resolve`` test passes): the
        rigid motions' eigenvalues, zero in the continuum, are off on a grid by the
        error of the linearization's rigid-motion identities, and the slow eigenvalues
        by about as much (:func:`kernel_resolution`). While their level (largest
        ``|lambda| + error``) exceeds ``kernel_resolve`` of the slowest other
        ``|lambda|``, the grid is refined as for ``resolve`` and the spectrum computed
        again. The default ``1e-3`` asks the slowest eigenvalue to about 0.1%, a tenth
        of the 1% of the rate check. ``None``: no test.
    spectrum_options : dict, optional
        Keywords of :func:`qsa.spectra.spectrum` (e.g. ``{"k": 10}``, the ten
        eigenvalues nearest 0 by shift-invert, for grids where the whole spectrum and
        its two-resolution check do not fit in memory).

    Returns
    -------
    FoldedEquilibrium
        A failed polish gives ``success=False``, the last iterate and no spectrum. A
        state that the grids up to ``max_N`` do not resolve has ``resolved=False``, the
        reason in ``unresolved_reason`` and ``success=False``, and an
        :class:`UnderResolvedWarning` is issued.
    """
    if isinstance(x, Curve) and y is None:
        if not isinstance(x.grid, Fourier):
            raise ValueError(f"x: a Curve guess must be on a Fourier grid, got {x.grid!r}; "
                             "resample it with x.on_grid(Fourier(N))")
        guess = x
    else:
        x, y = np.asarray(x, float), np.asarray(y, float)
        if x.shape != y.shape or x.ndim != 1:
            raise ValueError(f"x, y: need two 1-D arrays of the same length, got shapes "
                             f"{x.shape} and {y.shape}")
        # Fourier: on finite differences the rigid-motion identities of a two-point V^n
        # hold only to the grid's order, so no exact equilibrium (nor kernel) exists there
        N = x.size + 1 - x.size % 2
        guess = Curve.from_positions(x, y, Fourier(N))
    L_star = float(rho) * float(L0)
    params = {"eps": float(eps), "beta": float(beta), "rho": float(rho), "L0": float(L0),
              "L_star": L_star, "A0": float(A0), "l_star": float(l_star), "a": float(a)}
    E = folded_energy(eps, beta, L_star, A0, l_star, a)
    if kernel_resolve is not None:
        kernel_resolve = real_number(kernel_resolve, "kernel_resolve", positive=True)
    if spectrum_options is not None and not isinstance(spectrum_options, dict):
        raise ValueError(f"spectrum_options: need a dict of keywords of qsa.spectra.spectrum, "
                         f"got {type(spectrum_options).__name__}")
    sopts = dict(spectrum_options or {})
    pr = polish(E, guess, tol=tol, maxiter=maxiter)
    refinements, sp, stop = [], None, None
    while pr.success:
        sp, why = None, None
        if resolve is not None and pr.residual > resolve * pr.residual_scale:
            why = {"reason": "residual"}
        elif with_spectrum:
            sp = spectrum(E, pr.curve, **sopts)
            kr = kernel_resolution(sp) if kernel_resolve is not None else None
            if kr is not None and kr["ratio"] > kernel_resolve:
                why = {"reason": "kernel", "kernel_ratio": kr["ratio"],
                       "kernel_eigenvalues": kr["kernel_eigenvalues"],
                       "slowest": kr["slowest"]}
        if why is None:
            break
        N2 = 2 * pr.curve.N - 1
        if maxiter == 0 or N2 > max_N:
            stop = ("the state is evaluated as given (maxiter = 0)" if maxiter == 0 else
                    f"Fourier({N2}) is beyond max_N = {max_N}")
            break
        fine = polish(E, pr.curve.on_grid(Fourier(N2)), tol=tol, maxiter=maxiter)
        refinements.append({"N": int(fine.curve.N), "success": bool(fine.success),
                            "relative_V": float(fine.residual / fine.residual_scale),
                            "energy_change": float(E.energy(fine.curve) - E.energy(pr.curve)),
                            "n_newton": int(fine.n_newton), **why})
        if not fine.success:
            stop = f"the polish on Fourier({N2}) failed: {fine.message}"
            break
        pr = fine
    fe = FoldedEquilibrium(name=name, params=params, N=pr.curve.N, energy=E, guess=guess,
                           polished=pr, n_slow=int(n_slow), refinements=refinements)
    if not pr.success:
        return fe
    if sp is None and with_spectrum:
        sp = spectrum(E, pr.curve, **sopts)
    fe.spectrum = sp
    _resolution_verdict(fe, resolve, kernel_resolve, stop)
    if sp is None:
        return fe
    if rate_check:
        rate = relaxation_rate(fe, **(rate_options or {}))
        fe.flow = rate.pop("_flow")
        fe.rate = rate
    return fe


def _resolution_verdict(fe, resolve, kernel_resolve, stop):
    """Set ``fe.resolved`` and ``fe.unresolved_reason`` from the two tests; warn if unresolved."""
    pr, failed, tested = fe.polished, [], False
    if resolve is not None:
        tested = True
        rel = pr.residual / pr.residual_scale
        if rel > resolve:
            failed.append(f"max|V^n| is {rel:.2e} of its scale (resolve = {resolve:g})")
    kr = None if fe.spectrum is None or kernel_resolve is None else kernel_resolution(fe.spectrum)
    if kr is not None:
        tested = True
        if kr["ratio"] > kernel_resolve:
            failed.append(f"the rigid motions' eigenvalues reach {kr['kernel_level']:.2e}, "
                          f"{kr['ratio']:.2g} of the slowest other |lambda| "
                          f"{kr['slowest']:.4g} (kernel_resolve = {kernel_resolve:g})")
    if not tested:
        return
    fe.resolved = not failed
    if failed:
        fe.unresolved_reason = (f"Fourier({fe.N}) does not resolve the state: "
                                + "; ".join(failed) + (f"; not refined: {stop}" if stop else ""))
        warnings.warn(f"{fe.name}: {fe.unresolved_reason}", UnderResolvedWarning, stacklevel=3)


def folded_equilibria(runs, **options):
    """:func:`folded_equilibrium` of the final state of each :class:`CHARun` in ``runs``."""
    out = []
    for r in runs:
        sc = r.scenario
        out.append(folded_equilibrium(r.snap_x[-1], r.snap_y[-1], eps=sc.eps, beta=sc.beta,
                                      rho=sc.rho, L0=r.L0, A0=sc.A0, l_star=sc.l_star, a=sc.a,
                                      name=r.name, **options))
    return out
