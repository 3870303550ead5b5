"""Exact Jacobian of the two-point normal velocity ``V^n_A = -(force . n + kappa B)`` (e:Adh-NV).

The adhesion normal velocity of :class:`~qsa.energies.Adhesion` is evaluated from the
node positions ``X``, the tangent angles ``theta`` and the weights ``w = omega g``:

    V_i = -(F_i . n_i + kappa_i B_i),   F_i = 4 sum_j A'(l_ij) d_ij w_j,
    B_i = 2 A0 w_i + 2 sum_j A(l_ij) w_j,   d_ij = X_i - X_j,  n = (sin theta, -cos theta),

with ``theta = theta0 + C(g kappa)`` and ``X = gamma0 + C(g tau)`` (``C`` the grid's
cumulative integral). Its derivative along ``U1 = (kappa1, g1)`` is

    dV = V_U U1 + V_Y Y1,     Y1 = (theta1, x1, y1) = Z U1,

with the explicit partial derivatives (``H_ij = 2 A''(l) d d^T + A'(l) I``, pairs ``i < j``)

    dV_i/dkappa_i = -B_i,           dV_i/dtheta_i = -F_i . tau_i,
    dV_i/dX_j = 4 w_j n_i^T H_ij + kappa_i w_j 4 A'(l_ij) d_ij     (j a partner of i),
    dV_i/dX_i = -sum_j dV_i/dX_j   (translation invariance),
    dV_i/dw_j = -4 A'(l_ij) n_i . d_ij - 2 kappa_i A(l_ij),   dV_i/dw_i = -2 kappa_i A0,
    dV/dg = (dV/dw) diag(omega),

(for the partner's row ``d`` changes sign), and the state derivative ``Z`` of the
cumulative sums,

    theta1 = C(g kappa1 + kappa g1),   x1 = C(cos theta g1 - g sin theta theta1),
    y1 = C(sin theta g1 + g cos theta theta1).

``V_U`` and ``V_Y`` have O(N + pairs) entries; ``Z`` is dense (a cumulative sum), but on
finite-difference grids ``Y1`` solves the sparse lower-triangular equations
``cY Y1 + cU U1 = 0`` of :func:`~qsa.energies.adhesion_hessian.position_state_equations`,
so a Newton matrix that carries ``Y1`` as extra unknowns stays sparse.

Examples
--------
>>> import numpy as np
>>> from qsa import Curve, FiniteDifference
>>> from qsa.energies import Adhesion
>>> c = Curve.polar(lambda t: 1 + 0.2 * np.cos(3 * t), FiniteDifference(96))
>>> E = Adhesion(A0=10.0, l_star=0.3)
>>> J = E.normal_velocity_jacobian(c)
>>> U1, h = np.cos(np.arange(192.0)), 1e-6
>>> fd = (E.normal_velocity(c.with_U(c.U + h * U1))
...       - E.normal_velocity(c.with_U(c.U - h * U1))) / (2 * h)
>>> bool(np.allclose(J @ U1, fd, rtol=1e-6, atol=1e-6 * np.abs(fd).max()))
True
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from qsa.curve import Curve
from qsa.energies.adhesion_hessian import position_state_equations

__all__ = ["VelocityJacobian", "adhesion_velocity_jacobian"]


@dataclass(frozen=True, eq=False)
class VelocityJacobian:
    """``dV^n / dU = V_U + V_Y Z`` of a normal velocity with the positions as implicit state.

    Parameters
    ----------
    curve : Curve
    VU : scipy.sparse.csr_matrix, shape (N, 2N)
        Partial derivatives in ``(kappa, g)`` at fixed state.
    VY : scipy.sparse.csr_matrix, shape (N, 3N)
        Partial derivatives in the state ``Y = (theta, x, y)``.

    Notes
    -----
    Sums of instances at the same curve add both parts (the state is the same).
    """

    curve: Curve
    VU: sp.csr_matrix
    VY: sp.csr_matrix

    @property
    def shape(self):
        """``(N, 2N)``."""
        return self.VU.shape

    def __add__(self, other):
        if not isinstance(other, VelocityJacobian):
            return NotImplemented
        if other.curve is not self.curve:
            raise ValueError("velocity Jacobians at different curves cannot be added")
        return VelocityJacobian(self.curve, (self.VU + other.VU).tocsr(),
                                (self.VY + other.VY).tocsr())

    def state_equations(self):
        """Sparse ``(cY, cU)`` with ``cY Y1 + cU U1 = 0`` (finite-difference grids).

        Returns
        -------
        cY : scipy.sparse matrix, shape (3N, 3N)
        cU : scipy.sparse matrix, shape (3N, 2N)

        See :func:`~qsa.energies.adhesion_hessian.position_state_equations`.
        """
        return position_state_equations(self.curve)

    def state_direction(self, U1) -> np.ndarray:
        """``Y1 = Z U1``: the change of ``(theta, x, y)`` along ``U1`` (cumulative sums).

        Parameters
        ----------
        U1 : ndarray, shape (2N,) or (2N, m)

        Returns
        -------
        ndarray, shape (3N,) or (3N, m)
        """
        c = self.curve
        N, grid = c.N, c.grid
        U1 = np.asarray(U1, dtype=float)
        col = (slice(None),) + (None,) * (U1.ndim - 1)
        g, kappa = c.g[col], c.kappa[col]
        th = c.theta()
        cs, sn = np.cos(th)[col], np.sin(th)[col]
        k1, g1 = U1[:N], U1[N:]
        th1 = grid.cumulative(g * k1 + kappa * g1)
        x1 = grid.cumulative(cs * g1 - g * sn * th1)
        y1 = grid.cumulative(sn * g1 + g * cs * th1)
        return np.concatenate([th1, x1, y1])

    def __matmul__(self, U1):
        U1 = np.asarray(U1, dtype=float)
        return self.VU @ U1 + self.VY @ self.state_direction(U1)

    def dense(self) -> np.ndarray:
        """``V_U + V_Y Z`` as a dense ndarray, shape (N, 2N) (O(N^2) memory).

        Integrated from the left (``V_Y C`` by transposed cumulative sums): with
        ``P_x = V_x C``, ``P_y = V_y C``, ``Q = V_theta - P_x diag(g sin) + P_y diag(g cos)``
        and ``P_theta = Q C``, ``V_Y Z = [P_theta diag(g), P_theta diag(kappa) +
        P_x diag(cos) + P_y diag(sin)]``: O(N^2) on finite differences.
        """
        c = self.curve
        N, grid = c.N, c.grid
        th = c.theta()
        cs, sn = np.cos(th), np.sin(th)
        right = lambda M: grid.cumulative_transpose(np.asarray(M).T).T    # M C
        VY = self.VY.tocsc()
        Px = right(VY[:, N:2 * N].toarray())
        Py = right(VY[:, 2 * N:].toarray())
        Q = VY[:, :N].toarray() - Px * (c.g * sn)[None, :] + Py * (c.g * cs)[None, :]
        Pth = right(Q)
        out = self.VU.toarray()
        out[:, :N] += Pth * c.g[None, :]
        out[:, N:] += Pth * c.kappa[None, :] + Px * cs[None, :] + Py * sn[None, :]
        return out


def adhesion_velocity_jacobian(kernel, c: Curve, pairs) -> VelocityJacobian:
    """The exact Jacobian of ``V^n_A`` at ``c`` for the given pairs (module docstring).

    Parameters
    ----------
    kernel : AdhesionKernel
    c : Curve
    pairs : tuple of ndarray
        ``(i, j)``, ``i < j``: the pairs of the fields (a cutoff neighbour list or all).

    Returns
    -------
    VelocityJacobian
    """
    N = c.N
    i, j = (np.asarray(p, dtype=np.intp) for p in pairs)
    x, y = c.positions()
    w = c.dsigma
    th = c.theta()
    nx, ny = np.sin(th), -np.cos(th)
    kappa = c.kappa
    dx, dy = x[i] - x[j], y[i] - y[j]
    A, dA, d2A = kernel.derivatives(dx * dx + dy * dy)
    t = 2.0 * d2A
    hxx, hxy, hyy = t * dx * dx + dA, t * dx * dy, t * dy * dy + dA
    fx, fy = 4.0 * dA * dx, 4.0 * dA * dy
    # force and B at the nodes (as in adhesion_fields)
    F = np.column_stack([np.bincount(i, fx * w[j], N) - np.bincount(j, fx * w[i], N),
                         np.bincount(i, fy * w[j], N) - np.bincount(j, fy * w[i], N)])
    B = 2.0 * kernel.A0 * w + 2.0 * (np.bincount(i, A * w[j], N) + np.bincount(j, A * w[i], N))
    # dV_r / dX_q for (r, q) = (i, j) and (j, i): 4 w_q n_r^T H + kappa_r w_q (+-f)
    rows, cols, vals = [], [], []

    def add(r, q, sign):
        ax = 4.0 * w[q] * (nx[r] * hxx + ny[r] * hxy) + sign * kappa[r] * w[q] * fx
        ay = 4.0 * w[q] * (nx[r] * hxy + ny[r] * hyy) + sign * kappa[r] * w[q] * fy
        for off, a in ((N, ax), (2 * N, ay)):
            rows.extend([r, r])
            cols.extend([off + q, off + r])
            vals.extend([a, -a])  # the diagonal block is minus the sum of the partners

    add(i, j, 1.0)
    add(j, i, -1.0)
    n = np.arange(N)
    rows.append(n)
    cols.append(n)
    vals.append(-(F[:, 0] * np.cos(th) + F[:, 1] * np.sin(th)))     # d/dtheta: -F . tau
    VY = sp.coo_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                       shape=(N, 3 * N)).tocsr()
    # dV_r / dw_q = -n_r . (+-f) - 2 kappa_r A
    om = c.grid.weights
    wr = np.concatenate([i, j, n])
    wq = np.concatenate([j, i, n])
    wv = np.concatenate([-(nx[i] * fx + ny[i] * fy) - 2.0 * kappa[i] * A,
                         (nx[j] * fx + ny[j] * fy) - 2.0 * kappa[j] * A,
                         -2.0 * kappa * kernel.A0])
    Vg = sp.coo_matrix((wv * om[wq], (wr, wq)), shape=(N, N))
    VU = sp.hstack([sp.diags(-B), Vg], format="csr")
    return VelocityJacobian(c, VU, VY)
