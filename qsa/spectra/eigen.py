"""Eigen-solvers for the linearizations, kernel checks and spurious-mode rejection.

:func:`spectrum` solves the eigenproblem of a linearization
(:mod:`qsa.spectra.linearization`) densely (all eigenvalues) or by sparse
shift-invert (the ``k`` eigenvalues nearest a shift ``sigma``):

* ``gauge="normal"`` (default): ``J`` is dsigma-self-adjoint, so the problem is
  solved in the symmetric standard form ``S = W^{1/2} J W^{-1/2}``
  (``W = diag(dsigma)``, equivalently the generalized symmetric problem
  ``(W J) phi = lambda W phi``): real eigenvalues, eigenvectors orthonormal in
  ``<f, h> = int f h dsigma``.
* ``"comoving"`` and ``"scaled"``: non-symmetric; their non-zero eigenvalues are
  those of ``J`` (MATH.md section 4), so the real parts are returned and the
  largest relative imaginary part is reported (``max_imag``).
* ``"paper"``: e:FOE-Lin as printed; complex eigenvalues are returned as they are.

Kernel tolerance (documented, explicit): an eigenvalue counts as *kernel* when
``|lambda| <= kernel_tol``, with (unless given)

    kernel_tol = max(10 max |rho_j|, eps |J|),

``rho_j`` the Ritz values of ``J`` on the span of the normal components of the
rigid motions (exactly 0 in the continuum, ``ker J``; their size is the
discretization defect of the kernel, second order in the eigenvector error) and
``eps |J|`` the round-off bound of a backward-stable eigen-solver (``|J|`` the
operator norm in ``<.,.>``, estimated by power iteration; for the smooth low modes the
observed error is 10-100 times below this bound). For the non-normal 2N x 2N gauges (``"comoving"``,
``"paper"``), whose kernel is (nearly) defective, the floor is raised to
``10 sqrt(eps) |J|``. ``n_unstable`` counts the accepted eigenvalues with
``Re lambda > kernel_tol``.

Spurious-mode rejection: the problem is solved again at about 1.5 times the
resolution (the curve resampled with :meth:`Curve.on_grid`) and an eigenvalue is
kept only if the nearest eigenvalue there is within
``drift_tol * max(|lambda|, kernel_tol)`` (the inverse of the drift ratio of
eigentools); eigenvalues that moved by less than the kernel tolerance (the absolute accuracy of
the solve) are kept as well. On by
default for Fourier grids with the dense solver.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from qsa import geometry
from qsa._checks import real_number
from qsa.curve import Curve
from qsa.discretize import FiniteDifference, Fourier
from qsa.linalg import SparsePlusLowRank, to_dense
from qsa.spectra.hessian import check_input, inner_norm, lagrange_hessian
from qsa.spectra.linearization import (
    _check_gauge,
    linearization,
    normal_operator,
    scaled_operator,
    symmetric_form,
)

__all__ = ["Spectrum", "KernelReport", "spectrum", "kernel_report", "NotEquilibriumWarning",
           "second_resolution", "operator_norm", "small_cluster"]

_EPS = np.finfo(float).eps


class NotEquilibriumWarning(UserWarning):
    """The analysed curve is not (close to) an equilibrium: the spectrum is not a linearization.

    Examples
    --------
    >>> import warnings
    >>> from qsa import Curve, Fourier
    >>> from qsa.energies import Faceting, Perimeter
    >>> c = Curve.polar(lambda t: 1 + 0.1 * np.cos(3 * t), Fourier(33))
    >>> with warnings.catch_warnings(record=True) as w:
    ...     warnings.simplefilter("always")
    ...     s = spectrum(Faceting(0.1, 5.0) + Perimeter(5.0, 6.0), c)
    >>> any(issubclass(x.category, NotEquilibriumWarning) for x in w), s.status
    (True, 1)
    """


# ------------------------------------------------------------------------ results
@dataclass(frozen=True, eq=False)
class KernelReport:
    """Residuals of the exact kernel relations at a curve (MATH.md section 4).

    All norms are ``<.,.>`` norms; relative residuals divide by ``|A| |x|`` with
    ``|A|`` the operator norm (estimated, see :func:`operator_norm`).

    Attributes
    ----------
    lagrange_kernel : float
        ``|L_Lambda (nabla_s kappa, 0)| / (|L_Lambda| |(nabla_s kappa, 0)|)``:
        small at a constrained equilibrium (e:Hessian_Kernel, corrected).
    energy_kernel : float
        The same for ``nabla^2 E``. NOT small when ``Lambda_3 != 0``:
        ``nabla^2 E (nabla_s kappa, 0) = (nabla_s d_kE, d_kE nabla_s kappa / g)`` and
        ``d_kE = Lambda_3`` at equilibrium (MATH.md section 4).
    energy_kernel_predicted : float
        The relative size of ``Lambda_3 nabla^2 C_3 (nabla_s kappa, 0) =
        (0, Lambda_3 nabla_s kappa / g)``, which ``energy_kernel`` should equal.
    rigid : ndarray, shape (3,)
        ``|M r_j| / (|M| |r_j|)`` for the rigid motions (lem:kerM).
    psi : ndarray, shape (3,)
        ``|M-dagger Psi_j| / (|M| |Psi_j|)`` (``ker M-dagger``).
    reparameterization : float
        ``|L_Lambda M(0, v)| / (|L_Lambda| |M(0, v)|)`` for a random smooth ``v``
        (Fourier modes 1..8 with normal random coefficients, fixed seed).
    rigid_normal : ndarray, shape (3,)
        ``|J phi_j| / |phi_j|`` for an orthonormal basis of the normal components of
        the rigid motions (``phi_j`` in ``ker J``); the last is 0 if that span has
        dimension 2 (circles).
    kernel_dimension : int or None
        Number of eigenvalues of ``J`` with ``|lambda| <= kernel_tol`` (None if no
        eigenvalues were computed).
    expected_kernel_dimension : int
        ``dim span{rigid normal components}``: 3, or 2 for a circle.
    kernel_tol : float
    multipliers : ndarray, shape (3,)
    projection_residual, relative_projection_residual, relative_residual : float
        See :class:`~qsa.spectra.hessian.LagrangeHessian`.
    notes : tuple of str

    Parameters
    ----------
    Constructed by :func:`kernel_report` (and :func:`spectrum`); the fields are the
    attributes above.

    Examples
    --------
    >>> from qsa.equilibria import circle
    >>> eq = circle(1.0, 0.1, grid=17, kstar=5.0)
    >>> kr = kernel_report(eq.energy, eq.curve)
    >>> kr.kernel_dimension, kr.expected_kernel_dimension, bool(kr.relative_residual < 1e-10)
    (2, 2, True)
    """

    lagrange_kernel: float
    energy_kernel: float
    energy_kernel_predicted: float
    rigid: np.ndarray
    psi: np.ndarray
    reparameterization: float
    rigid_normal: np.ndarray
    kernel_dimension: int | None
    expected_kernel_dimension: int
    kernel_tol: float
    multipliers: np.ndarray
    projection_residual: float
    relative_projection_residual: float
    relative_residual: float
    notes: tuple = ()

    def summary(self) -> dict:
        """JSON-serialisable dict.

        Returns
        -------
        dict
        """
        out = {}
        for k, v in self.__dict__.items():
            if isinstance(v, np.ndarray):
                out[k] = [float(x) for x in v]
            elif isinstance(v, (np.floating, np.integer)):
                out[k] = v.item()
            elif isinstance(v, tuple):
                out[k] = list(v)
            else:
                out[k] = v
        return out


@dataclass(frozen=True, eq=False)
class Spectrum:
    """Eigenvalues of a linearization at a curve, with the checks that qualify them.

    Attributes
    ----------
    eigenvalues : ndarray, shape (m,)
        Sorted by decreasing real part (most unstable first). Real for the
        ``"normal"``, ``"comoving"`` and ``"scaled"`` gauges (theory: their non-zero
        spectrum is that of the self-adjoint ``J``), complex for ``"paper"``.
    eigenvectors : ndarray, shape (n, m)
        Columns, normalised in ``<.,.>`` (``"normal"``: nodal ``phi``, dsigma weights;
        ``"comoving"``/``"paper"``: stacked ``(kappa1, g1)``; ``"scaled"``:
        ``(kappa1, g1)`` with weights ``(dsigma, L)``).
    n_unstable : int
        Number of eigenvalues with ``Re lambda > kernel_tol`` (with ``k``: among the k
        computed ones).
    n_kernel : int
        Number of eigenvalues with ``|lambda| <= kernel_tol``.
    kernel_tol : float
        See the module docstring.
    n_small : int
        Size of the cluster of small eigenvalues: the ``m >= max(n_kernel, 1)``
        maximising ``gap_ratio = |lambda|_(m) / |lambda|_(m-1)`` over the ``|lambda|``
        sorted increasingly (floored at the round-off level ``10 eps |J|``), among
        the smallest ``N // 4``. For a splice of 2N fronts (N corners) well apart,
        ``n_small = 2N - 1``: the 2N front positions less the total-turning
        constraint, i.e. the 2N - 4 free splice parameters (MATH.md section 5) plus
        the 3 rigid motions; they are small like the residuals, the rest O(1).
    gap_ratio : float
        The ratio at ``n_small`` (how well the cluster is separated).
    kernel : KernelReport
    spurious : ndarray
        Eigenvalues rejected by the two-resolution check (empty if it was not run).
    drift : ndarray, shape (m,)
        Relative drift of each kept eigenvalue between the two resolutions
        (NaN if the check was not run).
    gauge, method : str
        ``method`` is ``"dense"`` or ``"shift-invert"``.
    sigma : float or None
    N, N2 : int
        Resolution, and the second resolution (None if not used).
    roundoff : float
        ``eps |J|`` (``|J|`` the ``<.,.>`` operator norm): the absolute round-off
        level of every computed eigenvalue. ``J`` is a differential operator of
        order 6 for the faceting energy (4 for Canham-Helfrich), so this grows like
        ``N^6``: eigenvalues below it are noise (the message says so). Use the
        smallest N that resolves the fronts (MATH.md section 4).
    max_imag : float
        ``max |Im lambda| / max(|lambda|)`` before taking real parts (0 for ``"normal"``).
    asymmetry : float
        Relative non-self-adjointness of ``J`` as assembled (``"normal"`` only; NaN otherwise).
    multipliers : ndarray, shape (3,)
    projection_residual, relative_residual : float
        Distance from a constrained critical point (see :class:`KernelReport`).
    success : bool
    status : int
        0 ok, 1 not an equilibrium (warning issued), 2 eigen-solver failure.
    message : str

    Parameters
    ----------
    Constructed by :func:`spectrum`; the fields are the attributes above.

    Examples
    --------
    >>> import numpy as np
    >>> from qsa.equilibria import circle
    >>> eq = circle(1.0, 0.1, grid=17, kstar=5.0)
    >>> s = spectrum(eq.energy, eq.curve)
    >>> s.n_unstable, s.n_kernel, np.round(s.eigenvalues[2:4], 6).tolist()
    (0, 2, [-4.86, -4.86])
    >>> s.unstable.size, s.summary()["n_eigenvalues"]
    (0, 17)
    """

    eigenvalues: np.ndarray
    eigenvectors: np.ndarray
    n_unstable: int
    n_kernel: int
    kernel_tol: float
    n_small: int
    gap_ratio: float
    kernel: KernelReport
    spurious: np.ndarray
    drift: np.ndarray
    gauge: str
    method: str
    sigma: float | None
    N: int
    N2: int | None
    roundoff: float
    max_imag: float
    asymmetry: float
    multipliers: np.ndarray
    projection_residual: float
    relative_residual: float
    success: bool = True
    status: int = 0
    message: str = ""
    extra: dict = field(default_factory=dict, repr=False)

    def __repr__(self):
        return (f"Spectrum(gauge={self.gauge!r}, method={self.method!r}, N={self.N}, "
                f"n_eigenvalues={self.eigenvalues.size}, n_unstable={self.n_unstable}, "
                f"n_kernel={self.n_kernel}, n_small={self.n_small}, "
                f"n_spurious={self.spurious.size}, status={self.status})")

    @property
    def unstable(self) -> np.ndarray:
        """The eigenvalues counted by ``n_unstable``.

        Returns
        -------
        ndarray, shape (n_unstable,)
        """
        return self.eigenvalues[np.real(self.eigenvalues) > self.kernel_tol]

    def summary(self, max_eigenvalues=20) -> dict:
        """JSON-serialisable dict (the ``max_eigenvalues`` largest eigenvalues).

        Parameters
        ----------
        max_eigenvalues : int
            How many eigenvalues to include.

        Returns
        -------
        dict
        """
        ev = self.eigenvalues[:max_eigenvalues]

        def num(x):
            return [float(v) for v in x] if np.isrealobj(x) else [[float(v.real), float(v.imag)]
                                                                   for v in x]

        return {
            "gauge": self.gauge, "method": self.method, "N": self.N, "N2": self.N2,
            "sigma": self.sigma, "n_eigenvalues": int(self.eigenvalues.size),
            "eigenvalues": num(ev), "n_unstable": self.n_unstable, "n_kernel": self.n_kernel,
            "kernel_tol": self.kernel_tol, "n_small": self.n_small,
            "gap_ratio": self.gap_ratio, "n_spurious": int(self.spurious.size),
            "roundoff": self.roundoff, "max_imag": self.max_imag, "asymmetry": self.asymmetry,
            "multipliers": [float(x) for x in self.multipliers],
            "projection_residual": self.projection_residual,
            "relative_residual": self.relative_residual,
            "success": self.success, "status": self.status, "message": self.message,
            "kernel": self.kernel.summary(),
        }


# --------------------------------------------------------------------- helpers
def _apply(A, x):
    return A @ x


def _apply_T(A, x):
    return A.T @ x


def operator_norm(curve: Curve, A, iters=30, seed=0) -> float:
    """Estimate of the ``<.,.>``-operator norm of ``A`` (power iteration on ``A-dagger A``).

    ``A`` acts on nodal (N,) or stacked (2N,) vectors; the estimate is a lower
    bound, accurate to a few digits after ``iters`` iterations.

    Parameters
    ----------
    curve : Curve
        Supplies the ``<f, h> = int f h dsigma`` weights.
    A : matrix, shape (N, N) or (2N, 2N)
    iters : int
    seed : int
        Seed of the random start vector.

    Returns
    -------
    float

    Examples
    --------
    >>> import numpy as np
    >>> from qsa import Curve, Fourier
    >>> c = Curve.circle(1.0, Fourier(17))
    >>> est = operator_norm(c, np.diag(np.linspace(1.0, 3.0, 17)))  # exact norm: 3
    >>> bool(2.99 < est <= 3.0 + 1e-12)
    True
    """
    n = A.shape[0]
    w = curve.dsigma if n == curve.N else np.concatenate([curve.dsigma] * (n // curve.N))
    rw = np.sqrt(w)
    x = np.random.default_rng(seed).standard_normal(n)
    x /= np.linalg.norm(x)
    val = 0.0
    for _ in range(iters):
        # B = W^{1/2} A W^{-1/2}; power iteration on B^T B
        y = rw * _apply(A, x / rw)
        z = _apply_T(A, rw * y) / rw
        nz = np.linalg.norm(z)
        if nz == 0 or not np.isfinite(nz):
            return float(np.linalg.norm(y))
        val = np.sqrt(nz)
        x = z / nz
    return float(val)


def _rel(curve, A, x, normA):
    nx = inner_norm(curve, x)
    if nx == 0 or normA == 0:
        return 0.0
    return inner_norm(curve, A @ x) / (normA * nx)


def _rigid_normal_basis(curve: Curve, rtol=1e-8):
    """``<.,.>``-orthonormal basis of the normal components of the rigid motions, (r, N)."""
    N = curve.N
    phi = geometry.rigid_motions(curve)[:, :N]
    rw = np.sqrt(curve.dsigma)
    U, s, Vt = np.linalg.svd((phi * rw).T, full_matrices=False)
    r = int(np.sum(s > rtol * s[0]))
    return (U[:, :r] / rw[:, None]).T


def _smooth_random(curve: Curve, modes=8, seed=1):
    rng = np.random.default_rng(seed)
    s = curve.grid.s
    kmax = max(1, min(modes, (curve.N - 1) // 6))
    v = rng.standard_normal()
    for k in range(1, kmax + 1):
        a, b = rng.standard_normal(2) / k
        v = v + a * np.cos(2 * np.pi * k * s) + b * np.sin(2 * np.pi * k * s)
    return v


def _kernel_tolerance(curve, J, normJ, basis):
    """``(kernel_tol, defect)``: ``max(10 max |Ritz values of J on the rigid span|, eps |J|)``.

    ``defect[j] = |J phi_j|`` for the orthonormal rigid normal basis ``phi_j``.
    """
    JB = np.array([J @ phi for phi in basis])
    defect = np.array([inner_norm(curve, r) for r in JB])
    ritz = np.zeros(1)
    if basis.shape[0]:
        B = (basis * curve.dsigma) @ JB.T
        ritz = np.linalg.eigvalsh(0.5 * (B + B.T))
    return max(10.0 * np.max(np.abs(ritz)), _EPS * normJ), defect


def _build_kernel_report(energy, curve, LH, J, normJ, eigenvalues, kernel_tol, basis, defect):
    N = curve.N
    L = LH.matrix
    H = LH.energy_hessian
    normL = operator_norm(curve, L)
    normH = operator_norm(curve, H)
    Mmat = geometry.M(curve)
    normM = operator_norm(curve, Mmat)
    ks = curve.grad_s(curve.kappa)
    if inner_norm(curve, ks) <= 1e-9 * inner_norm(curve, curve.kappa) * N / curve.length():
        ks = np.zeros(N)  # a circle: nabla_s kappa is round-off
    x = np.concatenate([ks, np.zeros(N)])
    lag = _rel(curve, L, x, normL)
    en = _rel(curve, H, x, normH)
    pred = 0.0
    if inner_norm(curve, x) > 0 and normH > 0:
        pred = float(abs(LH.multipliers[2]) * inner_norm(curve, np.concatenate([np.zeros(N),
                                                                             ks / curve.g]))
                / (normH * inner_norm(curve, x)))
    rig = geometry.rigid_motions(curve)
    rigid = np.array([_rel(curve, Mmat, r, normM) for r in rig])
    Md = geometry.M_adjoint(curve)
    Psi = geometry.constraint_gradients(curve)
    psi = np.array([_rel(curve, Md, p, normM) for p in Psi])
    v = _smooth_random(curve)
    rep = _rel(curve, L, geometry.reparameterization_mode(curve, v), normL)
    rigid_normal = np.zeros(3)
    rigid_normal[: defect.size] = defect
    kdim = None if eigenvalues is None else int(np.sum(np.abs(eigenvalues) <= kernel_tol))
    notes = []
    if inner_norm(curve, x) == 0:
        notes.append("nabla_s kappa = 0 (a circle): the kernel element (nabla_s kappa, 0) is void")
    elif pred > max(1e-10, 10 * lag):
        notes.append(
            f"Lambda_3 = {LH.multipliers[2]:.6g} != 0, so nabla^2 E (nabla_s kappa, 0) = "
            "(nabla_s d_kE, d_kE nabla_s kappa / g) is not 0: the kernel element belongs to "
            "L_Lambda = nabla^2 E - Lambda . nabla^2 C, not to nabla^2 E (MATH.md section 4)")
    if basis.shape[0] < 3:
        notes.append(f"the rigid motions have only {basis.shape[0]} independent normal "
                     "components (rotation of a circle about its centre is a reparameterization)")
    if kdim is not None and kdim != basis.shape[0]:
        notes.append(f"numerical kernel dimension {kdim} differs from the expected "
                     f"{basis.shape[0]} (kernel_tol = {kernel_tol:.2e})")
    return KernelReport(lag, en, pred, rigid, psi, rep, rigid_normal, kdim, basis.shape[0],
                        float(kernel_tol), LH.multipliers, LH.projection_residual,
                        LH.relative_projection_residual, LH.relative_residual, tuple(notes))


def kernel_report(energy, curve: Curve, eigenvalues=None, kernel_tol=None) -> KernelReport:
    """Residual norms of the exact kernel relations, and the kernel dimension of ``J``.

    Parameters
    ----------
    energy : Energy
    curve : Curve
    eigenvalues : array_like, optional
        Eigenvalues of ``J`` to count the kernel from; default: computed (dense
        for Fourier grids and ``N <= 2000``, else the 8 nearest 0 by shift-invert).
    kernel_tol : float, optional
        Default: see the module docstring.

    Returns
    -------
    KernelReport

    Examples
    --------
    >>> from qsa.equilibria import npulse
    >>> eq = npulse(3, 0.3)
    >>> rep = kernel_report(eq.energy, eq.curve)
    >>> rep.kernel_dimension, rep.expected_kernel_dimension, rep.lagrange_kernel < 1e-6
    (3, 3, True)
    """
    check_input(energy, curve)
    LH = lagrange_hessian(energy, curve)
    J = normal_operator(energy, curve, lagrange=LH)
    normJ = operator_norm(curve, J)
    basis = _rigid_normal_basis(curve)
    tol_auto, defect = _kernel_tolerance(curve, J, normJ, basis)
    tol = tol_auto if kernel_tol is None else _positive(kernel_tol, "kernel_tol")
    if eigenvalues is None:
        S = symmetric_form(curve, J)
        if not curve.grid.sparse or curve.N <= 2000:
            eigenvalues = sla.eigvalsh(to_dense(S))
        else:
            eigenvalues = _shift_invert(S, min(8, curve.N - 2), 0.0, symmetric=True)[0]
    ev = np.real(np.asarray(eigenvalues))
    return _build_kernel_report(energy, curve, LH, J, normJ, ev, tol, basis, defect)


def _positive(x, name):
    return real_number(x, name, positive=True)


# ---------------------------------------------------------------- eigen-solvers
def _shift_invert_operator(A, sigma):
    """LinearOperator applying ``(A - sigma I)^{-1}`` (sparse LU + Woodbury for low rank)."""
    n = A.shape[0]
    if isinstance(A, SparsePlusLowRank):
        lu = spla.splu((A.S - sigma * sp.identity(n, format="csr")).tocsc())
        AiU = lu.solve(A.U)
        cap = np.eye(A.rank) + A.V.T @ AiU
        cap_lu = sla.lu_factor(cap)

        def solve(b):
            y = lu.solve(b)
            return y - AiU @ sla.lu_solve(cap_lu, A.V.T @ y)
    elif sp.issparse(A):
        lu = spla.splu((A - sigma * sp.identity(n, format="csr")).tocsc())
        solve = lu.solve
    else:
        f = sla.lu_factor(np.asarray(A) - sigma * np.eye(n))

        def solve(b):
            return sla.lu_solve(f, b)
    return spla.LinearOperator((n, n), matvec=solve, dtype=float)


def _as_operator(A):
    if isinstance(A, SparsePlusLowRank):
        return A.aslinearoperator()
    return spla.aslinearoperator(A)


def _shift_invert(A, k, sigma, symmetric):
    n = A.shape[0]
    k = int(min(k, n - 2))
    try:
        OPinv = _shift_invert_operator(A, sigma)
    except RuntimeError:  # exactly singular at sigma: move the shift off the spectrum
        sigma = sigma + 1e-10 * max(1.0, abs(sigma))
        OPinv = _shift_invert_operator(A, sigma)
    v0 = np.random.default_rng(0).standard_normal(n)
    if symmetric:
        vals, vecs = spla.eigsh(_as_operator(A), k=k, sigma=sigma, OPinv=OPinv, which="LM",
                                v0=v0)
    else:
        vals, vecs = spla.eigs(_as_operator(A), k=k, sigma=sigma, OPinv=OPinv, which="LM",
                               v0=v0)
    return vals, vecs


def second_resolution(grid, factor=1.5):
    """The grid of about ``factor`` times the resolution (odd N for Fourier).

    Parameters
    ----------
    grid : Grid
    factor : float

    Returns
    -------
    Grid
        Same kind, about ``factor * grid.N`` nodes.

    Examples
    --------
    >>> from qsa import Fourier
    >>> second_resolution(Fourier(17))
    Fourier(27)
    """
    N2 = int(round(factor * grid.N))
    if isinstance(grid, Fourier):
        N2 += 1 - N2 % 2
        return Fourier(N2)
    return FiniteDifference(N2)


def _solve(energy, curve, gauge, k, sigma, LH, J=None, vectors=True):
    """Eigenvalues/vectors in the gauge; returns (vals, vecs, weights, max_imag, asym)."""
    w = curve.dsigma
    if gauge == "normal":
        J = normal_operator(energy, curve, lagrange=LH) if J is None else J
        S = symmetric_form(curve, J)
        asym = _asymmetry(curve, J)
        if k is None and not vectors:
            return sla.eigvalsh(to_dense(S)), None, w, 0.0, asym
        if k is None:
            vals, Y = sla.eigh(to_dense(S))
        else:
            vals, Y = _shift_invert(S, k, sigma, symmetric=True)
        vecs = Y / np.sqrt(w)[:, None]
        return vals, vecs, w, 0.0, asym
    if gauge == "scaled":
        A = scaled_operator(energy, curve, lagrange=LH)
        wts = np.append(w, curve.length())
    else:
        A = linearization(energy, curve, gauge=gauge, lagrange=LH)
        wts = np.concatenate([w, w])
    if k is None and not vectors:
        vals, vecs = sla.eigvals(to_dense(A)), None
    elif k is None:
        vals, vecs = sla.eig(to_dense(A))
    else:
        vals, vecs = _shift_invert(A, k, sigma, symmetric=False)
    scale = np.max(np.abs(vals)) if vals.size else 1.0
    max_imag = float(np.max(np.abs(vals.imag)) / scale) if scale > 0 else 0.0
    if gauge != "paper":
        vals = vals.real
    if vecs is None:
        return vals, None, wts, max_imag, np.nan
    if gauge != "paper":
        vecs = vecs.real
    norms = np.sqrt(np.sum(wts[:, None] * np.abs(vecs) ** 2, axis=0))
    vecs = vecs / np.where(norms > 0, norms, 1.0)
    return vals, vecs, wts, max_imag, np.nan


def _asymmetry(curve, J, probes=3):
    """``max |W J x - (W J)^T x| / |W J x|`` over random probes (Euclidean)."""
    w = curve.dsigma
    rng = np.random.default_rng(2)
    worst = 0.0
    for _ in range(probes):
        x = rng.standard_normal(curve.N)
        a = w * (J @ x)
        b = J.T @ (w * x)
        worst = max(worst, np.linalg.norm(a - b) / max(np.linalg.norm(a), 1e-300))
    return float(worst)


def _sort(vals, vecs):
    order = np.lexsort((np.imag(vals), -np.real(vals)))
    return vals[order], vecs[:, order]


def _match_drift(vals, vals2, tol):
    """``(drift, keep)``: relative distance to the nearest eigenvalue of the second solve.

    Kept: ``|lambda - lambda2| <= max(drift_tol |lambda|, tol)`` is decided by the
    caller from ``drift = |lambda - lambda2| / |lambda|`` and ``dist``.
    """
    dist = np.array([np.min(np.abs(vals2 - lam)) for lam in vals])
    drift = dist / np.maximum(np.abs(vals), 1e-300)
    return drift, dist


def small_cluster(eigenvalues, n_kernel=0, floor=0.0, max_size=None):
    """``(m, ratio)``: size of the cluster of small eigenvalues and its separation.

    ``|lambda|`` sorted increasingly and floored at ``floor``; ``m`` maximises
    ``|lambda|_(m) / |lambda|_(m-1)`` over ``max(n_kernel, 1) <= m <= max_size``
    (default: half the number of eigenvalues). See :class:`Spectrum` ``n_small``.

    Parameters
    ----------
    eigenvalues : array_like, shape (n,)
    n_kernel : int
        Lower bound of the cluster size.
    floor : float
        Round-off level: smaller ``|lambda|`` count as ``floor``.
    max_size : int, optional

    Returns
    -------
    m : int
    ratio : float
        ``|lambda|_(m) / |lambda|_(m-1)``.

    Examples
    --------
    >>> m, ratio = small_cluster([-1e-6, 2e-6, -3e-6, -1.0, -2.0, -5.0], floor=1e-12)
    >>> m, round(ratio)
    (3, 333333)
    """
    a = np.sort(np.abs(np.asarray(eigenvalues)))
    if a.size < 2:
        return int(a.size), np.nan
    a = np.maximum(a, max(floor, 1e-300))
    hi = min(a.size - 1, max_size if max_size is not None else a.size // 2)
    lo = max(int(n_kernel), 1)
    if lo > hi:
        return int(min(lo, a.size)), np.nan
    ratios = a[lo: hi + 1] / a[lo - 1: hi]
    j = int(np.argmax(ratios))
    return lo + j, float(ratios[j])


def spectrum(energy, curve: Curve, k=None, sigma=None, gauge="normal", *, kernel_tol=None,
             reject_spurious=None, drift_tol=1e-6, factor=1.5, equilibrium_tol=1e-6):
    """Eigenvalues and eigenvectors of the linearization at an equilibrium.

    Parameters
    ----------
    energy : Energy
    curve : Curve
        An equilibrium or quasi-equilibrium (else a :class:`NotEquilibriumWarning`
        is issued and ``status = 1``).
    k : int, optional
        Number of eigenvalues nearest ``sigma`` (sparse shift-invert, ARPACK). Default:
        all eigenvalues (dense).
    sigma : float, optional
        Shift for ``k`` (default 0).
    gauge : {"normal", "comoving", "scaled", "paper"}
        The linearization (:func:`~qsa.spectra.linearization`); default ``"normal"``
        (``J``, whose spectrum equals the non-zero spectrum of the comoving operator).
    kernel_tol : float, optional
        Threshold of ``n_kernel``/``n_unstable``; default see the module docstring.
    reject_spurious : bool, optional
        Two-resolution check; default True for Fourier grids with the dense solver.
    drift_tol : float
        Largest relative drift of a kept eigenvalue.
    factor : float
        Resolution ratio of the check (about 1.5).
    equilibrium_tol : float
        Warn when ``max|V^n|`` relative to its largest term exceeds this.

    Returns
    -------
    Spectrum

    Raises
    ------
    ValueError
        Bad ``energy``, ``curve``, ``gauge``, ``k``, ``sigma``, ``kernel_tol``,
        ``drift_tol`` or ``factor``.

    Examples
    --------
    >>> from qsa import Fourier
    >>> from qsa.equilibria import circle
    >>> eq = circle(1.0, 0.1, grid=Fourier(33))
    >>> s = spectrum(eq.energy, eq.curve)
    >>> s.n_unstable, s.n_kernel, round(float(s.eigenvalues[2]), 6)  # lambda_2 = -9 * 0.54
    (0, 2, -4.86)
    """
    check_input(energy, curve)
    _check_gauge(gauge)
    if k is not None:
        if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or k < 1:
            raise ValueError(f"k must be a positive integer, got {k!r}")
        n = curve.N + (curve.N if gauge in ("comoving", "paper") else 0)
        if k > n - 2:
            raise ValueError(f"k={k} is too large for a problem of size {n}: use k=None "
                             "(dense) or k <= n - 2")
    if sigma is not None:
        sigma = float(sigma)
        if not np.isfinite(sigma):
            raise ValueError(f"sigma must be finite, got {sigma}")
    elif k is not None:
        sigma = 0.0
    if not (np.isfinite(drift_tol) and drift_tol > 0):
        raise ValueError(f"drift_tol must be positive, got {drift_tol}")
    if not (np.isfinite(factor) and 1.1 <= factor <= 4):
        raise ValueError(f"factor must be in [1.1, 4], got {factor}")
    if reject_spurious is None:
        reject_spurious = isinstance(curve.grid, Fourier) and k is None

    LH = lagrange_hessian(energy, curve)
    J = normal_operator(energy, curve, lagrange=LH)
    normJ = operator_norm(curve, J)
    basis = _rigid_normal_basis(curve)
    tol, defect = _kernel_tolerance(curve, J, normJ, basis)
    nonnormal = gauge in ("comoving", "paper")
    if nonnormal and k is not None:
        # non-normal 2N x 2N: its kernel is (nearly) defective, round-off ~ sqrt(eps)
        tol = max(tol, 10 * np.sqrt(_EPS) * normJ)
    if kernel_tol is not None:
        tol = _positive(kernel_tol, "kernel_tol")

    status, notes = 0, []
    if LH.relative_residual > equilibrium_tol:
        status = 1
        text = (f"the curve is not an equilibrium: max|V^n| is {LH.relative_residual:.2e} of "
                f"its largest term, projection residual |grad E - Lambda.Psi| = "
                f"{LH.projection_residual:.3e} ({LH.relative_projection_residual:.1e} relative); "
                "the eigenvalues are those of the operator at this curve, not of a "
                "linearization about an equilibrium")
        warnings.warn(text, NotEquilibriumWarning, stacklevel=2)
        notes.append(text)

    try:
        vals, vecs, _, max_imag, asym = _solve(energy, curve, gauge, k, sigma, LH, J)
    except (np.linalg.LinAlgError, spla.ArpackError, spla.ArpackNoConvergence,
            RuntimeError) as exc:
        kr = _build_kernel_report(energy, curve, LH, J, normJ, None, tol, basis, defect)
        empty = np.array([])
        return Spectrum(empty, np.zeros((curve.N, 0)), 0, 0, float(tol), 0, np.nan, kr, empty,
                        empty,
                        gauge, "dense" if k is None else "shift-invert", sigma, curve.N, None,
                        float(_EPS * normJ), np.nan, np.nan, LH.multipliers,
                        LH.projection_residual,
                        LH.relative_residual, False, 2, f"eigen-solver failed: {exc}")
    vals, vecs = _sort(vals, vecs)
    if nonnormal and k is None and kernel_tol is None:
        # a (nearly) defective kernel perturbed by eps |calL| splits like sqrt(eps |calL| rho),
        # rho = the smallest non-kernel |lambda| of J (the scale of the coupled modes)
        lamJ = np.abs(sla.eigvalsh(to_dense(symmetric_form(curve, J))))
        rho = np.min(lamJ[lamJ > tol], initial=np.max(lamJ, initial=1.0))
        tol = max(tol, 10 * float(np.sqrt(_EPS * np.max(np.abs(vals)) * rho)))

    spurious = np.array([], dtype=vals.dtype)
    drift = np.full(vals.size, np.nan)
    N2 = None
    if reject_spurious:
        grid2 = second_resolution(curve.grid, factor)
        N2 = grid2.N
        c2 = curve.on_grid(grid2)
        LH2 = lagrange_hessian(energy, c2)
        J2 = normal_operator(energy, c2, lagrange=LH2)
        tol2 = max(_kernel_tolerance(c2, J2, operator_norm(c2, J2), _rigid_normal_basis(c2))[0],
                   tol)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", NotEquilibriumWarning)
            vals2 = _solve(energy, c2, gauge, k, sigma, LH2, J2, vectors=False)[0]
        drift, dist = _match_drift(vals, vals2, tol)
        keep = (drift <= drift_tol) | (dist <= tol2)
        spurious = vals[~keep]
        vals, vecs, drift = vals[keep], vecs[:, keep], drift[keep]

    re = np.real(vals)
    n_unstable = int(np.sum(re > tol))
    n_kernel = int(np.sum(np.abs(vals) <= tol))
    kvals = vals if gauge == "normal" else None
    kr = _build_kernel_report(energy, curve, LH, J, normJ, kvals, tol, basis, defect)
    expected = kr.expected_kernel_dimension + {"comoving": curve.N, "paper": curve.N,
                                               "scaled": 1}.get(gauge, 0)
    if n_kernel != expected and (k is None or n_kernel > expected):
        why = ("the 2N x 2N operator has spurious eigenvalues from under-resolved "
               "reparameterization modes (MATH.md section 4): prefer gauge='normal'"
               if nonnormal else
               f"round-off eps |J| = {_EPS * normJ:.2e}; J has order 6 for faceting, so small "
               "eigenvalues drown in round-off at large N: use the smallest N that resolves "
               "the fronts")
        notes.append(f"{n_kernel} eigenvalues within kernel_tol = {tol:.2e}, {expected} "
                     f"expected ({why})")
    msg = (f"{gauge} gauge, {'dense' if k is None else f'shift-invert (k={k}, sigma={sigma})'}"
           f": {vals.size} eigenvalues, {n_unstable} unstable, {n_kernel} in the kernel "
           f"(|lambda| <= {tol:.2e})")
    if reject_spurious:
        msg += f"; {spurious.size} rejected as spurious (N = {curve.N} vs {N2})"
    if notes:
        msg += "; " + "; ".join(notes)
    n_small, gap = small_cluster(vals, n_kernel, 10 * _EPS * normJ, max(2, curve.N // 4))
    return Spectrum(vals, vecs, n_unstable, n_kernel, float(tol), n_small, gap, kr, spurious,
                    drift, gauge,
                    "dense" if k is None else "shift-invert", sigma, curve.N, N2,
                    float(_EPS * normJ), float(max_imag), float(asym), LH.multipliers,
                    LH.projection_residual,
                    LH.relative_residual, True, status, msg)
