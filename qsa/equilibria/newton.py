"""Newton polishing of discrete equilibria: ``V^n = 0`` with closure, in scaled arc length.

The equilibrium equations of a gradient flow ``U_t = -M M-dagger nabla_I E`` are
``V^n(U) = -[M-dagger nabla_I E]_1 = 0`` (e:L2grad, e:Abs-CP) on the closed manifold
``C(U) = 0`` (e:C1, e:C2). They are geometric: every reparameterization of an
equilibrium is one. :func:`polish` fixes the gauge and solves a square system.

Gauge
-----
* *Reparameterization*: scaled arc length, ``g = L`` constant (one unknown ``L``).
* *Translation and rotation*: the intrinsic state ``(kappa, L)`` with fixed base
  angle ``theta0`` and base point ``gamma(0)`` does not see translations; a
  rotation of the curve is a shift of the parameter origin. The shift is fixed
  by the phase condition ``<kappa - kappa_ref, nabla_s kappa_ref> = 0`` against
  the initial guess.

Unknowns and equations (``N + 4`` each)::

    V^n(kappa, L) + sum_j a_j phi_j = 0      (N)
    C(kappa, L)                     = 0      (3)
    <kappa - kappa_ref, d_s kappa_ref> = 0   (1)

with unknowns ``x = (kappa, L, a_1, a_2, a_3)``. The unfolding fields ``phi_j`` are the
normal components of the rigid motions of the initial guess (``e1.n``, ``e2.n``,
``(gamma - gamma_c).tau``): on closed curves ``<V^n, phi_j> = 0`` identically
(``ker M-dagger`` argument, Conventions and errata, section 2), so the ``N + 3`` equations for
``N + 1`` unknowns are consistent but carry three redundancies; the unfolding
parameters ``a_j`` make the system square and are zero at the solution (their
size is reported: it measures how well the discrete identities hold). For
circles the shift and the rotation are void and the phase row and ``a_3`` are
dropped.

Jacobian
--------
Exact derivatives of the *discrete* residual (verified against central
differences in the tests). With ``mu = d_kappa E``, ``xi = g d_g E`` (``nabla_I E``
in ``<f, h> = int f h dsigma``) and ``H = nabla_I^2 E``, ::

    V^n = (Delta_s + kappa^2) mu - kappa xi,
    dV^n/dkappa = (Delta_s + kappa^2) H_kk + diag(2 kappa mu - xi) - diag(kappa g) H_gk,
    dV^n/dL     = (Delta_s + kappa^2)(H_kg 1 + H_gg-part - mu/L) - (2/L) Delta_s mu
                  - kappa L (H 1)_g,

(``d mu = [H dU]_kappa - (dg/g) mu``: the dsigma-gradient moves with its weight;
``d xi = g [H dU]_g``; ``Delta_s`` scales like ``1/L^2``). The closure rows are the
exact derivatives of the grid's quadrature of ``C`` with ``theta = theta0 + D kappa``.
Finite-difference grids give a sparse ``N x N`` block bordered by 4 dense
rows and columns, factored by sparse LU: O(N) per Newton step.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from qsa._checks import integer, real_number
from qsa.curve import Curve
from qsa.discretize import FiniteDifference
from qsa.energies import Energy
from qsa.constraints import bind_constraints, constraint_normals, flow_multipliers
from qsa.energies.constrained import multipliers, normal_velocity, residual_scale
from qsa.equilibria.constraint_terms import (
    area_energy_jacobian,
    constraint_jacobian,
    split_area_energies,
)
from qsa.equilibria.result import Equilibrium
from qsa.geometry import laplace_s
from qsa.linalg import SparsePlusLowRank

# multipliers, normal_velocity and residual_scale are properties of the energy on the
# closed manifold (qsa.energies.constrained); they are re-exported here for old imports.
__all__ = ["polish", "PolishResult", "MESSAGES", "NewtonRun", "newton_solve",
           "EquilibriumSystem", "multipliers", "residual_scale", "normal_velocity"]

_EPS = np.finfo(float).eps

#: Meaning of :attr:`PolishResult.status` (0 success, positive: success with a caveat,
#: negative: failure); :attr:`PolishResult.message` starts with the entry.
MESSAGES = {
    0: "converged: relative residual below tol",
    1: "converged to the round-off floor (tol is below what this grid can resolve)",
    -1: "maximum number of Newton iterations reached",
    -2: "singular or non-finite Newton system",
    -3: "line search failed: the residual does not decrease along the Newton direction",
}
#: Deprecated name of :data:`MESSAGES` (the failure codes were 2, 3, 4; now -1, -2, -3).
STATUS_MESSAGES = MESSAGES


@dataclass(frozen=True, eq=False)
class PolishResult(Equilibrium):
    """An :class:`Equilibrium` from :func:`polish`, with the Newton record.

    Besides the attributes of :class:`Equilibrium`:

    Attributes
    ----------
    status : int
        A key of :data:`MESSAGES`: 0 converged to ``tol``, 1 converged to the round-off
        floor, -1 ``maxiter`` reached, -2 singular system, -3 line search failed.
        ``success = status >= 0``.
    n_newton : int
        Newton steps taken (``n_iter`` is a read-only alias).
    n_lu : int
        Factorizations of the Newton matrix.
    history : ndarray, shape (n_newton + 1,)
        Relative residual of the square system before each step and at the end:
        ``max(max|V^n + a.phi| / scale, |C| / L)``.
    unfolding : ndarray, shape (3,)
        Final unfolding parameters ``a`` (zero up to round-off at a true equilibrium).
    noise_floor : float
        Estimated round-off level of the relative residual on this grid.
    constraints : tuple of Constraint
        The bound length / area constraints of the solve (empty without).
    constraint_multipliers : ndarray, shape (m,)
        Their multipliers ``mu_i``: ``nabla_I E = Lambda . Psi + sum_i mu_i nabla_I c_i``.

    Parameters
    ----------
    Constructed by :func:`polish`; the fields are the attributes above.

    Examples
    --------
    >>> from qsa.equilibria import circle
    >>> eq = circle(1.0, 0.1, kstar=5.0)
    >>> res = polish(eq.energy, eq.curve)
    >>> bool(res.success), res.status, res.n_newton <= 2
    (True, 0, True)
    """

    status: int = 0
    n_newton: int = 0
    n_lu: int = 0
    history: np.ndarray = field(default_factory=lambda: np.zeros(0))
    unfolding: np.ndarray = field(default_factory=lambda: np.zeros(3))
    noise_floor: float = 0.0
    constraints: tuple = ()
    constraint_multipliers: np.ndarray = field(default_factory=lambda: np.zeros(0))

    @property
    def n_iter(self) -> int:
        """Read-only alias of :attr:`n_newton` (the former name)."""
        return self.n_newton

    def summary(self) -> dict:
        """The :meth:`Equilibrium.summary` plus the Newton record (status, counters, history)."""
        out = super().summary()
        out.update(status=int(self.status), n_newton=int(self.n_newton), n_lu=int(self.n_lu),
                   history=[float(h) for h in self.history],
                   unfolding=[float(a) for a in self.unfolding],
                   noise_floor=float(self.noise_floor),
                   constraints=[k.params() for k in self.constraints],
                   constraint_multipliers=[float(m) for m in self.constraint_multipliers])
        return out


# ----------------------------------------------------------------------------- helpers
def _cumulative_transpose(grid, v, Cmat=None):
    """``C^T v`` for the grid's cumulative-integral matrix ``C`` (``C f = cumulative(f)``)."""
    v = np.asarray(v, dtype=float)
    if Cmat is not None:
        return Cmat.T @ v
    if isinstance(grid, FiniteDifference):
        # trapezoid: (C f)_i = h sum_{j<i} (f_j + f_{j+1})/2
        h = grid.h
        tail = np.concatenate([np.cumsum(v[::-1])[::-1][1:], [0.0]])  # sum_{i>k} v_i
        out = h * (tail + 0.5 * v)
        out[0] = 0.5 * h * tail[0]
        return out
    return grid.cumulative_matrix().T @ v


def _blocks(H, N):
    """``(H_kk, H_gk, H @ [0, 1], low)`` of a dense, sparse or sparse-plus-low-rank Hessian.

    ``low = (P_k, P_g, Q)`` holds the low-rank part restricted to kappa columns,
    ``H_kk += P_k Q^T``, ``H_gk += P_g Q^T`` (None if there is none).
    """
    ones = np.concatenate([np.zeros(N), np.ones(N)])
    col = H @ ones
    if isinstance(H, SparsePlusLowRank):
        S = H.S
        # keep the low-rank columns that act on kappa and reach the kappa or g rows
        keep = np.any(H.V[:N] != 0, axis=0) & np.any(H.U != 0, axis=0)
        low = (H.U[:N, keep], H.U[N:, keep], H.V[:N, keep]) if np.any(keep) else None
        return S[:N, :N].tocsr(), S[N:, :N].tocsr(), col, low
    if sp.issparse(H):
        H = H.tocsr()
        return H[:N, :N], H[N:, :N], col, None
    H = np.asarray(H)
    return H[:N, :N], H[N:, :N], col, None


def _equal_arclength(curve: Curve) -> Curve:
    """The same curve (same base point and angle) reparameterized to constant ``g``."""
    g = curve.g
    if np.max(np.abs(g - g.mean())) <= 1e-13 * g.mean():
        return curve if np.all(g == g[0]) else curve.with_g(np.full(curve.N, curve.length()))
    grid = curve.grid
    L = curve.length()
    # sigma(s)/L - s is periodic; invert sigma(s) = L t at t = s_j by Newton.
    p = grid.cumulative(g) / L - grid.s
    t = grid.s
    s = t.copy()
    for _ in range(50):
        r = s + grid.interpolate(p, s) - t
        ds = r / (grid.interpolate(g, s) / L)
        s = s - ds
        if np.max(np.abs(ds)) < 1e-15:
            break
    kappa = grid.interpolate(curve.kappa, s)
    return Curve(kappa, L, grid, curve.theta0, curve.origin)


# ------------------------------------------------------------------------ the system
class EquilibriumSystem:
    """The square system ``F(x) = 0`` of :func:`polish` (see the module docstring).

    Parameters
    ----------
    energy : Energy
    reference : Curve
        Initial guess with constant ``g``: supplies the grid, ``theta0``, ``gamma(0)``,
        the phase reference and the unfolding fields ``phi_j``.
    constraints : sequence of Constraint, optional
        Bound length / area constraints (:func:`qsa.constraints.bind_constraints`): one
        multiplier ``mu_i`` (appended to the unknowns) and one equation each
        (:mod:`qsa.equilibria.constraint_terms`).

    Examples
    --------
    >>> import numpy as np
    >>> from qsa.equilibria import circle
    >>> eq = circle(1.0, 0.1, kstar=5.0)
    >>> system = EquilibriumSystem(eq.energy, eq.curve)
    >>> x = system.pack(eq.curve)  # [kappa, L, a, ...]: 33 + 3 unknowns
    >>> F = system.residual(x)
    >>> x.size, bool(np.abs(F).max() < 1e-10), system.jacobian(x).shape == (36, 36)
    (36, True, True)
    """

    def __init__(self, energy, reference: Curve, constraints=()):
        self.energy = energy
        self.constraints = tuple(constraints)
        for con in self.constraints:
            if con.target is None:
                raise ValueError("constraints must be bound to a curve first "
                                 "(qsa.constraints.bind_constraints)")
        self.m = len(self.constraints)
        self.ref = reference
        self.grid = reference.grid
        self.N = reference.N
        c = reference
        N = self.N
        dk = self.grid.derivative() @ c.kappa
        self.circle = bool(np.max(np.abs(dk)) <= 1e-9 * max(np.max(np.abs(c.kappa)), 1e-300))
        w = self.grid.weights
        tau, n = c.tangent(), c.normal()
        xy = c.positions()
        centre = (xy @ c.dsigma) / c.length()
        rot = np.sum((xy - centre[:, None]) * tau, axis=0)
        phis = [n[0], n[1]] if self.circle else [n[0], n[1], rot]
        self.phi = np.array([f / np.sqrt((f**2) @ w) for f in phis])  # (m, N)
        if self.circle:
            self.phase = None
        else:
            self.phase = w * dk / np.linalg.norm(w * dk)
            self.phase_value = float(self.phase @ c.kappa)
        self.n_unfold = self.phi.shape[0]
        self._Cmat = None if self.grid.sparse else self.grid.cumulative_matrix()
        self.size = N + 1 + self.n_unfold + self.m

    # state <-> curve
    def pack(self, curve: Curve, mu=None) -> np.ndarray:
        """Unknowns ``x = [kappa (N,), L, a (n_unfold,), mu (m,)]`` of a constant-g curve.

        ``a = 0``; ``mu`` (the constraints' multipliers) defaults to the projection of
        ``V^n`` of :attr:`energy` (:func:`qsa.constraints.flow_multipliers`).
        """
        if mu is None:
            mu = (flow_multipliers(self.constraints, curve, normal_velocity(self.energy, curve))
                  if self.m else np.zeros(0))
        return np.concatenate([curve.kappa, [curve.g[0]], np.zeros(self.n_unfold),
                               np.asarray(mu, dtype=float).reshape(self.m)])

    def unfolding(self, x) -> np.ndarray:
        """The unfolding parameters ``a`` of unknowns ``x``, shape (n_unfold,)."""
        return np.asarray(x[self.N + 1: self.N + 1 + self.n_unfold])

    def constraint_multipliers(self, x) -> np.ndarray:
        """The multipliers ``mu`` of the constraints in unknowns ``x``, shape (m,)."""
        return np.asarray(x[self.size - self.m:])

    def curve(self, x) -> Curve:
        """The :class:`~qsa.curve.Curve` of unknowns ``x`` (``g = L``, reference base point)."""
        N = self.N
        return Curve(x[:N], x[N], self.grid, self.ref.theta0, self.ref.origin)

    def residual(self, x, energy=None) -> np.ndarray:
        """``F(x)``, shape (size,): ``[V^n + a.phi + mu.n, C, phase, c - c*]``.

        Parameters
        ----------
        x : ndarray, shape (size,)
            Unknowns (:meth:`pack`).
        energy : Energy, optional
            Another energy on the same system (default the system's).

        Returns
        -------
        ndarray, shape (size,)
        """
        energy = self.energy if energy is None else energy
        N = self.N
        c = self.curve(x)
        V = normal_velocity(energy, c) + self.unfolding(x) @ self.phi
        if self.m:
            V = V + self.constraint_multipliers(x) @ constraint_normals(self.constraints, c)
        parts = [V, c.closure()]
        if self.phase is not None:
            parts.append([self.phase @ x[:N] - self.phase_value])
        parts.append([con.defect(c) for con in self.constraints])
        return np.concatenate(parts)

    def _constraint_rows(self):
        """Index of the first constraint row of ``F``."""
        return self.N + 3 + (self.phase is not None)

    def scaled_parts(self, F, c: Curve, scale: float) -> np.ndarray:
        """``(max|F_V| / scale, |F_C| / L, |F_phase| / max|kappa|, max |c - c*| / |c*|)``, (4,).

        Parameters
        ----------
        F : ndarray, shape (size,)
            :meth:`residual`.
        c : Curve
            :meth:`curve` of the same ``x``.
        scale : float
            :func:`residual_scale` at ``c``.

        Returns
        -------
        ndarray, shape (4,)
        """
        N = self.N
        out = np.zeros(4)
        out[0] = np.max(np.abs(F[:N])) / scale
        out[1] = np.linalg.norm(F[N:N + 3]) / c.length()
        if self.phase is not None:
            out[2] = abs(F[N + 3]) / max(np.max(np.abs(c.kappa)), 1.0)
        if self.m:
            out[3] = np.max(np.abs(self._scaled_defects(F)))
        return out

    def _scaled_defects(self, F):
        r = self._constraint_rows()
        return F[r:r + self.m] / np.array([abs(con.target) for con in self.constraints])

    def step_norm(self, dx, x, scale: float) -> float:
        """Size of a change ``dx`` of the unknowns ``x``: a scaled RMS norm in state space.

        ``kappa`` is measured against ``max(max|kappa|, 2 pi / L)``, ``L`` against ``L``,
        the unfolding parameters against the residual scale (they have the units of
        ``V^n``) and a constraint multiplier ``mu_i`` against the residual scale over
        ``max|n_i|``. The Newton line search compares Newton corrections in this norm
        (the natural monotonicity test of :func:`newton_solve`).

        Parameters
        ----------
        dx, x : ndarray, shape (size,)
        scale : float
            :func:`residual_scale` at ``x``.

        Returns
        -------
        float
        """
        N = self.N
        L = abs(x[N])
        k_scale = max(float(np.max(np.abs(x[:N]))), 2 * np.pi / L)
        m = np.mean((dx[:N] / k_scale) ** 2) + (dx[N] / L) ** 2
        m += np.sum((self.unfolding(dx) / scale) ** 2)
        if self.m:
            c = self.curve(x)
            n_size = np.array([np.max(np.abs(con.normal_variation(c)))
                               for con in self.constraints])
            m += np.sum((self.constraint_multipliers(dx) * n_size / scale) ** 2)
        return float(np.sqrt(m))

    def scaled_norm(self, F, c: Curve, scale: float) -> float:
        """``max`` of :meth:`scaled_parts`: the relative residual of the square system.

        Parameters
        ----------
        F, c, scale
            As in :meth:`scaled_parts`.

        Returns
        -------
        float
        """
        return float(np.max(self.scaled_parts(F, c, scale)))

    def jacobian_parts(self, x, energy=None):
        """Blocks of ``dF/dx``: the ``N x N`` block ``A`` and dense borders.

        Returns
        -------
        A : matrix (N, N)
            ``dV^n/dkappa`` (sparse for finite differences, dense for Fourier).
        B : ndarray (N, m)
            Columns ``dV^n/dL``, ``phi_j`` and ``n_i`` (the constraints' multipliers).
        Crows : ndarray (m', N)
            Closure (phase, constraint) rows, derivatives w.r.t. kappa.
        D : ndarray (m', m)
            Their derivatives w.r.t. ``(L, a, mu)``.
        low : list of (P, Q)
            Low-rank terms ``P Q^T`` of ``A`` (from sparse-plus-low-rank Hessians and
            area penalties).
        """
        energy = self.energy if energy is None else energy
        N = self.N
        grid = self.grid
        c = self.curve(x)
        L = x[N]
        k = c.kappa
        lap = laplace_s(c)
        Gm = lap + grid.diag(k**2)  # = -G
        diag = grid.diag
        # area energies have the exact constant V^n = -F'(A): their own derivatives
        rest, area_terms = split_area_energies(energy)
        low = []
        if rest is not None:
            grad = rest.gradient(c)
            mu, xi = grad[:N], L * grad[N:]
            H = rest.hessian(c)
            Hkk, Hgk, Hcol, lowH = _blocks(H, N)
            A = Gm @ Hkk + diag(2 * k * mu - xi) - diag(k * L) @ Hgk
            if lowH is not None:
                Pk, Pg, Q = lowH
                low.append((Gm @ Pk - (k * L)[:, None] * Pg, Q))
            dmu = Hcol[:N] - mu / L
            dxi = L * Hcol[N:]
            VL = Gm @ dmu - (2.0 / L) * (lap @ mu) - k * dxi
        else:
            A = diag(np.zeros(N))
            VL = np.zeros(N)
        low_area, VL_area = area_energy_jacobian(area_terms, c)
        if low_area is not None:
            low.append(low_area)
        VL = VL + VL_area
        cj = constraint_jacobian(self.constraints, c, self.constraint_multipliers(x))
        if np.any(cj.diagonal != 0):
            A = A + diag(cj.diagonal)
        if sp.issparse(A):
            A = A.tocsr()
        B = np.column_stack([VL, self.phi.T, cj.columns])
        # closure rows: exact derivatives of the quadrature of C
        w = grid.weights
        th = c.theta()
        g = c.g
        cs, sn = np.cos(th), np.sin(th)
        Ct1 = _cumulative_transpose(grid, -w * g * sn, self._Cmat)
        Ct2 = _cumulative_transpose(grid, w * g * cs, self._Cmat)
        rows = [g * Ct1, g * Ct2, w * g]
        dL = [np.sum(w * cs) + Ct1 @ k, np.sum(w * sn) + Ct2 @ k, np.sum(w * k)]
        m = B.shape[1]
        if self.phase is not None:
            rows.append(self.phase)
            dL.append(0.0)
        rows.extend(cj.rows)
        dL.extend(cj.dL)
        Crows = np.array(rows)
        D = np.zeros((len(rows), m))
        D[:, 0] = dL
        return A, B, Crows, D, low

    def jacobian(self, x, energy=None):
        """Assembled ``dF/dx``, shape (size, size): sparse CSC for FD, dense for Fourier.

        Parameters
        ----------
        x : ndarray, shape (size,)
        energy : Energy, optional

        Returns
        -------
        sparse CSC matrix or ndarray, shape (size, size)
            Euclidean derivative ``dF/dx`` (no inner-product weights).
        """
        A, B, Crows, D, low = self.jacobian_parts(x, energy)
        return _assemble(A, B, Crows, D, low)


def _assemble(A, B, Crows, D, low):
    """``[[A, B, P], [Crows, D, 0], [Q^T, 0, -I]]`` (low-rank terms of A unfolded)."""
    if low:
        P = np.hstack([p for p, _ in low])
        Q = np.hstack([q for _, q in low])
        r = P.shape[1]
    else:
        r = 0
    mB, mC = B.shape[1], Crows.shape[0]
    if sp.issparse(A):
        blocks = [[A, sp.csr_matrix(B)], [sp.csr_matrix(Crows), sp.csr_matrix(D)]]
        if r:
            blocks[0].append(sp.csr_matrix(P))
            blocks[1].append(None)
            blocks.append([sp.csr_matrix(Q.T), None, -sp.identity(r)])
        return sp.bmat(blocks, format="csc")
    top = np.hstack([A, B] + ([P] if r else []))
    mid = np.hstack([Crows, D] + ([np.zeros((mC, r))] if r else []))
    rows = [top, mid]
    if r:
        rows.append(np.hstack([Q.T, np.zeros((r, mB)), -np.eye(r)]))
    return np.vstack(rows)


class _Factor:
    """LU factorization of the Newton matrix (sparse or dense) with the sign of its determinant."""

    def __init__(self, J):
        self.sparse = sp.issparse(J)
        self.n = J.shape[0]
        if self.sparse:
            self.lu = spla.splu(sp.csc_matrix(J), permc_spec="COLAMD")
            diagU = self.lu.U.diagonal()
            self.singular = not np.all(np.isfinite(diagU)) or np.min(np.abs(diagU)) == 0
            self._diag = diagU
        else:
            self.lu = sla.lu_factor(J, check_finite=True)
            self._diag = np.diag(self.lu[0])
            self.singular = np.min(np.abs(self._diag)) == 0

    def solve(self, b):
        if self.sparse:
            return self.lu.solve(b)
        return sla.lu_solve(self.lu, b)

    def det_sign(self) -> int:
        """Sign of ``det J`` (from the LU diagonal and the permutation parities)."""
        s = int(np.prod(np.sign(self._diag)))
        if self.sparse:
            s *= _perm_parity(self.lu.perm_r) * _perm_parity(self.lu.perm_c)
        else:
            piv = self.lu[1]
            s *= (-1) ** int(np.sum(piv != np.arange(piv.size)))
        return s


def _perm_parity(p) -> int:
    p = np.asarray(p)
    seen = np.zeros(p.size, dtype=bool)
    parity = 0
    for i in range(p.size):
        if not seen[i]:
            j, length = i, 0
            while not seen[j]:
                seen[j] = True
                j = p[j]
                length += 1
            parity += length - 1
    return -1 if parity % 2 else 1


def _noise_floor(system, x, scale, energy=None, seed=0):
    """Relative residual change under a perturbation of x at the rounding level."""
    rng = np.random.default_rng(seed)
    F0 = system.residual(x, energy)
    x1 = x * (1 + _EPS * rng.choice([-1.0, 1.0], size=x.size))
    F1 = system.residual(x1, energy)
    return system.scaled_parts(F1 - F0, system.curve(x), scale)


def _at_floor(system, x, F, scale, tol, floor):
    """Every part of the residual is below ``max(tol, 100 x its round-off floor)``."""
    parts = system.scaled_parts(F, system.curve(x), scale)
    return bool(np.all(parts <= np.maximum(tol, 100 * floor)))


def _check_curve(energy, curve):
    if not isinstance(curve, Curve):
        raise ValueError(f"curve must be a qsa Curve, got {type(curve).__name__}")
    if not isinstance(energy, Energy):
        raise ValueError(f"energy must be a qsa Energy, got {type(energy).__name__}")


@dataclass(frozen=True, eq=False)
class NewtonRun:
    """The record of :func:`newton_solve`.

    Attributes
    ----------
    x : ndarray, shape (system.size,)
        The best state found (the last one unless a later step was worse).
    status : int
        A key of :data:`MESSAGES`.
    history : ndarray, shape (n_newton + 1,)
        Relative residual before each step and at the end.
    n_newton, n_lu : int
        Newton steps taken and factorizations of the Newton matrix.
    noise_floor : float
        Estimated round-off level of the relative residual.
    """

    x: np.ndarray
    status: int
    history: np.ndarray
    n_newton: int
    n_lu: int
    noise_floor: float

    @property
    def success(self) -> bool:
        """``status >= 0``."""
        return self.status >= 0


def newton_solve(system, x0, tol=1e-10, maxiter=30, energy=None, line_search=True) -> NewtonRun:
    """Damped Newton on ``system.residual`` from ``x0``.

    Step control (``line_search=True``): a trial step ``x + t dx`` (``t = 1, 1/2, ...``,
    at most 10 halvings) is accepted when the relative residual decreases, or when it
    passes the *natural monotonicity test*

        ||J(x)^{-1} F(x + t dx)|| <= (1 - t/4) ||dx||

    in the state norm :meth:`EquilibriumSystem.step_norm` (one more solve with the
    factorization of ``J(x)``). The residual itself is a poor merit for the
    equilibrium equations: ``V^n`` is a differential operator of order 4 (faceting)
    or 6 (second-order energies) in ``kappa``, so the quadratic error of a good
    Newton step, being rough, can raise ``max|V^n|`` a hundredfold although the state
    moved towards the solution. The natural test measures the residual in the norm of
    the Newton corrections instead (it is invariant under any rescaling of the
    equations), so full steps are taken wherever Newton converges. Never raises for
    non-convergence: the best state (smallest relative residual, never worse than
    ``x0``) is returned with a status code (a key of :data:`MESSAGES`).

    Parameters
    ----------
    system : EquilibriumSystem
    x0 : ndarray, shape (system.size,)
    tol : float
        Target of :meth:`EquilibriumSystem.scaled_norm`.
    maxiter : int
    energy : Energy, optional
        Another energy on the same system (default the system's).
    line_search : bool

    Returns
    -------
    NewtonRun
    """
    x = np.array(x0, dtype=float)
    scale = residual_scale(system.energy if energy is None else energy, system.curve(x))
    F = system.residual(x, energy)
    r = system.scaled_norm(F, system.curve(x), scale)
    history = [r]
    best = (r, x.copy())
    status = -1
    floor = None
    n_newton = n_lu = 0
    for it in range(maxiter + 1):
        if not np.isfinite(r):
            status = -2
            break
        if r <= tol:
            status = 0
            break
        if it == maxiter:
            status = -1
            break
        try:
            n_lu += 1
            fac = _Factor(system.jacobian(x, energy))
            if fac.singular:
                status = -2
                break
            dx = -fac.solve(F)
        except (RuntimeError, np.linalg.LinAlgError, ValueError):
            status = -2
            break
        if not np.all(np.isfinite(dx)):
            status = -2
            break
        size = system.step_norm(dx, x, scale)
        t = 1.0
        accepted = False
        for _ in range(11 if line_search else 1):
            xt = x + t * dx
            if xt[system.N] > 0:
                try:
                    Ft = system.residual(xt, energy)
                    rt = system.scaled_norm(Ft, system.curve(xt), scale)
                except ValueError:
                    rt = np.inf
                if np.isfinite(rt) and (not line_search or rt < r
                                        or _natural_test(system, fac, Ft, x, scale, size, t)):
                    accepted = True
                    break
            t *= 0.5
        n_newton += 1
        if not accepted:
            # At the round-off floor no step can decrease the residual any more.
            floor = _noise_floor(system, x, scale, energy)
            status = 1 if _at_floor(system, x, F, scale, tol, floor) else -3
            break
        x, F, r = xt, Ft, rt
        history.append(r)
        if r < best[0]:
            best = (r, x.copy())
        # Stagnation at the round-off floor: a step that no longer gains much.
        if len(history) >= 3 and r > 0.5 * history[-2]:
            floor = _noise_floor(system, x, scale, energy)
            if _at_floor(system, x, F, scale, tol, floor):
                status = 1 if r > tol else 0
                break
    if best[0] < r:
        x, r = best[1], best[0]
    if floor is None:
        floor = _noise_floor(system, x, scale, energy)
    return NewtonRun(x, status, np.array(history), n_newton, n_lu, float(np.max(floor)))


def _natural_test(system, fac, Ft, x, scale, size, t) -> bool:
    """``||J(x)^{-1} F(x + t dx)|| <= (1 - t/4) ||dx||`` (restricted monotonicity test)."""
    try:
        dxbar = fac.solve(Ft)
    except (RuntimeError, ValueError):
        return False
    return bool(np.all(np.isfinite(dxbar))
                and system.step_norm(dxbar, x, scale) <= (1 - t / 4) * size)


def _params(energy, curve, Lambda, constraints=(), mu=()):
    params = {"L": curve.length(), "A": curve.area()}
    for t in energy.terms():
        for name in ("alpha", "kstar", "eps", "beta", "L_star", "p"):
            v = getattr(t, name, None)
            if isinstance(v, (int, float)) and name not in params:
                params[name] = float(v)
    if "beta" in params and "L_star" in params:
        params["nu2"] = params["beta"] * (params["L"] - params["L_star"])
    params["nu1"] = float(-Lambda[2])
    for con, m in zip(constraints, mu, strict=True):
        params[f"mu_{con.symbol}"] = float(m)
    return params


def polish(energy, curve: Curve, tol=1e-10, maxiter=30, *, line_search=True,
           constraints=None) -> PolishResult:
    """Polish an approximate equilibrium by Newton's method on ``V^n = 0`` with closure.

    Parameters
    ----------
    energy : Energy
        E.g. ``Faceting(alpha, kstar) + Perimeter(beta, L_star)``.
    curve : Curve
        Initial guess (an N-pulse, a splice, a relaxed flow state...). If its ``g``
        is not constant it is first reparameterized to constant ``g`` (same base
        point, same base angle).
    tol : float
        Target for the relative residual ``max(max|V^n| / scale, |C(U)| / L)``,
        ``scale`` = the largest single term of ``V^n`` (:func:`residual_scale`).
    maxiter : int
        Maximum number of Newton steps.
    line_search : bool
        Damp the Newton step (default True): halve it until the relative residual
        decreases or the natural monotonicity test in state space passes (see
        :func:`newton_solve`); full steps are taken wherever Newton converges.
    constraints : sequence of Constraint, optional
        Exact constraints besides closure, e.g. ``[FixedLength(), FixedArea()]``
        (:mod:`qsa.constraints`; a ``None`` target is the value of ``curve``). The
        equations become ``V^n + sum_i mu_i n_i = 0`` with ``c_i = c_i*`` (``n_L = kappa``,
        ``n_A = 1``), the multipliers ``mu_i`` unknowns of the Newton system
        (:mod:`qsa.equilibria.constraint_terms`).

    Returns
    -------
    PolishResult
        An :class:`Equilibrium` (``kind="polished"``) with ``residual = max|V^n|``
        (``max|V^n + sum_i mu_i n_i|`` with constraints),
        ``closure = |C(U)|``, ``multipliers`` (Lambda, by projection of
        ``nabla_I E`` on ``span Psi`` in ``<f, h> = int f h dsigma``), ``params``
        (``L``, the energy's parameters, ``nu1 = -Lambda_3``, ``nu2 = beta (L - L*)``
        when a perimeter term is present), plus ``status``, ``n_newton``, ``n_lu``, ``history``
        (relative residual per iteration), ``unfolding``, ``noise_floor``, and the
        bound ``constraints`` with their ``constraint_multipliers`` (also in ``params``
        as ``mu_L``, ``mu_A``: ``mu_A`` is the pressure holding the shape). A solve
        that does not converge returns ``success=False`` with the best state found.

    Raises
    ------
    ValueError
        ``energy``/``curve`` of the wrong type, ``tol <= 0``, ``maxiter < 0`` or bad
        ``constraints``.

    Notes
    -----
    The square system, its gauge and its exact Jacobian are described in the
    module docstring (e:L2grad, e:Abs-CP, e:C1, e:C2). On a finite-difference
    grid the Newton matrix is sparse with four dense borders (sparse LU, O(N)
    per step); on a Fourier grid it is dense.

    Examples
    --------
    >>> from qsa import Curve, Fourier
    >>> from qsa.energies import Faceting, Perimeter
    >>> from qsa.equilibria import npulse
    >>> eq = npulse(3, 0.15, grid=Fourier(127))
    >>> res = polish(eq.energy, eq.curve)
    >>> bool(res.success), res.residual < 1e-8 * res.residual_scale
    (True, True)

    An inextensible ring under pressure relaxes to the circle of its length, with
    ``mu_L = -R (p + eps / (2 R^3))`` (here ``R = 1``):

    >>> import numpy as np
    >>> from qsa.constraints import FixedLength
    >>> from qsa.energies import CanhamHelfrich, Pressure
    >>> c = Curve.polar(lambda t: 1 + 0.01 * np.cos(2 * t), Fourier(33))
    >>> res = polish(CanhamHelfrich(1.0) + Pressure(-1.0), c,
    ...              constraints=[FixedLength(2 * np.pi)])
    >>> bool(res.success), round(res.params["L"] / np.pi, 10), round(res.params["mu_L"], 8)
    (True, 2.0, 0.5)
    """
    _check_curve(energy, curve)
    tol = real_number(tol, "tol", positive=True)
    maxiter = integer(maxiter, "maxiter", minimum=0)
    cons = bind_constraints(constraints, curve)
    guess = _equal_arclength(curve)
    system = EquilibriumSystem(energy, guess, cons)
    run = newton_solve(system, system.pack(guess), tol, maxiter, line_search=line_search)
    return polish_result(energy, system, run, reparameterized=curve is not guess)


def polish_result(energy, system, run: NewtonRun, reparameterized=False) -> PolishResult:
    """The :class:`PolishResult` of a Newton run on ``system`` (residuals, multipliers, message).

    Parameters
    ----------
    energy : Energy
        The energy the state is an equilibrium of.
    system : EquilibriumSystem
    run : NewtonRun
    reparameterized : bool
        Say in the message that the guess was reparameterized to constant ``g``.

    Returns
    -------
    PolishResult
    """
    x, status = run.x, run.status
    c = system.curve(x)
    cons = system.constraints
    mu = np.array(system.constraint_multipliers(x), dtype=float)
    V = normal_velocity(energy, c)
    if cons:
        V = V + mu @ constraint_normals(cons, c)
    scale = residual_scale(energy, c)
    res = float(np.max(np.abs(V)))
    clo = float(np.linalg.norm(c.closure()))
    Lambda = multipliers(energy, c, constraints=cons)[:3]
    name = "max|V^n + mu.n|" if cons else "max|V^n|"
    msg = (f"{MESSAGES[status]}; {run.n_newton} Newton steps, {name} = {res:.2e} "
           f"({res / scale:.1e} of the largest term), |C(U)| = {clo:.2e}, "
           f"round-off floor ~{run.noise_floor:.1e}")
    if cons:
        msg += "; " + ", ".join(f"{k.symbol} = {k.value(c):.10g} (mu_{k.symbol} = {m:.6g})"
                                for k, m in zip(cons, mu, strict=True))
    if reparameterized:
        msg += "; the guess was reparameterized to constant g"
    a = np.array(system.unfolding(x), dtype=float)
    unfolding = a if a.size == 3 else np.concatenate([a, [0.0]])
    return PolishResult(c, energy, _params(energy, c, Lambda, cons, mu), Lambda, res, clo, scale,
                        kind="polished", success=status >= 0, message=msg, status=status,
                        n_newton=run.n_newton, n_lu=run.n_lu,
                        history=np.asarray(run.history, dtype=float), unfolding=unfolding,
                        noise_floor=float(run.noise_floor), constraints=cons,
                        constraint_multipliers=mu)
