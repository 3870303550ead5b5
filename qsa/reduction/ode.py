r"""The front-position ODE: quasi-steady faceting dynamics on the splice manifold.

Between coarsening events a faceting flow (e:Facet-NV) stays close to the
manifold of heteroclinic splices ``psi_N(p)`` (e:psi_N; built by
:class:`qsa.equilibria.SpliceProfile`) and only the front positions
``p = (p_1 < ... < p_2N)`` move, exponentially slowly. This module reduces the
flow to ``p' = F(p)``.

Derivation of the reduced dynamics
----------------------------------
*The flow and its metric.* In intrinsic coordinates ``U = (kappa, g)`` the
faceting flow is ``U_t = -M M^dagger grad_I E + M(0, v)`` (e:FoE_IG), where
``M(0, v)`` is a reparameterization (the tangential gauge; the DAE of
:mod:`qsa.flows.dae` picks ``v`` so that ``g`` stays uniform). On
``range M`` the flow is the gradient flow of ``E`` for the metric
``<U1, (M M^dagger)^+ U1>``: with ``U1 = M w``, ``w = (phi, v)`` the extrinsic
(normal, tangential) velocity and ``M = A S B^T`` a singular value
decomposition, ``(M M^dagger)^+ M w = A S^{-1} B^T w`` and

    <M w, (M M^dagger)^+ M w> = |B^T w|^2 = min_{r in ker M} |w - r|^2_{L2(dsigma)},

the ``L^2(dsigma)`` norm of the velocity modulo rigid motions (``ker M``,
MATH.md section 2). Reparameterizations cost nothing in the flow (the energy is
invariant and the gauge is free), so the metric the flow induces on shapes is
the quotient by ``v``: minimising over ``v`` removes the tangential part and
the tangential components of the rigid motions, leaving

    |U1|^2 = min_{c in R^3} int (phi - c . r^n)^2 dsigma,
    r^n = (e1 . n, e2 . n, gamma . tau),

the normal velocity modulo rigid normal velocities. This is the metric of
``V^n = -[M^dagger grad_I E]_1`` itself: ``dE/dt = -int (V^n)^2 dsigma``.

*Pull-back.* On the splice manifold (``g = L`` uniform, ``L = L*`` so the
perimeter penalty is balanced) the curve is
``gamma(sigma) = int_0^sigma tau(theta) dsigma'`` with
``theta(sigma) = int_0^sigma psi_N``. A change of ``p_j`` changes the angle by
``Theta_j(sigma) = int_0^sigma d psi_N / d p_j`` and, since
``d tau / d theta = -n``, the position by
``d gamma / d p_j = -int_0^sigma n Theta_j dsigma'``. Its normal velocity is

    phi_j = n . d gamma / d p_j,   phi_j^perp = phi_j - (projection on span r^n),

and the pulled-back metric is the Gram matrix

    G_ij = int phi_i^perp phi_j^perp dsigma       (2N x 2N, positive semi-definite).

A common shift of all ``p_j`` only moves the base point (a rigid motion of the
shape): ``G 1 = 0``.

*Energy and constraints.* With ``L`` fixed,
``E(p) = int alpha^2/2 psi_N'^2 + W(psi_N) dsigma`` and, integrating by parts,

    dE/dp_j = int R_kappa d psi_N / d p_j dsigma,
    R_kappa = -alpha^2 psi_N'' + W'(psi_N),

an exponentially small interaction force (``~ exp(-kstar d / (sqrt 2 alpha))``,
``d`` the spacing of neighbouring fronts). The closure constraints ``C(p) = 0``
(e:C1 two components, e:C2 the total turning; see
:func:`qsa.equilibria.splice_closure`) restrict ``p`` to a manifold of
dimension ``2N - 3``; the base point is fixed by ``sum p_j' = 0``.

*Reduced flow.* The constrained gradient flow of ``E(p)`` in the metric ``G``
(equivalently the Galerkin projection of ``V^n`` on the tangent space,
``min |V^n - sum p_j' phi_j^perp|``) is the saddle-point system

    [ G   A^T ] [ p' ]   [ -dE/dp ]
    [ A   0   ] [ mu ] = [    0   ],    A = [ dC/dp ; 1^T / sqrt(2N) ],

``mu`` the multipliers (the first three are ``Lambda``-like). ``F(p) = p'``
decreases ``E`` at the rate ``p'^T G p'``. The front positions here are the
splice parameters ``p_j``; on the profile they are the ``kstar / 2`` crossings
up to the neighbours' tails (:meth:`FrontODE.crossings` gives the crossings).

*Variable length.* With ``beta`` given, ``L`` is a further unknown and the
energy gains ``beta/2 (L - L*)^2``. Lengthening the curve at fixed ``p``
inserts arc at the base point ``sigma = L ~ 0`` (the middle of the last facet)
and moves no point of ``[0, L)``: it has no normal velocity and costs no
dissipation, but it changes ``C`` (``dC/dL ~ (cos theta(L), sin theta(L), 0)``)
and, through the images of the fronts across the base point, ``E``. So ``L'``
is tied to ``p'`` by the closure rows and the saddle-point system gains one
unknown and one row: ``dC/dL L' + dC/dp p' = 0`` and ``(dC/dL) . mu =
-(dE/dL + beta (L - L*))``. At the quasi-static length (``L' = 0``) of a stiff
perimeter it reduces to the fixed-length flow (tested). ``dE/dL`` and
``dC/dL`` are evaluated without seam errors by writing
``d psi/dL = g - (sigma/L) psi'`` with ``g`` smooth and periodic and integrating
the last term by parts.

*Collisions.* When two neighbouring fronts come within ``d_c`` -- the spacing
at which the superposed pair no longer crosses ``kstar / 2`` (``2 ln 3 /
lambda`` for the quartic well) -- the splice manifold ends: the pair is
removed, the remaining positions are closed again (minimum-norm Gauss-Newton,
:func:`qsa.equilibria.close_positions`) and the integration continues.

*Validity.* The reduction neglects the slaving of the fast modes (the
perimeter mode, rate ``~ 2 pi beta / R``, is the slowest of them) and the
deviation of the true slow manifold from the splices. A relative error ``eps``
of the interaction rate is exponentially amplified near a collision: a pair
closing as ``d' = -c exp(-lambda d)`` with rate ``c (1 + eps)`` is off by

    (eps / lambda) (t / t_c) / (1 - t / t_c)

at time ``t`` (:func:`collision_sensitivity`), finite for ``t < t_c`` but
unbounded at the collision itself. Position agreement *up to* the collision
therefore needs ``eps`` far below 1%; a few per cent of rate error is already a
several-per-cent collision-time error and, at ``t -> t_c``, an O(facet) position
error. The DAE itself shows it between resolutions (``compare_fronts`` at N = 1200
and 2400, BDF2 tol 1e-6, fronts of N = 1200 interpolated to the N = 2400 times, in
units of the smallest facet): triangle 0.51 / 0.97 / 3.6% up to 0.9 / 0.95 / 0.99
``t_c`` but 36% up to the collision (its ``t_c`` moves by 0.85%); short facet 0.02 /
0.03 / 0.15% but 7.4%. The reduction (length free, ``correction="newton"``) against
the N = 2400 DAE: triangle 0.13 / 0.25 / 1.3%, 21% up to the collision; short facet
0.06 / 0.12 / 0.32%, 17%.

Accuracy
--------
Measured (``qsa reproduce fronts``, alpha = 0.1, kstar = 5, beta = 5; the DAE
collision time converges like ``N^-2`` and was extrapolated from N = 600, 1200,
2400): triangle (130, 120, 110 degrees) ``t_c`` 2.7726 (ODE) against 2.745
(DAE, N -> inf), +1.0%; trapezoid with a short facet 0.06546 against 0.06331,
+3.4%. Part of it is the perimeter mode, captured by the variable-length
reduction (``FrontODE(beta=...)``: short facet +2.4%; triangle +0.33% against
the extrapolated DAE, positions within 0.08% of the smallest facet up to 0.99
``t_c``). Positions agree within 5% of the smallest facet up to 0.95 ``t_c``
(0.6% and 2.7%) and then diverge as above. The slow eigenvalues agree with the
full linearization (``qsa.spectra``) within ~1% at polished regular polygons
(see :func:`qsa.reduction.compare.compare_eigenvalues`).

*Where the remaining rate error comes from* (``benchmarks/diag_front_rates.py``:
DAE states at fractions of ``t_c``, splice fitted to the same ``kstar/2``
crossings, closing rate of the shortest gap; beta = 500 so the length is fixed,
N = 1200 and 2400 agree to ~0.1%). It is *not* a constant: on the short facet
the ODE closes it slower by ``eps_F`` = 0.95, 1.5, 2.1, 2.7, 3.6, 6.7% at
``t/t_c`` = 0.1, 0.3, 0.5, 0.7, 0.85, 0.95 (gap 0.269 ... 0.193), tracking
``eps_F ~ -psi_mid / kstar`` (the splice's tail overlap at the centre of the
gap, ``~ exp(-lambda d / 2)``; this is why it depends on ``lambda d`` and not
on alpha). ``kappa_DAE - psi_N(p)`` is localized in the centre of the closing
gap (max about 3 front widths inside it, +2.0% ... +7.5% of ``psi_mid``), not
at the corners (the O(alpha) curvature correction is < 1e-3 there) nor at the
cutoff (the other facets' centres differ by ~1e-3, absolute): the splice superposes the
overlapping tails linearly, while the well's nonlinearity lifts the true
quasi-steady profile there, which strengthens the attraction. Evaluating the
reduced force with the DAE state's own residual removes most of it (``eps_R``
0.24 ... 1.7%). One Newton step from the splice (:meth:`slow_correction`,
``correction="newton"``) predicts the lift (+2.5 ... +9.3%) and gives
``eps_N`` = 0.08 ... 1.1%. The remaining ~1% is *not* removed by slaving the
metric's tangent fields to first order: with ``d(psi_N + delta)/dp_j`` (they
differ from ``d psi_N/dp_j`` by ~3e-4) in ``G`` the short-facet ``t_c`` moves the
wrong way (fixed length +0.42% instead of +0.29% against the DAE; +0.75% with the
force and the closure also from ``psi_N + delta``), the triangle's barely (-0.89%
instead of -0.95%); so this is not done. Collision times with ``correction="newton"``: short facet
0.06414 (fixed length) against 0.06394 (DAE, beta = 500, N = 2400), +0.3%
(uncorrected +2.4%); with ``beta = 5`` and the variable length 0.06352
against 0.06331, +0.3% (uncorrected +2.4%). Triangle (fixed length, DAE
beta = 500, N = 1200: 2.7929): 2.7665 (-0.9%) against 2.7727 (-0.7%)
uncorrected: its late-time rate error halves (1.2% -> 0.55% at ``t/t_c =
0.95``), but an early +1% (``t/t_c ~ 0.1``, rates 20x slower than late) that
the correction does not touch dominates its collision time. The correction is
a banded solve (:meth:`_correction`: 8th-order differences for ``d^2``, nodes in
folded order, Schur complement on the ``2N + 1`` translation and turning modes;
it agrees with the dense spectral solve to ~1e-7 of the force) and costs
1.2-1.4x the uncorrected ODE's CPU time (the dense ``M x M`` solve cost 5-8x).
``qsa reproduce fronts --scenario short-facet --correction newton`` (beta =
5, N = 1200): variable length ``t_c`` +0.29% (uncorrected +2.38%), positions
within 0.08%, 0.15%, 0.43% of the smallest facet up to 0.9, 0.95, 0.99 ``t_c``
(uncorrected 0.84%, 1.68%, 6.26%); fixed length +1.26% (uncorrected +3.35%).
Triangle (N = 2400, whose DAE ``t_c`` 2.7529 is itself ~0.3% above the
extrapolated 2.745): variable length 2.7479 (-0.18%; uncorrected 2.7541,
+0.05%), positions 1.3% (uncorrected 0.15%) at 0.99 ``t_c``: there the
correction is within the DAE's own discretization uncertainty and gains
nothing measurable, hence it is an option, off by default.

*Cost* (``benchmarks/bench_reduction.py``, CPU seconds to the first collision, best of
5; DAE: BDF2 tol 1e-6, triangle 1.56 / 2.75 s and short facet 0.74 / 1.32 s at N =
1200 / 2400). rtol 1e-4, ``method="auto"``: RK45 at fixed length and for the short
facet's variable length (its perimeter mode is mild over the interval), Radau with the
Jacobian's length column only for the triangle's (stiff). ``backend="numpy"`` (the
reference) spends ~0.5 ms per evaluation in numpy call overhead on ``M x 2N ~ 315 x 8``
arrays; ``backend="numba"`` (:mod:`qsa.reduction._kernels`, the optional ``fast``
extra) fuses one evaluation into a compiled kernel of ~45 us (~95 us with the Newton
correction):

    ===========  =================  =======  ======  =====  ==========
    scenario     correction, L      backend  cpu s   nfev   x DAE 2400
    ===========  =================  =======  ======  =====  ==========
    triangle     none, fixed        numpy    0.074   146     37
    triangle     none, fixed        numba    0.0087  140    317
    triangle     newton, fixed      numpy    0.099   150     28
    triangle     newton, fixed      numba    0.0153  150    180
    triangle     none, variable     numpy    0.196   303     14
    triangle     none, variable     numba    0.0216  303    127
    triangle     newton, variable   numpy    0.229   282     12
    triangle     newton, variable   numba    0.0337  282     81
    short facet  none, fixed        numpy    0.055    98     24
    short facet  none, fixed        numba    0.0071   98    186
    short facet  newton, fixed      numpy    0.075   103     18
    short facet  newton, fixed      numba    0.0125  103    106
    short facet  none, variable     numpy    0.074   105     18
    short facet  none, variable     numba    0.0088  123    150
    short facet  newton, variable   numpy    0.091   104     15
    short facet  newton, variable   numba    0.0128  104    103
    ===========  =================  =======  ======  =====  ==========

(x DAE 1200: divide by ~1.75 for the triangle, ~1.8 for the short facet.) With numba
the triangle's variable-length runs are bounded by Radau's own per-step work (~40% of
their time). The numba kernel differs from the numpy path only by round-off: ``Theta_j`` in
closed form (the cut fronts' own integrals), the other cumulative integrals by a
16th-order local periodic rule (``~1e-10`` of the spectral ones at 3 nodes per width),
an unpivoted banded ``L D L^T`` for the Newton matrix (growth-factor guarded, pivoted LU
otherwise); velocities, metric, force and constraints agree to ``< 1e-10`` relative at
valid splices and the collision times to ``< 2e-7`` relative (``1.4e-7``: the triangle
without correction, whose step sequence shifts, 140 instead of 146 evaluations; the
others ``< 3e-10``), far below the model error (0.3-3%). First use compiles the kernel
(~15 s, cached on disk afterwards: well under a second to load). The ODE's evaluation count is set
by the finite-time approach to the collision (``d' ~ -c exp(-lambda d)``; step sizes
shrink geometrically).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from operator import itemgetter

import numpy as np
from scipy.integrate import solve_ivp
from scipy.linalg.lapack import dgbsv
from scipy.optimize import brentq

from qsa.discretize import Fourier
from qsa.equilibria import heteroclinic
from qsa.equilibria._wells import resolve_well
from qsa.equilibria.splice import (
    SpliceProfile,
    _smoothstep,
    close_positions,
    default_cutoff,
)

__all__ = ["FrontODE", "FrontODEResult", "collision_distance", "collision_sensitivity"]


#: ``method="auto"`` of :meth:`FrontODE.integrate` switches to Radau above this
#: ``|dL'/dL| * interval`` (RK45's stability limit makes it take ``~|mu| T / 3.3`` steps).
STIFF_AUTO = 100.0


def collision_distance(front):
    """Spacing ``d_c`` at which a superposed pair of opposite fronts stops crossing ``kstar/2``.

    Solves ``psi_h(d/2) - psi_h(-d/2) = kstar / 2`` (the profile at the midpoint
    of the pair); ``2 ln 3 / lambda`` for the quartic well.
    """
    k = front.kstar
    return brentq(lambda d: front(0.5 * d) - front(-0.5 * d) - 0.5 * k, 1e-12 * front.width,
                  50 * front.width, xtol=1e-14 * front.width)


def collision_sensitivity(eps, t, t_c, lam):
    """Position error ``(eps / lam) (t/t_c) / (1 - t/t_c)`` from a relative rate error ``eps``.

    For a pair closing as ``d' = -c exp(-lam d)`` (``t_c`` its collision time), a
    model with rate ``c (1 + eps)`` is off by this much at time ``t`` (first order
    in ``eps``).
    """
    x = np.asarray(t, dtype=float) / t_c
    return eps / lam * x / (1 - x)


def _fft_size(n):
    """Smallest odd ``M >= n`` with no prime factor above 7 (fast FFTs; odd: no Nyquist)."""
    M = int(np.ceil(n))
    M += 1 - M % 2
    while True:
        r = M
        for q in (3, 5, 7):
            while r % q == 0:
                r //= q
        if r == 1:
            return M
        M += 2


#: Periodic central differences for ``d^2/dx^2`` at unit spacing, 8th order: weights of
#: the offsets 0, +-1, ..., +-4.
_D2_STENCIL = np.array([-205 / 72, 8 / 5, -1 / 5, 8 / 315, -1 / 560])


def _folded_band(M, c):
    """A symmetric periodic band stencil as an ordinary band matrix in folded order.

    Ordering the nodes ``0, M-1, 1, M-2, ...`` puts periodic neighbours (also across
    the seam) at most ``2 m`` apart, so the periodic matrix is banded with half-bandwidth
    ``2 m`` and no corners. Returns ``perm`` (the order) and the stencil part of the
    matrix in LAPACK ``gbsv`` layout, shape ``(6 m + 1, M)`` (``2 m`` leading rows of
    fill-in space).
    """
    m = c.size - 1
    h = (M + 1) // 2
    perm = np.empty(M, dtype=int)
    perm[0::2] = np.arange(h)
    perm[1::2] = np.arange(M - 1, h - 1, -1)
    pos = np.empty(M, dtype=int)
    pos[perm] = np.arange(M)
    kb = 2 * m
    ab = np.zeros((3 * kb + 1, M))
    for d in range(-m, m + 1):
        i = np.arange(M)
        j = (i + d) % M
        ab[2 * kb + pos[i] - pos[j], pos[j]] += c[abs(d)]
    return perm, np.asfortranarray(ab)


@dataclass(frozen=True)
class FrontODE:
    """The front-position ODE ``p' = F(p)`` of the faceting flow (see module docstring).

    Parameters
    ----------
    alpha, kstar : float
        Faceting parameters (``alpha > 0``).
    length : float
        Curve length ``L`` (``= L*``; fixed).
    well : object, optional
        Double well (default the quartic).
    cutoff : (float, float), optional
        Fixed cutoff of the fronts (:class:`SpliceProfile`); default
        :func:`qsa.equilibria.default_cutoff` of the positions passed to
        :meth:`integrate` (kept fixed between collisions).
    points_per_width : float
        Quadrature resolution (nodes per front width ``1/lambda``).
    beta : float, optional
        Perimeter penalty ``beta/2 (L - L*)^2``. ``None`` (default): ``L`` is held
        at ``length`` (the ``beta -> inf`` limit). Otherwise ``L`` is a further
        unknown (state ``(p, L)``, see "Variable length" in the module docstring).
    L_star : float, optional
        Preferred length (default ``length``).
    correction : {None, "newton"}
        ``"newton"``: evaluate the force ``dE/dp_j`` with the residual of the
        profile corrected by one Newton step towards the slow manifold
        (:meth:`slow_correction`) instead of the splice's own residual; removes
        most of the rate error of closing pairs (see "Accuracy"). Costs one banded
        solve of size ``M`` (quadrature nodes) per evaluation, ~1.2-1.4x the
        uncorrected ODE (numpy backend; ~1.7x with numba).
    backend : {"auto", "numpy", "numba"}
        Evaluation of the right-hand side. ``"numpy"``: the reference (spectral
        cumulative integrals). ``"numba"``: one compiled kernel per evaluation
        (:mod:`qsa.reduction._kernels`; needs the optional ``numba``, ``pip install
        qsa[fast]``, and the quartic well); same results to round-off (closed-form
        ``Theta_j``, 16th-order local cumulative quadrature: < 1e-10 relative), 6-10x
        cheaper per evaluation (see "Cost"). ``"auto"`` (default): numba when
        importable and the well is the quartic, else numpy. :attr:`backend_used` tells
        which one runs.
    """

    alpha: float
    kstar: float
    length: float
    well: object = None
    cutoff: tuple = None
    points_per_width: float = 3.0
    beta: float = None
    L_star: float = None
    correction: str = None
    backend: str = "auto"
    front: object = field(init=False, repr=False)
    grid: object = field(init=False, repr=False)
    _fd: tuple = field(init=False, repr=False, compare=False)
    _inv_ik: np.ndarray = field(init=False, repr=False, compare=False)
    _kernel: tuple = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        for name in ("alpha", "kstar", "length", "points_per_width"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v > 0):
                raise ValueError(f"{name} must be positive, got {v!r}")
        well, kstar = resolve_well(self.well, self.kstar)
        front = heteroclinic(self.alpha, well, kstar)
        object.__setattr__(self, "front", front)
        M = _fft_size(max(self.points_per_width * self.length / front.width, 255))
        object.__setattr__(self, "grid", Fourier(M))
        kk = np.arange(M // 2 + 1)
        object.__setattr__(self, "_inv_ik", np.where(kk == 0, 0.0, 1 / (2j * np.pi * np.maximum(
            kk, 1)))[:, None])
        object.__setattr__(self, "_fd", _folded_band(M, _D2_STENCIL))
        if self.beta is not None and not (np.isfinite(self.beta) and self.beta >= 0):
            raise ValueError(f"beta must be non-negative, got {self.beta!r}")
        if self.L_star is None:
            object.__setattr__(self, "L_star", float(self.length))
        if self.correction not in (None, "newton"):
            raise ValueError(f"correction must be None or 'newton', got {self.correction!r}")
        object.__setattr__(self, "_kernel", self._resolve_backend())

    def _resolve_backend(self):
        """``None`` (numpy) or ``(front_rhs, constants)`` of the numba kernel."""
        if self.backend not in ("auto", "numpy", "numba"):
            raise ValueError(f"backend must be 'auto', 'numpy' or 'numba', got {self.backend!r}")
        if self.backend == "numpy":
            return None
        try:
            from qsa.reduction import _kernels
        except ImportError as exc:
            if self.backend == "numba":
                raise ValueError("backend='numba' needs numba (pip install numba, or the "
                                 "'fast' extra: pip install qsa[fast])") from exc
            return None
        if not self.front.closed_form:
            if self.backend == "numba":
                raise ValueError("backend='numba' supports the quartic well only")
            return None
        perm, band = self._fd
        consts = (float(self.front.kstar), float(self.front.rates[0]), float(self.alpha**2),
                  int(self.grid.s.size), _kernels.end_weights(_kernels.cell_weights(8)),
                  _kernels.band_rows(perm, band), np.ascontiguousarray(perm, dtype=np.int64))
        return _kernels.front_rhs, consts, _kernels.front_velocity

    @property
    def backend_used(self):
        """The backend actually evaluating the right-hand side: ``"numpy"`` or ``"numba"``."""
        return "numpy" if self._kernel is None else "numba"

    def _run_kernel(self, p, cutoff=None, L=None, correction=None, full=True):
        """The numba kernel's outputs (see :func:`qsa.reduction._kernels.front_rhs`);
        only ``(sol, status)`` unless ``full``."""
        fn, (k, lam, a2, M, wq, band, perm), fv = self._kernel
        fn = fn if full else fv
        Lv = float(self.length if L is None else L)
        p = np.ascontiguousarray(p, dtype=float)
        l1, l2 = cutoff or self.cutoff or default_cutoff(p, Lv)
        corr = self.correction == "newton" if correction is None else bool(correction)
        beta = 0.0 if self.beta is None else float(self.beta)
        return fn(p, Lv, float(l1), float(l2), k, lam, a2, M, wq, corr, band, perm,
                  L is not None, beta, float(self.L_star))

    # ------------------------------------------------------------ geometry
    @property
    def sigma(self):
        """Quadrature nodes in arc length, shape (M,)."""
        return self.length * self.grid.s

    @property
    def collision_distance(self):
        """:func:`collision_distance` of the front."""
        return collision_distance(self.front)

    def profile(self, p, cutoff=None):
        """The :class:`SpliceProfile` at positions ``p``."""
        p = np.asarray(p, dtype=float)
        cut = cutoff or self.cutoff or default_cutoff(p, self.length)
        return SpliceProfile(self.front, p, self.length, cut)

    def _check(self, p):
        p = np.asarray(p, dtype=float)
        if p.ndim != 1 or p.size < 4 or p.size % 2:
            raise ValueError(f"p must hold 2N >= 4 positions, got shape {p.shape}")
        if not np.all(np.isfinite(p)):
            raise ValueError("p contains NaN or inf")
        if np.any(np.diff(p) <= 0) or p[-1] - p[0] >= self.length:
            raise ValueError("p must increase strictly and span less than the length")
        return p

    def _cut_front(self, prof, x):
        """``SpliceProfile.cut_front`` (values, first, second derivative) at ``x``.

        For the quartic well the front is logistic, so one exponential gives all
        three (``q = e^{-lambda |x|} / (1 + e^{-lambda |x|})``: ``psi_h - kstar H(x) =
        -+ kstar q``, ``psi_h' = lambda kstar q (1 - q)``, ``psi_h'' = -+ lambda^2
        kstar q (1 - q) (1 - 2 q)``), and the cutoff is evaluated only where it acts
        (``|x| > l1``). Other wells use the profile's own evaluation.
        """
        front = self.front
        if not front.closed_form:
            return prof.cut_front(x)
        k, lam = front.kstar, front.rates[0]
        r = np.abs(x)
        pos = x > 0
        live = r < prof.l2
        sg = np.where(pos, -k, k) * live  # beyond l2 the cut front is the bare step
        q = np.exp(-lam * r)
        q /= 1 + q
        q1 = q * (1 - q)
        gap = sg * q
        v0 = gap + k * pos
        v1 = (lam * k) * q1 * live
        v2 = (lam * lam) * sg * q1 * (1 - 2 * q)
        mid = np.flatnonzero(live & (r > prof.l1))
        if mid.size:
            w = prof.l2 - prof.l1
            f0, f1, f2 = v0.reshape(-1), v1.reshape(-1), v2.reshape(-1)  # views
            S, S1, S2 = _smoothstep((prof.l2 - r.reshape(-1)[mid]) / w)
            dchi, d2chi = -np.sign(x.reshape(-1)[mid]) * S1 / w, S2 / w**2
            g, d1 = gap.reshape(-1)[mid], f1[mid]
            f0[mid] = f0[mid] + (S - 1) * g
            f1[mid] = dchi * g + S * d1
            f2[mid] = d2chi * g + 2 * dchi * d1 + S * f2[mid]
        return v0, v1, v2

    def _cumulative(self, F, twice=None):
        """``int_0^s F`` (unit period, along axis 0) of periodic columns by one real FFT pair.

        With ``twice`` (column indices), also ``int_0^s int_0^s' F`` of those columns,
        appended. Same result as ``Fourier.cumulative`` (applied twice).
        """
        M = F.shape[0]
        s = self.grid.s[:, None]
        Fh = np.fft.rfft(F, axis=0)
        mean = Fh[0].real / M
        inv = self._inv_ik
        Ph = Fh * inv
        if twice is not None:
            Ph = np.concatenate([Ph, Ph[:, twice] * inv], axis=1)
        P = np.fft.irfft(Ph, n=M, axis=0)
        n = F.shape[1]
        out = P[:, :n] - P[0, :n] + mean * s
        if twice is None:
            return out
        P1, Q, mt = P[:, twice], P[:, n:], mean[twice]
        return out, Q - Q[0] - P1[0] * s + 0.5 * mt * s**2

    def _fields(self, p, cutoff=None, L=None):
        """Everything on the quadrature grid (``sigma = L s``) from one evaluation of the fronts."""
        L = self.length if L is None else float(L)
        p = np.asarray(p, dtype=float)
        cut = cutoff or self.cutoff or default_cutoff(p, L)
        prof = SpliceProfile(self.front, p, L, cut)
        grid = self.grid
        s = L * grid.s
        y = s[:, None] - prof.c
        y -= L * np.floor(y / L + 0.5)  # prof.local(s): wrapped into [-L/2, L/2)
        M, m = s.size, prof.a.size
        X = np.empty((M, 2 * m))  # columns up_1, down_1, up_2, ... (the order of p)
        X[:, 0::2] = y + prof.a
        X[:, 1::2] = y - prof.a
        v0, v1, v2 = self._cut_front(prof, X)
        sgn = np.tile([1.0, -1.0], m)  # psi_N = sum up - sum down
        psi, d1, d2 = v0 @ sgn, v1 @ sgn, v2 @ sgn
        dpsi = -sgn * v1
        w = L * grid.weights
        out = {"psi": psi, "d1": d1, "d2": d2, "dpsi": dpsi, "w": w, "n": np.size(p), "L": L}
        if self.beta is None:  # fixed length: no d/dL
            cum = L * self._cumulative(np.column_stack([psi, dpsi]))
            out["theta"], out["Theta"] = cum[:, 0], cum[:, 1:]
            return out
        # d/dL at fixed p moves the periodic images: y = (sigma - c) - k L, dy/dL = -k
        # psi_L jumps at the seam sigma = L ~ 0; g = psi_L + (sigma/L) psi' is smooth
        k = np.repeat(np.rint((s[:, None] - prof.c - y) / L), 2, axis=1) * sgn
        x = s / L
        g = -(k * v1).sum(axis=1) + x * d1
        dg = -(k * v2).sum(axis=1) + d1 / L + x * d2
        F = np.empty((M, 2 * m + 2))
        F[:, 0], F[:, 1:-1], F[:, -1] = psi, dpsi, g
        cum = L * self._cumulative(F)
        theta, Theta = cum[:, 0], cum[:, 1:-1]
        Theta_L = cum[:, -1] - x * psi + theta / L  # int_0^sigma psi_L, pointwise
        out.update(theta=theta, Theta=Theta, g=g, dg=dg, Theta_L=Theta_L)
        return out

    def _length_derivatives(self, f):
        """``dE_facet/dL`` and ``dC/dL`` at fixed ``p`` (shape (3,)).

        ``E = int_0^L e dsigma`` gains the density at the end and the change of the
        images' tails; ``C`` likewise (``theta(L) = 2 pi + C_3``).
        """
        W = self.front.well
        a2 = self.alpha**2
        psi, d1, w, L = f["psi"], f["d1"], f["w"], f["L"]
        # with psi_L = g - (sigma/L) psi' and integration by parts every integral is
        # of a smooth periodic function (spectral accuracy):
        e = 0.5 * a2 * d1**2 + W.W(psi)
        dE = (W.dW(psi) * f["g"] + a2 * d1 * f["dg"]) @ w + ((e - a2 * d1**2) @ w) / L
        int_psi_L = f["g"] @ w - psi[0] + (psi @ w) / L
        tL = f["theta"][0] + psi @ w  # theta(L)
        c, s_ = np.cos(f["theta"]), np.sin(f["theta"])
        # Theta_L jumps by int psi_L at the seam: end-corrected (trapezoid) sums
        h2 = 0.5 * w[0]
        dC1 = np.cos(tL) - (s_ * f["Theta_L"]) @ w - h2 * np.sin(tL) * int_psi_L
        dC2 = np.sin(tL) + (c * f["Theta_L"]) @ w + h2 * np.cos(tL) * int_psi_L
        dC = np.array([dC1, dC2, psi[0] + int_psi_L])
        return float(dE), dC

    def _energy(self, f):
        return float((0.5 * self.alpha**2 * f["d1"] ** 2 + self.front.well.W(f["psi"]))
                     @ f["w"])

    def energy(self, p, cutoff=None):
        """``E(psi_N(p)) = int alpha^2/2 psi'^2 + W(psi) dsigma`` (``L`` fixed)."""
        return self._energy(self._fields(p, cutoff))

    def _gradient(self, f):
        R = -(self.alpha**2) * f["d2"] + self.front.well.dW(f["psi"])
        return (R * f["w"]) @ f["dpsi"]

    def gradient(self, p, cutoff=None):
        """``dE/dp_j = int R_kappa d psi_N/d p_j dsigma``, shape (2N,)."""
        if self._kernel is not None:
            return self._run_kernel(p, cutoff, correction=False)[4]
        return self._gradient(self._fields(p, cutoff))

    def _correction(self, f):
        """Newton step ``delta`` and the corrected residual (see :meth:`slow_correction`).

        ``H = -alpha^2 d^2 + W''(psi_N)`` with the periodic 8th-order central difference
        ``d^2`` on the quadrature grid: a band matrix (half-bandwidth 8) once the nodes
        are taken in folded order (:func:`_folded_band`). The bordered system
        ``[[H, B], [B^T, 0]] (delta, mu) = (-R, 0)``, ``B = [d psi_N / d p, 1]``, is
        solved by one banded LU of ``H`` and the Schur complement ``B^T H^{-1} B``
        (size 2N + 1): O(M (2N + 2)) per evaluation instead of the dense ``O(M^3)`` of
        :meth:`_correction_dense` (the spectral reference; they agree to the difference
        error, ~1e-7 of the force). ``H delta = -R - B mu`` then gives the corrected
        residual without applying ``d^2`` again: ``R(psi + delta) = N(delta) - B mu``,
        ``N(delta) = W'(psi + delta) - W'(psi) - W''(psi) delta``.
        """
        psi, W, a2 = f["psi"], self.front.well, self.alpha**2
        M = psi.size
        perm, band = self._fd
        kb = (band.shape[0] - 1) // 3
        d2W = W.d2W(psi)
        dW = W.dW(psi)
        R = -a2 * f["d2"] + dW
        ab = (-a2 * (M / f["L"]) ** 2) * band  # -alpha^2 d^2, unit-spacing stencil scaled
        ab[2 * kb] += d2W[perm]
        nb = f["dpsi"].shape[1] + 1
        rhs = np.empty((M, 1 + nb), order="F")
        rhs[:, 0] = -R[perm]
        rhs[:, 1:-1] = f["dpsi"][perm]
        rhs[:, -1] = 1.0
        _, _, X, info = dgbsv(kb, kb, ab, rhs, overwrite_ab=True, overwrite_b=True)
        if info != 0:  # H singular: the dense reference copes (least squares)
            return self._correction_dense(f)
        B = np.column_stack([f["dpsi"][perm], np.ones(M)])
        S = B.T @ X[:, 1:]
        try:
            mu = np.linalg.solve(S, B.T @ X[:, 0])
        except np.linalg.LinAlgError:
            mu = np.linalg.lstsq(S, B.T @ X[:, 0], rcond=1e-12)[0]
        d = X[:, 0] - X[:, 1:] @ mu
        # B^T delta = 0 holds to the solve's round-off, which the near kernel of H
        # (the translation modes) amplifies to ~1e-9 relative: project it out exactly
        d -= B @ np.linalg.solve(B.T @ B, B.T @ d)
        delta = np.empty(M)
        delta[perm] = d
        Rc = (W.dW(psi + delta) - dW - d2W * delta) - f["dpsi"] @ mu[:-1] - mu[-1]
        return delta, Rc

    def _correction_dense(self, f):
        """Reference for :meth:`_correction`: spectral ``d^2``, dense bordered solve."""
        psi, W, a2, L = f["psi"], self.front.well, self.alpha**2, f["L"]
        M = psi.size
        k = 2 * np.pi * np.fft.fftfreq(M, d=1.0 / M)  # unit-length wavenumbers
        D2 = np.fft.ifft(-(k**2)[:, None] * np.fft.fft(np.eye(M), axis=0), axis=0).real / L**2
        R = -a2 * f["d2"] + W.dW(psi)
        B = np.column_stack([f["dpsi"], np.ones(M)])
        nb = B.shape[1]
        K = np.block([[-a2 * D2 + np.diag(W.d2W(psi)), B], [B.T, np.zeros((nb, nb))]])
        rhs = np.concatenate([-R, np.zeros(nb)])
        try:
            delta = np.linalg.solve(K, rhs)[:M]
        except np.linalg.LinAlgError:
            delta = np.linalg.lstsq(K, rhs, rcond=1e-12)[0][:M]
        Rc = -a2 * (f["d2"] + D2 @ delta) + W.dW(psi + delta)
        return delta, Rc

    def slow_correction(self, p, cutoff=None):
        """One Newton step from the splice towards the slow manifold.

        Solves ``(-alpha^2 d^2 + W''(psi_N)) delta = -R_kappa`` modulo the front
        translation modes ``d psi_N / d p_j`` and a constant (``delta`` orthogonal
        to them: the positions and the total turning are kept). The splice
        superposes the fronts' tails linearly; ``delta`` is the nonlinear response
        (through the curvature of ``W'``) to the overlapping tails, of relative size
        ``O(exp(-lambda d / 2))`` in the centre of a gap of width ``d``.

        Returns
        -------
        delta : ndarray, shape (M,)
            On :attr:`sigma`.
        R : ndarray, shape (M,)
            The residual ``-alpha^2 kappa'' + W'(kappa)`` of ``psi_N + delta``.
        """
        return self._correction(self._fields(self._check(p), cutoff))

    def _normal(self, f):
        # d gamma / d p_j = -int_0^sigma n Theta_j. Theta_j = (periodic) + c_j s, so with
        # m = int_0^s n ds' (periodic on a closed curve) and
        # int_0^s s' n ds' = s m - int_0^s m ds', every cumulative integral is of a
        # periodic function: spectral (Fourier) accuracy, no end corrections. One real
        # FFT pair gives them all.
        theta, Theta, w = f["theta"], f["Theta"], f["w"]
        L, s = f["L"], self.grid.s
        k = Theta.shape[1]
        c = (L / s.size) * f["dpsi"].sum(axis=0)  # Theta_j(L)
        cs, sn_ = np.cos(theta), np.sin(theta)
        Y = np.empty((s.size, 4 + 2 * k))
        Y[:, 0], Y[:, 1], Y[:, 2], Y[:, 3] = cs, sn_, sn_, -cs  # tau, n
        periodic = Theta - s[:, None] * c
        np.multiply(sn_[:, None], periodic, out=Y[:, 4:4 + k])
        np.multiply(-cs[:, None], periodic, out=Y[:, 4 + k:])
        cum, mm = self._cumulative(Y, twice=[2, 3])  # mm = int_0^s m
        gx, gy = L * cum[:, 0], L * cum[:, 1]
        m = cum[:, 2:4]
        sn = s[:, None] * m - mm  # int_0^s s' n ds'
        dgx = -L * (cum[:, 4:4 + k] + sn[:, 0:1] * c)
        dgy = -L * (cum[:, 4 + k:] + sn[:, 1:2] * c)
        phi = sn_[:, None] * dgx - cs[:, None] * dgy
        R = np.column_stack([sn_, -cs, gx * cs + gy * sn_])
        Rw = R.T * w
        coef = np.linalg.solve(Rw @ R, Rw @ phi)
        return phi - R @ coef

    def normal_velocities(self, p, cutoff=None):
        """``phi_j^perp``: normal velocity per unit ``p_j'`` modulo rigid motions, (M, 2N).

        Also returns the quadrature weights ``dsigma`` (shape (M,)).
        """
        if self._kernel is not None:
            phi = self._run_kernel(p, cutoff, correction=False)[2]
            return phi.T.copy(), self.length * self.grid.weights
        f = self._fields(p, cutoff)
        return self._normal(f), f["w"]

    def metric(self, p, cutoff=None):
        """The pulled-back metric ``G_ij = int phi_i^perp phi_j^perp dsigma``, (2N, 2N)."""
        if self._kernel is not None:
            return self._run_kernel(p, cutoff, correction=False)[3]
        phi, w = self.normal_velocities(p, cutoff)
        return phi.T @ (w[:, None] * phi)

    @staticmethod
    def _constraints(f):
        c, s, w = np.cos(f["theta"]), np.sin(f["theta"]), f["w"]
        C = np.array([c @ w, s @ w, f["psi"] @ w - 2 * np.pi])
        return C, np.vstack([-(s * w) @ f["Theta"], (c * w) @ f["Theta"], w @ f["dpsi"]])

    def constraints(self, p, cutoff=None):
        """``C(p)`` (shape (3,), as :func:`qsa.equilibria.splice_closure`) and ``dC/dp`` (3, 2N)."""
        if self._kernel is not None:
            out = self._run_kernel(p, cutoff, correction=False)
            return out[5], out[6]
        return self._constraints(self._fields(p, cutoff))

    def velocity(self, p, cutoff=None, multipliers=False):
        """``F(p)``: the reduced velocity ``p'`` (shape (2N,)); with the multipliers if asked."""
        return self._velocity(self._check(p), cutoff, multipliers)

    def velocity_length(self, p, L, cutoff=None):
        """``(p', L')`` of the variable-length reduction (needs ``beta``), shapes (2N,), ()."""
        if self.beta is None:
            raise ValueError("velocity_length needs beta (a variable length)")
        v = self._velocity(self._check_length(p, L), cutoff, L=float(L))
        return v[:-1], float(v[-1])

    def _check_length(self, p, L):
        if not (np.isfinite(L) and L > 0):
            raise ValueError(f"L must be positive, got {L!r}")
        p = np.asarray(p, dtype=float)
        if p.ndim != 1 or p.size < 4 or p.size % 2 or np.any(np.diff(p) <= 0) \
                or p[-1] - p[0] >= L:
            raise ValueError("p must hold 2N >= 4 increasing positions spanning less than L")
        return p

    def _velocity(self, p, cutoff=None, multipliers=False, L=None):
        """:meth:`velocity` without the ordering check (trial stages of the integrator).

        With ``L`` (variable length, ``beta`` set) the unknowns are ``(p', L')``:
        inserting length at ``sigma = L`` moves no point of the curve (zero metric),
        so ``L'`` is tied to ``p'`` by the closure constraints; ``dE/dL`` and
        ``dC/dL`` at fixed ``p`` come from the images' tails
        (:meth:`_length_derivatives`).
        """
        if self._kernel is not None:
            sol, status = self._run_kernel(p, cutoff, L, full=False)
            if status == 1:  # degenerate constraints: as the numpy path
                K, rhs = itemgetter(7, 8)(self._run_kernel(p, cutoff, L))
                sol = np.linalg.lstsq(K, rhs, rcond=1e-12)[0]
            if status == 2:  # (a wild trial stage of the integrator)
                raise np.linalg.LinAlgError("Singular matrix")
            if status < 2:
                n = p.size + (L is not None)
                return (sol[:n], sol[n:]) if multipliers else sol[:n]
            # a singular solve in the Newton correction: the numpy path's fallbacks
        f = self._fields(p, cutoff, L)
        phi = self._normal(f)
        G = phi.T @ (f["w"][:, None] * phi)
        if self.correction == "newton":
            dE = (self._correction(f)[1] * f["w"]) @ f["dpsi"]
        else:
            dE = self._gradient(f)
        _, J = self._constraints(f)
        n = p.size
        A = np.vstack([J, np.ones((1, n)) / np.sqrt(n)])
        if L is not None:
            dEL, dCL = self._length_derivatives(f)
            dEL += self.beta * (L - self.L_star)
            G = np.pad(G, ((0, 1), (0, 1)))
            dE = np.append(dE, dEL)
            A = np.column_stack([A, np.append(dCL, 0.0)])
            n += 1
        K = np.zeros((n + 4, n + 4))
        K[:n, :n], K[:n, n:], K[n:, :n] = G, A.T, A
        rhs = np.zeros(n + 4)
        rhs[:n] = -dE
        try:
            sol = np.linalg.solve(K, rhs)
        except np.linalg.LinAlgError:  # degenerate constraints (e.g. a symmetric lens)
            sol = np.linalg.lstsq(K, rhs, rcond=1e-12)[0]
        return (sol[:n], sol[n:]) if multipliers else sol[:n]

    # ------------------------------------------------------------ linearization
    def tangent_basis(self, p, cutoff=None):
        """Orthonormal basis of ``{dC/dp . q = 0, sum q = 0}``, shape (2N, 2N - 4)."""
        p = self._check(p)
        _, J = self.constraints(p, cutoff)
        A = np.vstack([J, np.ones((1, p.size))])
        _, _, Vt = np.linalg.svd(A)
        return Vt[4:].T

    def jacobian(self, p, cutoff=None, step=None):
        """``dF/dp`` by central differences, shape (2N, 2N), and the tangent-space block.

        Returns
        -------
        J : ndarray, shape (2N, 2N)
        J_T : ndarray, shape (2N - 4, 2N - 4)
            ``T^T J T`` with ``T`` = :meth:`tangent_basis`: the linearization of the
            reduced flow on the splice manifold; its eigenvalues are the slow
            eigenvalues of the faceting flow at the splice.
        """
        p = self._check(p)
        cut = cutoff or self.cutoff or default_cutoff(p, self.length)
        h = 1e-3 * self.front.width if step is None else float(step)
        n = p.size
        J = np.empty((n, n))
        for j in range(n):
            e = np.zeros(n)
            e[j] = h
            J[:, j] = (self.velocity(p + e, cut) - self.velocity(p - e, cut)) / (2 * h)
        T = self.tangent_basis(p, cut)
        return J, T.T @ J @ T

    def eigenvalues(self, p, cutoff=None):
        """Eigenvalues of the tangent-space Jacobian (sorted by real part, descending)."""
        ev = np.linalg.eigvals(self.jacobian(p, cutoff)[1])
        return ev[np.argsort(-ev.real)]

    def crossings(self, p, cutoff=None):
        """Crossings of ``kstar/2`` by the splice profile (the detector's front positions)."""
        from qsa.reduction.fronts import detect_fronts

        prof = self.profile(p, cutoff)
        f = detect_fronts(prof(self.sigma), self.front.kstar, self.length)
        return f.positions

    # ------------------------------------------------------------ integration
    def integrate(self, p0, t_final, t_eval=None, rtol=1e-8, atol=None, method="auto",
                  max_collisions=10, close=True):
        """Integrate ``p' = F(p)`` from ``p0``, removing colliding pairs.

        Parameters
        ----------
        p0 : array_like, shape (2N,)
            Initial positions (closed to ``1e-12`` first when ``close``).
        t_final : float
        t_eval : array_like, optional
            Output times (default: the solver's steps).
        rtol, atol, method
            Passed to :func:`scipy.integrate.solve_ivp` (``atol`` default
            ``1e-9 * width``). With a variable length the implicit methods ("Radau",
            "BDF", "LSODA") get the Jacobian's length column only (one evaluation; the
            perimeter mode is the only stiff one). ``"auto"`` (default): RK45 at fixed
            length; with a variable length RK45 when the perimeter mode's rate ``mu``
            (``dL'/dL``, measured at the start of each segment) is mild over the
            interval, ``|mu| (t_final - t0) <= STIFF_AUTO = 100`` (e.g. the short facet,
            7.8), Radau otherwise (the triangle, 355): explicit steps would be limited
            by stability to ``~ 3.3 / |mu|``.
        max_collisions : int
        close : bool
            Project ``p0`` and the positions after each collision onto ``C = 0``.

        Returns
        -------
        FrontODEResult
        """
        import time

        if not (np.isfinite(t_final) and t_final > 0):
            raise ValueError(f"t_final must be positive, got {t_final!r}")
        start = time.perf_counter()
        p = self._check(p0)
        var = self.beta is not None
        L = float(self.length)
        ids = np.arange(p.size)  # track index of each current front
        t0, segments, events, nfev = 0.0, [], [], 0
        if t_eval is not None:
            t_eval = np.asarray(t_eval, dtype=float)
        atol = 1e-9 * self.front.width if atol is None else atol
        dc = self.collision_distance
        status, message = 0, "reached t_final"
        while True:
            cut = self.cutoff or default_cutoff(p, L)
            if close and not (self._kernel is not None and np.linalg.norm(
                    self._run_kernel(p, cut, L if var else None, False)[5]) <= 1e-12):
                # (the kernel's C on the ODE grid spares closing an already closed p0)
                p, hist, _ = close_positions(p, self.front, L, cut)

            last = {}  # the latest evaluation (the implicit methods' Jacobian reuses it)
            count = [0]

            def rhs(t, y, cut=cut, last=last, count=count):
                key = y.tobytes()
                if key in last:
                    return last[key]
                count[0] += 1
                q, Lq = (y[:-1], y[-1]) if var else (y, None)
                try:
                    v = self._velocity(q, cut, L=Lq)
                except np.linalg.LinAlgError:
                    v = None
                # a wild trial stage (fronts overrun near a collision): NaN makes the
                # Runge-Kutta error estimate reject the step and shrink it
                if v is None or not np.all(np.isfinite(v)):
                    v = np.full(y.size, np.nan)
                last.clear()
                last[key] = v
                return v

            def jac(t, y, cut=cut, rhs=rhs, count=count):
                # Only the length column: the stiffness of the variable-length flow is the
                # perimeter mode (eigenvalue ~ -2 pi beta / R), the positions are slow
                # (|dF/dp| ~ 1/t_c); a difference Jacobian would cost 2N + 1 evaluations.
                f0 = rhs(t, y)
                h = 1e-7 * y[-1]
                count[0] += 1
                J = np.zeros((y.size, y.size))
                J[:, -1] = (self._velocity(y[:-1], cut, L=y[-1] + h) - f0) / h
                return J

            def gap_event(t, y, L=L):
                q, Lq = (y[:-1], y[-1]) if var else (y, L)
                return np.min(np.diff(np.append(q, q[0] + Lq))) - dc

            gap_event.terminal = True
            gap_event.direction = -1
            te = None if t_eval is None else t_eval[(t_eval >= t0) & (t_eval <= t_final)]
            y0 = np.append(p, L) if var else p
            meth = method
            if method == "auto":
                meth = "RK45"
                if var:
                    mu = jac(t0, y0)[-1, -1]
                    meth = "Radau" if abs(mu) * (t_final - t0) > STIFF_AUTO else "RK45"
            implicit = var and meth in ("Radau", "BDF", "LSODA")
            sol = solve_ivp(rhs, (t0, t_final), y0, method=meth, t_eval=te, rtol=rtol,
                            atol=atol, events=gap_event, **({"jac": jac} if implicit else {}))
            nfev += count[0]
            Y = np.asarray(sol.y, dtype=float).reshape(y0.size, -1).T
            Ls = Y[:, -1] if var else np.full(Y.shape[0], L)
            segments.append(_Segment(np.asarray(sol.t, dtype=float), Y[:, : p.size],
                                     ids.copy(), cut, Ls))
            if sol.status == -1:
                status, message = -1, f"solve_ivp failed: {sol.message}"
                break
            if sol.status == 0:
                break
            tc, yc = float(sol.t_events[0][0]), sol.y_events[0][0]
            pc = yc[: p.size]
            if var:
                L = float(yc[-1])
            gaps = np.diff(np.append(pc, pc[0] + L))
            i = int(np.argmin(gaps))
            j = (i + 1) % pc.size
            events.append(ODECollision(tc, (int(ids[i]), int(ids[j])), float(gaps[i]),
                                       pc.copy(), ids.copy()))
            keep = np.ones(pc.size, dtype=bool)
            keep[[i, j]] = False
            q, qids = pc[keep], ids[keep]
            if j == 0:  # the pair straddled s = 0: the first kept front is a down-front
                q = np.append(q[1:], q[0] + L)
                qids = np.append(qids[1:], qids[0])
            if q.size < 4 or len(events) > max_collisions:
                status, message = 1, (f"stopped after collision at t={tc:.6g}: "
                                      f"{q.size} fronts left")
                break
            p, ids, t0 = q, qids, tc
        return FrontODEResult(segments, events, status == 0 or status == 1, status, message,
                              nfev, time.perf_counter() - start)


@dataclass(frozen=True)
class _Segment:
    t: np.ndarray
    p: np.ndarray  # (n_t, n_fronts)
    ids: np.ndarray
    cutoff: tuple
    L: np.ndarray  # (n_t,)


@dataclass(frozen=True)
class ODECollision:
    """A pair removed by :meth:`FrontODE.integrate`.

    Attributes
    ----------
    time : float
    fronts : (int, int)
        Track indices (positions in the initial ``p0``) of the pair.
    gap : float
        Their spacing at removal (``= d_c``).
    positions : ndarray
        All positions at the collision.
    ids : ndarray
        Track indices of ``positions``.
    """

    time: float
    fronts: tuple
    gap: float
    positions: np.ndarray
    ids: np.ndarray


@dataclass(frozen=True)
class FrontODEResult:
    """Result of :meth:`FrontODE.integrate`.

    Attributes
    ----------
    segments : list
        Pieces between collisions (``t``, ``p``, ``ids``, ``cutoff``).
    events : list of ODECollision
    success : bool
    status : int
        0 reached ``t_final``; 1 stopped after a collision left < 4 fronts; -1 failed.
    message : str
    nfev : int
        Evaluations of ``F`` (also those for the Jacobian of an implicit method).
    elapsed : float
        Wall time in seconds.
    """

    segments: list
    events: list
    success: bool
    status: int
    message: str
    nfev: int
    elapsed: float

    @property
    def t(self):
        """All output times, shape (n_t,)."""
        return np.concatenate([s.t for s in self.segments])

    @property
    def n_fronts(self):
        """Number of initial fronts."""
        return self.segments[0].p.shape[1]

    @property
    def positions(self):
        """Positions by initial track index, NaN after removal, shape (n_t, 2N)."""
        rows = []
        for s in self.segments:
            P = np.full((s.t.size, self.n_fronts), np.nan)
            P[:, s.ids] = s.p
            rows.append(P)
        return np.vstack(rows)

    @property
    def first_collision(self):
        """The first :class:`ODECollision`, or None."""
        return self.events[0] if self.events else None
