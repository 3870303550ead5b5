"""The square system of the discrete equilibria: ``V^n = 0`` with closure, in scaled arc length.

The equilibrium equations of a gradient flow ``U_t = -M M-dagger nabla_I E`` are
``V^n(U) = -[M-dagger nabla_I E]_1 = 0`` (e:L2grad, e:Abs-CP) on the closed manifold
``C(U) = 0`` (e:C1, e:C2). They are geometric: every reparameterization of an
equilibrium is one. :class:`EquilibriumSystem` fixes the gauge and poses a square
system ``F(x) = 0`` with its exact Jacobian; :func:`qsa.equilibria.polish` solves it by
Newton's method and :mod:`qsa.continuation` follows its solutions in a parameter.

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
rows and columns (:func:`assemble_jacobian`), factored by sparse LU: O(N) per Newton
step. Two-point energies (whose ``V^n`` is evaluated from the node positions) are
differentiated through the positions instead, which become extra sparse unknowns on
finite-difference grids (:mod:`qsa.equilibria.two_point_terms`).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from qsa.constraints import constraint_normals, flow_multipliers
from qsa.curve import Curve
from qsa.energies.constrained import normal_velocity
from qsa.equilibria.constraint_terms import (
    area_energy_jacobian,
    constraint_jacobian,
    split_area_energies,
)
from qsa.equilibria.two_point_terms import (
    StateBorder,
    add_velocity_jacobians,
    split_velocity_terms,
)
from qsa.geometry import laplace_s
from qsa.linalg import SparsePlusLowRank

__all__ = ["EquilibriumSystem", "assemble_jacobian", "bordered_matrix", "equal_arclength"]


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


def equal_arclength(curve: Curve) -> Curve:
    """The same curve (same base point and angle) reparameterized to constant ``g``.

    The gauge of :class:`EquilibriumSystem` (scaled arc length, ``g = L``). A curve
    whose ``g`` is constant to ``1e-13`` is returned as it is (or with ``g`` set to
    its length exactly); otherwise ``sigma(s) = L t`` is inverted at ``t = s_j`` by
    Newton and ``kappa`` interpolated there.

    Parameters
    ----------
    curve : Curve

    Returns
    -------
    Curve
        On the same grid, ``g = curve.length()`` at every node.

    Examples
    --------
    >>> import numpy as np
    >>> from qsa import Curve, Fourier
    >>> grid = Fourier(33)
    >>> c = Curve(np.full(33, 2 * np.pi / 3.0), 3.0 * (1 + 0.1 * np.cos(2 * np.pi * grid.s)), grid)
    >>> e = equal_arclength(c)
    >>> bool(np.ptp(e.g) == 0), bool(np.isclose(e.length(), c.length(), rtol=1e-12))
    (True, True)
    """
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
    return Curve(kappa, np.full(grid.N, float(L)), grid, curve.theta0, curve.origin)


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
        (the natural monotonicity test of :func:`~qsa.equilibria.newton.newton_solve`).

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
        low : list of (P, Q) and StateBorder
            Low-rank terms ``P Q^T`` of ``A`` (from sparse-plus-low-rank Hessians and
            area penalties) and, on finite-difference grids, the position state of
            two-point energies (:mod:`qsa.equilibria.two_point_terms`).
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
        # two-point energies: V^n from the positions, differentiated through them
        rest, implicit = split_velocity_terms(rest)
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
        A, VL = add_velocity_jacobians(implicit, c, A, VL, low)
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
        Ct1, Ct2 = grid.cumulative_transpose(np.column_stack([-w * g * sn, w * g * cs])).T
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
        return assemble_jacobian(A, B, Crows, D, low)

    def bordered_jacobian(self, x, column, row, corner=0.0, energy=None):
        """``[[dF/dx, column], [row, corner]]`` with one extra unknown and one extra equation.

        The extra unknown follows ``x`` (index ``size``) and the extra equation follows
        the rows of ``F`` (index ``size``); any unknowns the Newton matrix unfolds
        (low-rank terms, implicit states) come after them, with zero right-hand side.
        The matrix of continuation's tangent and corrector.

        Parameters
        ----------
        x : ndarray, shape (size,)
        column : ndarray, shape (size,)
            Derivative of ``F`` with respect to the extra unknown.
        row : ndarray, shape (size,)
            Derivative of the extra equation with respect to ``x``.
        corner : float
            Derivative of the extra equation with respect to the extra unknown.
        energy : Energy, optional

        Returns
        -------
        sparse CSC matrix or ndarray
            Square, of size ``size + 1`` plus the unfolded unknowns.
        """
        return bordered_matrix(self.jacobian_parts(x, energy), column, row, corner)


def bordered_matrix(parts, column, row, corner=0.0):
    """:meth:`EquilibriumSystem.bordered_jacobian` from the blocks of ``jacobian_parts``."""
    A, B, Crows, D, low = parts
    N = A.shape[0]
    B2 = np.column_stack([B, column[:N]])
    C2 = np.vstack([Crows, row[:N]])
    D2 = np.zeros((D.shape[0] + 1, D.shape[1] + 1))
    D2[:-1, :-1] = D
    D2[:-1, -1] = column[N:]
    D2[-1, :-1] = row[N:]
    D2[-1, -1] = corner
    return assemble_jacobian(A, B2, C2, D2, low)


def assemble_jacobian(A, B, Crows, D, low):
    """The bordered sparse matrix of the Newton step, with low-rank terms and states unfolded.

    ``[[A, B, P, VY], [Crows, D, 0, 0], [Q^T, 0, -I, 0], [cK, cL e_1^T, 0, cY]]``.
    The low-rank terms ``P Q^T`` of ``A`` are unfolded into extra unknowns ``z = Q^T dx``
    (rows ``Q^T dx - z = 0``), and implicit states
    (:class:`~qsa.equilibria.two_point_terms.StateBorder`) into extra unknowns ``Y1``
    with their sparse equations, so the matrix stays sparse.

    Parameters
    ----------
    A : matrix, shape (N, N)
    B : ndarray, shape (N, m)
        Its first column is ``d/dL``.
    Crows : ndarray, shape (m', N)
    D : ndarray, shape (m', m)
    low : list of (P, Q) and StateBorder
        As returned by :meth:`EquilibriumSystem.jacobian_parts`.

    Returns
    -------
    sparse CSC matrix (sparse ``A``) or ndarray, square of size ``N + m + r + s``
        ``r`` the total rank of the low-rank terms, ``s`` the states' size (``m' = m``
        for the square system). The extra unknowns come last; their rows have zero
        right-hand side.
    """
    pairs = [t for t in low if not isinstance(t, StateBorder)]
    states = [t for t in low if isinstance(t, StateBorder)]
    if pairs:
        P = np.hstack([p for p, _ in pairs])
        Q = np.hstack([q for _, q in pairs])
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
        for st in states:
            for row in blocks:
                row.append(None)
            blocks[0][-1] = st.VY
            cLB = sp.csr_matrix((st.cL, (np.arange(st.size), np.zeros(st.size, dtype=int))),
                                shape=(st.size, mB))
            blocks.append([st.cK, cLB] + [None] * (len(blocks[0]) - 3) + [st.cY])
        return sp.bmat(blocks, format="csc")
    if states:
        raise ValueError("implicit-state borders need a sparse (finite-difference) Newton matrix")
    top = np.hstack([A, B] + ([P] if r else []))
    mid = np.hstack([Crows, D] + ([np.zeros((mC, r))] if r else []))
    rows = [top, mid]
    if r:
        rows.append(np.hstack([Q.T, np.zeros((r, mB)), -np.eye(r)]))
    return np.vstack(rows)
