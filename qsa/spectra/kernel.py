"""The kernel of the linearization: rigid motions, the exact kernel relations, their residuals.

At a constrained equilibrium (e:Abs-CP) the Lagrangian Hessian ``L_Lambda`` kills
``(nabla_s kappa, 0)`` and maps every reparameterization mode ``M(0, v)`` into
``span Psi`` (e:Hessian_Kernel, with the multiplier term: zero when every term of the
Lagrangian is reparameterization invariant off the closed manifold too, as the local
energies and ``C_3`` are; the enclosed area, and ``C_1, C_2``, are invariant only on it,
which leaves a multiple of ``Psi`` that ``M-dagger`` removes), ``M`` kills the rigid
motions (lem:kerM), ``M-dagger`` kills
the constraint gradients ``Psi_j``, and the normal components of the rigid motions span
the kernel of ``J``. :func:`kernel_report` measures each relation; the kernel of ``J`` is
counted from eigenvalues with error estimates: the deflated rigid modes (their Ritz
values) plus any further eigenvalue that cannot be told apart from them.
"""

from __future__ import annotations

import numpy as np

from qsa import geometry
from qsa._checks import real_number
from qsa.constraints import bind_constraints, normal_basis
from qsa.curve import Curve
from qsa.energies.adhesion_invariants import adhesion_invariants, two_point_terms
from qsa.spectra.factored import FactoredNormalOperator
from qsa.spectra.hessian import check_input, inner_norm, lagrange_hessian
from qsa.spectra.result import KernelReport
from qsa.spectra.solvers import certified_eigenpairs

__all__ = ["kernel_report", "operator_norm", "lanczos_norm", "rigid_normal_basis",
           "constraint_bases", "kernel_size", "EQUILIBRIUM_TOL"]

#: Relative residual (``max|V^n|`` over its largest term) below which a curve counts as an
#: equilibrium, so that the rigid motions are deflated from ``J``.
EQUILIBRIUM_TOL = 1e-6


def operator_norm(curve: Curve, A, iters=30, seed=0, symmetric=False) -> float:
    """Estimate of the ``<.,.>``-operator norm of ``A`` (Lanczos bidiagonalization).

    ``A`` acts on nodal (N,) or stacked (2N,) vectors. ``iters`` steps of Golub-Kahan
    bidiagonalization of ``B = W^{1/2} A W^{-1/2}`` (one product with ``A`` and one with
    ``A.T`` each, fully reorthogonalized) from a random start; the estimate is the
    largest singular value of the bidiagonal matrix, a lower bound of ``|A|`` that grows
    with the steps, converges faster than power iteration with as many products
    (clustered top singular values included) and is exact once the steps exhaust the
    space. With ``symmetric=True`` (``A`` self-adjoint in
    ``<.,.>``) Lanczos on ``B`` itself takes one product per step.

    Parameters
    ----------
    curve : Curve
        Supplies the ``<f, h> = int f h dsigma`` weights.
    A : matrix, shape (N, N) or (2N, 2N)
    iters : int
    seed : int
        Seed of the random start vector.
    symmetric : bool

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
    return lanczos_norm(lambda x: A @ x, None if symmetric else (lambda x, AT=A.T: AT @ x),
                        w, iters, seed)


def lanczos_norm(matvec, rmatvec, w, steps, seed=0) -> float:
    """``|A|`` in the ``w``-weighted norm by ``steps`` Lanczos steps (see :func:`operator_norm`).

    ``rmatvec`` applies ``A.T``; ``None`` means ``A`` is ``w``-self-adjoint (plain
    Lanczos, the estimate the largest ``|Ritz value|``). Non-finite products end the
    iteration with the estimate so far.
    """
    rw = np.sqrt(np.asarray(w, dtype=float))
    n = rw.size
    B = lambda x: rw * matvec(x / rw)
    BT = B if rmatvec is None else (lambda x: rmatvec(rw * x) / rw)
    v = np.random.default_rng(seed).standard_normal(n)
    v /= np.linalg.norm(v)
    V: list[np.ndarray] = [v]
    U: list[np.ndarray] = []
    alphas: list[float] = []
    betas: list[float] = []

    def orth(x, basis):
        for _ in range(2):  # twice is enough (classical Gram-Schmidt)
            Q = np.asarray(basis)
            x = x - Q.T @ (Q @ x)
        return x

    est = 0.0
    for _ in range(max(1, int(steps))):
        if rmatvec is None:  # Lanczos: B v_k = beta_{k-1} v_{k-1} + alpha_k v_k + beta_k v_{k+1}
            y = B(V[-1])
            if not np.all(np.isfinite(y)):
                break
            alphas.append(float(V[-1] @ y))
            y = orth(y, V)
            T = np.diag(alphas) + np.diag(betas, 1) + np.diag(betas, -1)
            est = float(np.max(np.abs(np.linalg.eigvalsh(T))))
        else:  # Golub-Kahan: B v_k = beta_{k-1} u_{k-1} + alpha_k u_k
            u = B(V[-1])
            if not np.all(np.isfinite(u)):
                break
            u = orth(u, U) if U else u
            a = float(np.linalg.norm(u))
            if a == 0.0:
                break
            U.append(u / a)
            alphas.append(a)
            Bk = np.diag(alphas) + np.diag(betas, 1)
            est = float(np.linalg.norm(Bk, 2))
            y = BT(U[-1])
            if not np.all(np.isfinite(y)):
                break
            y = orth(y, V)
        b = float(np.linalg.norm(y))
        if b <= 1e-14 * max(est, 1e-300) or len(V) == n:
            break
        betas.append(b)
        V.append(y / b)
    return est


def rigid_normal_basis(curve: Curve, rtol=1e-8) -> np.ndarray:
    """``<.,.>``-orthonormal basis of the normal components of the rigid motions, (m, N).

    ``m = 3``, or 2 for a circle (whose rotation is a reparameterization).

    Parameters
    ----------
    curve : Curve
    rtol : float
        Singular values below ``rtol`` times the largest are dropped.

    Returns
    -------
    ndarray, shape (m, N)

    Examples
    --------
    >>> from qsa import Curve, Fourier
    >>> rigid_normal_basis(Curve.circle(1.0, Fourier(17))).shape
    (2, 17)
    """
    N = curve.N
    phi = geometry.rigid_motions(curve)[:, :N]
    rw = np.sqrt(curve.dsigma)
    U, s, _ = np.linalg.svd((phi * rw).T, full_matrices=False)
    r = int(np.sum(s > rtol * s[0]))
    return (U[:, :r] / rw[:, None]).T


def constraint_bases(curve: Curve, constraints=()):
    """``(R, Rc)``: the rigid normal basis within the constraints' complement, and theirs.

    ``Rc`` is a ``<.,.>``-orthonormal basis of the constraints' normal variations
    ``n_c`` (``kappa`` for a length, ``1`` for an area; :mod:`qsa.constraints`), the
    directions the constrained flow cannot move in; ``R`` is
    :func:`rigid_normal_basis` with its components along ``Rc`` removed (they vanish
    in the continuum: ``int n dsigma = int kappa n dsigma = 0`` and likewise for
    ``gamma . tau``), re-orthonormalised, so that ``R`` lies in ``T = Rc^perp``.

    Parameters
    ----------
    curve : Curve
    constraints : sequence of Constraint

    Returns
    -------
    R : ndarray, shape (m, N)
    Rc : ndarray, shape (mc, N)
        ``mc`` = number of independent normals (a circle with both a length and an area
        constraint has one: ``kappa`` is constant).

    Examples
    --------
    >>> import numpy as np
    >>> from qsa import Curve, Fourier
    >>> from qsa.constraints import FixedArea, FixedLength
    >>> c = Curve.circle(1.0, Fourier(17))
    >>> R, Rc = constraint_bases(c, [FixedLength(), FixedArea()])
    >>> R.shape, Rc.shape
    ((2, 17), (1, 17))
    """
    R = rigid_normal_basis(curve)
    Rc = normal_basis(tuple(constraints), curve)
    if Rc.shape[0] == 0:
        return R, Rc
    rw = np.sqrt(curve.dsigma)
    R = R - (R * curve.dsigma) @ Rc.T @ Rc
    Q, _ = np.linalg.qr((R * rw).T)
    return (Q / rw[:, None]).T, Rc


def kernel_size(values, errors, is_kernel):
    """``(n_kernel, kernel_tol)`` of eigenvalues with errors and the deflated rigid modes.

    The kernel is the deflated rigid modes plus the other eigenvalues that are zero
    within their error (``|lambda| <= error``); ``kernel_tol`` is the largest
    ``|lambda| + error`` over it.

    Parameters
    ----------
    values, errors : ndarray, shape (m,)
    is_kernel : ndarray of bool, shape (m,)

    Returns
    -------
    n_kernel : int
    kernel_tol : float

    Examples
    --------
    >>> import numpy as np
    >>> kernel_size(np.array([1e-9, 2e-9, 0.5, -1e-12]), np.array([1e-10, 1e-10, 1e-9, 1e-11]),
    ...             np.array([True, True, False, False]))
    (3, 2.1e-09)
    """
    values = np.real(np.asarray(values))
    errors = np.asarray(errors, dtype=float)
    kernel = np.asarray(is_kernel, dtype=bool) | (np.abs(values) <= errors)
    tol = float(np.max(np.abs(values[kernel]) + errors[kernel], initial=0.0))
    return int(kernel.sum()), tol


def _rel(curve, A, x, normA):
    nx = inner_norm(curve, x)
    if nx == 0 or normA == 0:
        return 0.0
    return inner_norm(curve, A @ x) / (normA * nx)


def _modulo_closure(curve, A, x, normA, B):
    """``|A x|`` relative, less its ``<.,.>``-projection on ``span B`` (rows of ``B``)."""
    nx = inner_norm(curve, x)
    if nx == 0 or normA == 0:
        return 0.0
    y = A @ x
    w = np.concatenate([curve.dsigma, curve.dsigma])
    coef = np.linalg.lstsq((B * w) @ B.T, (B * w) @ y, rcond=1e-12)[0]
    return inner_norm(curve, y - coef @ B) / (normA * nx)


def _smooth_random(curve: Curve, modes=8, seed=1):
    rng = np.random.default_rng(seed)
    s = curve.grid.s
    kmax = max(1, min(modes, (curve.N - 1) // 6))
    v = rng.standard_normal()
    for k in range(1, kmax + 1):
        a, b = rng.standard_normal(2) / k
        v = v + a * np.cos(2 * np.pi * k * s) + b * np.sin(2 * np.pi * k * s)
    return v


def build_kernel_report(curve, LH, op, basis, n_kernel, kernel_tol, energy=None) -> KernelReport:
    """The :class:`KernelReport` from a Lagrangian Hessian and the kernel count.

    With ``energy`` holding a two-point term, the report also carries its invariants
    (:func:`qsa.energies.adhesion_invariants`).
    """
    N = curve.N
    L = LH.matrix
    H = LH.energy_hessian
    # scales of the relative residuals below: a digit is enough, and each product with a
    # two-point Hessian passes over all its pairs; L and H are <.,.>-self-adjoint, so
    # Lanczos (one product a step) instead of bidiagonalization (two)
    normL = operator_norm(curve, L, iters=8, symmetric=True)
    normH = operator_norm(curve, H, iters=8, symmetric=True)
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
    rep = _modulo_closure(curve, L, geometry.reparameterization_mode(curve, v), normL,
                          np.vstack([Psi] + [con.gradient(curve)[None, :]
                                             for con in LH.constraints]))
    rigid_normal = np.zeros(3)
    for j, phi in enumerate(basis):
        rigid_normal[j] = inner_norm(curve, op.matvec(phi))
    m = basis.shape[0]
    notes = []
    if inner_norm(curve, x) == 0:
        notes.append("nabla_s kappa = 0 (a circle): the kernel element (nabla_s kappa, 0) is void")
    elif pred > max(1e-10, 10 * lag):
        notes.append(
            f"Lambda_3 = {LH.multipliers[2]:.6g} != 0, so nabla^2 E (nabla_s kappa, 0) = "
            "(nabla_s d_kE, d_kE nabla_s kappa / g) is not 0: the kernel element belongs to "
            "L_Lambda = nabla^2 E - Lambda . nabla^2 C, not to nabla^2 E")
    if m < 3:
        notes.append(f"the rigid motions have only {m} independent normal "
                     "components (rotation of a circle about its centre is a reparameterization)")
    if n_kernel is not None and n_kernel != m:
        notes.append(f"numerical kernel dimension {n_kernel} differs from the expected {m}: "
                     f"{n_kernel - m} eigenvalue(s) within the rigid modes' level "
                     f"kernel_tol = {kernel_tol:.2e}")
    return KernelReport(lag, en, pred, rigid, psi, rep, rigid_normal, n_kernel, m,
                        float(kernel_tol), LH.multipliers, LH.projection_residual,
                        LH.relative_projection_residual, LH.relative_residual, tuple(notes),
                        np.array(LH.constraint_multipliers, dtype=float),
                        _two_point(energy, curve))


def _two_point(energy, curve):
    if energy is None or not two_point_terms(energy):
        return None
    return adhesion_invariants(energy, curve).summary()


def kernel_report(energy, curve: Curve, eigenvalues=None, kernel_tol=None,
                  constraints=None) -> KernelReport:
    """Residual norms of the exact kernel relations, and the kernel dimension of ``J``.

    Parameters
    ----------
    energy : Energy
    curve : Curve
    eigenvalues : array_like, optional
        Eigenvalues of ``J`` to count the kernel from (``|lambda| <= kernel_tol``).
        Default: the eigenvalues nearest 0 computed from the factors with the rigid
        motions deflated (:func:`qsa.spectra.solvers.certified_eigenpairs`), the kernel
        being the rigid modes and any eigenvalue indistinguishable from them.
    kernel_tol : float, optional
        Threshold for ``eigenvalues``; default: the rigid modes' level.
    constraints : sequence of Constraint, optional
        Length / area constraints (:mod:`qsa.constraints`): the Lagrangian Hessian has
        their multiplier terms and the kernel is that of the constrained operator
        ``P J P`` on their complement (their normal variations are excluded).

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
    cons = bind_constraints(constraints, curve)
    LH = lagrange_hessian(energy, curve, constraints=cons)
    op = FactoredNormalOperator.from_lagrangian(curve, LH.matrix, LH.energy_hessian)
    basis, cbasis = constraint_bases(curve, cons)
    m = basis.shape[0]
    if eigenvalues is None:
        # deflation is exact at an equilibrium only; elsewhere count from J's own spectrum
        k = min(m + 6, curve.N - 1 - cbasis.shape[0])
        if LH.is_equilibrium(EQUILIBRIUM_TOL):
            sol = certified_eigenpairs(op, basis, k=k, sigma=0.0, constrain=cbasis)
        else:
            sol = certified_eigenpairs(op, np.zeros((0, curve.N)), k=k, sigma=0.0,
                                       rigid=op.ritz_values(basis), constrain=cbasis)
        n_kernel, tol = kernel_size(sol.values, sol.errors, sol.is_kernel)
        if kernel_tol is not None:
            tol = real_number(kernel_tol, "kernel_tol", positive=True)
            n_kernel = int(np.sum(np.abs(sol.values) <= tol))
    else:
        ev = np.real(np.asarray(eigenvalues, dtype=complex))
        if kernel_tol is None:
            rvals, _, rerr = op.ritz(basis)
            tol = float(np.max(np.abs(rvals) + rerr, initial=0.0))
        else:
            tol = real_number(kernel_tol, "kernel_tol", positive=True)
        n_kernel = int(np.sum(np.abs(ev) <= tol))
    return build_kernel_report(curve, LH, op, basis, n_kernel, tol, energy)
