"""Symmetry-adapted spectra: the Z_n Bloch blocks of ``J`` at a symmetric curve.

A curve whose curvature repeats after ``q = N / n`` nodes (constant ``g``) is invariant
under the node shift ``(T f)_i = f_{i + q}``, and so are ``L_Lambda``, ``M`` and the
quadrature weights: ``T`` commutes with ``J`` and with the shift-invert operator
``K = (W J - sigma W)^{-1} W``. The nodal space splits into the Bloch sectors

    V_b = {phi : T phi = omega^b phi},   omega = exp(2 pi i / n),   b = 0, ..., n - 1,

each invariant under ``K``; ``V_{n-b}`` is the complex conjugate of ``V_b``, so the
eigenvalues of ``V_b`` and ``V_{n-b}`` coincide. The eigenvalues of ``J`` are those of
the compressions ``Q_b^H W K W Q_b`` (``Q_b`` a ``<.,.>``-orthonormal basis of ``V_b``
with the deflated rigid modes removed) for ``b = 0, ..., floor(n/2)``; for
``0 < b < n/2`` each is a double eigenvalue of ``J`` *exactly* (the real and imaginary
parts of one Bloch eigenvector), for ``b = 0`` and ``b = n/2`` simple. An ``n``-pulse
has ``n``-fold symmetry (``b`` = the Bloch index); a circle is invariant under every
shift (``n = N``), its sectors are the Fourier modes and ``b`` is the mode number
``m`` of ``cos m theta``.

A reflection ``kappa_{c - i} = kappa_i`` (indices mod ``N``) makes the symmetry group
dihedral; :attr:`BlochSymmetry.reflection` records ``c``. It is used to split the
critical plane of a double eigenvalue into reflection-even and -odd directions
(branch switching).

The rigid motions' normal components lie in sectors ``0`` (rotation) and ``+-1``
(translations); they are deflated sector by sector and reported as the kernel. Length
and area constraints (:mod:`qsa.constraints`) pose the problem on the complement of their
normal variations (``kappa``, ``1``: shift-invariant, so in sector 0), the operator being
``P J P`` with the constrained Lagrangian Hessian; those directions are excluded, not
reported.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse.linalg as spla

from qsa.constraints import bind_constraints
from qsa.curve import Curve
from qsa.spectra.factored import FactoredNormalOperator
from qsa.spectra.hessian import check_input, lagrange_hessian
from qsa.spectra.kernel import constraint_bases
from qsa.spectra.solvers import _shift

__all__ = ["BlochSymmetry", "SectorSpectrum", "detect_symmetry", "sector_basis",
           "sector_spectrum", "DENSE_SECTOR_LIMIT"]

_EPS = np.finfo(float).eps

#: Largest sector dimension solved by the dense compressed inverse (every eigenvalue of
#: the sector); larger sectors use complex ARPACK for the ``k`` nearest the shift.
DENSE_SECTOR_LIMIT = 400


@dataclass(frozen=True)
class BlochSymmetry:
    """The Z_n symmetry of a curve on its grid (and a reflection, if any).

    Attributes
    ----------
    order : int
        ``n``: the curvature repeats after ``N / n`` nodes (1: no symmetry).
    N : int
        Number of nodes.
    circle : bool
        Constant curvature (O(2) symmetry; ``order = N``).
    reflection : int or None
        ``c`` with ``kappa[(c - i) % N] == kappa[i]`` (None: no node-preserving
        reflection).

    Parameters
    ----------
    The attributes above.

    Examples
    --------
    >>> from qsa import Curve, Fourier
    >>> detect_symmetry(Curve.circle(1.0, Fourier(17)))
    BlochSymmetry(order=17, N=17, circle=True, reflection=0)
    """

    order: int
    N: int
    circle: bool = False
    reflection: int | None = None

    @property
    def shift(self) -> int:
        """``N / order``: the node shift generating the symmetry."""
        return self.N // self.order

    @property
    def sectors(self) -> tuple:
        """The computed Bloch indices ``0, ..., floor(order / 2)``."""
        return tuple(range(self.order // 2 + 1))

    def multiplicity(self, b) -> int:
        """2 for a complex sector (``0 < b < order/2``), 1 for ``b = 0`` and ``b = order/2``."""
        return 2 if 0 < b and 2 * b != self.order else 1

    def label(self) -> str:
        """``"mode"`` (circle: ``b`` is the mode number) or ``"bloch"``."""
        return "mode" if self.circle else "bloch"

    def reflect(self, phi):
        """``phi_{c - i}`` (the reflection; requires :attr:`reflection`)."""
        idx = (self.reflection - np.arange(self.N)) % self.N
        return np.asarray(phi)[idx]


def detect_symmetry(curve: Curve, tol=1e-8, max_order=None) -> BlochSymmetry:
    """The largest ``n`` dividing ``N`` with ``kappa`` invariant under the shift by ``N/n`` nodes.

    Parameters
    ----------
    curve : Curve
        Constant ``g`` required for a symmetry (else ``order = 1``).
    tol : float
        Relative tolerance: ``max|kappa(shifted) - kappa| <= tol max|kappa|``.
    max_order : int, optional
        Largest order considered (default ``N``).

    Returns
    -------
    BlochSymmetry

    Examples
    --------
    >>> from qsa.equilibria import npulse
    >>> eq = npulse(3, 0.2, grid=63)
    >>> s = detect_symmetry(eq.curve)
    >>> s.order, s.circle, s.reflection is not None
    (3, False, True)
    """
    k = np.asarray(curve.kappa)
    N = curve.N
    g = np.asarray(curve.g)
    scale = max(float(np.max(np.abs(k))), 1e-300)
    if np.max(np.abs(g - g[0])) > tol * abs(g[0]):
        return BlochSymmetry(1, N)
    if np.max(np.abs(k - k[0])) <= tol * scale:
        return BlochSymmetry(N, N, True, 0)
    order = 1
    for n in range(min(N, max_order or N), 1, -1):
        if N % n == 0 and np.max(np.abs(np.roll(k, -(N // n)) - k)) <= tol * scale:
            order = n
            break
    return BlochSymmetry(order, N, False, _reflection(k, tol * scale))


def _reflection(k, atol):
    """``c`` with ``k[(c - i) % N] = k[i]`` within ``atol``, or None."""
    N = k.size
    i = np.arange(N)
    # a reflection maps the largest curvature to a largest one: i0 -> j, so c = i0 + j
    i0 = int(np.argmax(k))
    for j in np.flatnonzero(k >= k[i0] - atol):
        c = int((i0 + j) % N)
        if np.max(np.abs(k[(c - i) % N] - k)) <= atol:
            return c
    return None


def sector_basis(symmetry: BlochSymmetry, b, dsigma) -> np.ndarray:
    """``<.,.>``-orthonormal basis of the Bloch sector ``V_b``, shape (N, N / n), complex.

    Column ``j`` is ``omega^(b l)`` at node ``j + l q`` (``l = 0..n-1``), 0 elsewhere,
    scaled to unit norm in ``<f, h> = int f conj(h) dsigma`` (``dsigma`` uniform).

    Parameters
    ----------
    symmetry : BlochSymmetry
    b : int
    dsigma : ndarray, shape (N,)

    Returns
    -------
    ndarray, shape (N, N / n), complex

    Examples
    --------
    >>> import numpy as np
    >>> sym = BlochSymmetry(3, 6)
    >>> Q = sector_basis(sym, 1, np.ones(6))
    >>> bool(np.allclose(np.roll(Q, -2, axis=0), np.exp(2j * np.pi / 3) * Q))
    True
    """
    n, N = symmetry.order, symmetry.N
    q = N // n
    Q = np.zeros((N, q), dtype=complex)
    phase = np.exp(2j * np.pi * b * np.arange(n) / n)
    for j in range(q):
        Q[j::q, j] = phase
    return Q / np.sqrt(n * dsigma[0])


@dataclass(frozen=True, eq=False)
class SectorSpectrum:
    """Eigenvalues of ``J`` labelled by their Bloch sector, with error estimates.

    Attributes
    ----------
    eigenvalues : ndarray, shape (m,)
        One entry per eigenvalue of a sector (a double eigenvalue of ``J`` appears once,
        with ``multiplicity`` 2); sorted decreasingly.
    errors : ndarray, shape (m,)
        Absolute error estimates (as in :class:`~qsa.spectra.Spectrum`).
    sector : ndarray of int, shape (m,)
        Bloch index ``b`` (the mode number on a circle).
    multiplicity : ndarray of int, shape (m,)
    vectors : ndarray, shape (N, m), complex
        ``<.,.>``-unit Bloch eigenvectors (``T v = omega^b v``).
    kernel : ndarray, shape (r,)
        Ritz values of the deflated rigid modes.
    kernel_errors : ndarray, shape (r,)
    symmetry : BlochSymmetry
    dsigma : ndarray, shape (N,)
        The quadrature weights of ``<.,.>``.
    complete : bool
        Every eigenvalue of every sector was computed (dense sectors); otherwise the
        ``k`` nearest ``sigma`` per sector.
    sigma : float

    Parameters
    ----------
    Constructed by :func:`sector_spectrum`; the fields are the attributes above.
    """

    eigenvalues: np.ndarray
    errors: np.ndarray
    sector: np.ndarray
    multiplicity: np.ndarray
    vectors: np.ndarray
    kernel: np.ndarray
    kernel_errors: np.ndarray
    symmetry: BlochSymmetry
    dsigma: np.ndarray
    complete: bool
    sigma: float

    @property
    def unstable(self) -> np.ndarray:
        """Mask of the certified positive eigenvalues (``lambda > error``)."""
        return self.eigenvalues > self.errors

    @property
    def n_unstable(self) -> int:
        """Number of unstable eigenvalues of ``J`` counted with multiplicity (kernel excluded)."""
        return int(np.sum(self.multiplicity[self.unstable]))

    @property
    def ambiguous(self) -> np.ndarray:
        """Mask of the eigenvalues whose sign is not certified (``|lambda| <= error``)."""
        return np.abs(self.eigenvalues) <= self.errors

    def real_vectors(self, i):
        """Real ``<.,.>``-orthonormal eigenvectors of entry ``i``, shape (N, multiplicity).

        The real and imaginary parts of the Bloch vector (one real vector for
        ``b = 0`` or ``n/2``, after removing its phase).
        """
        v = self.vectors[:, i]
        w = self.dsigma[:, None]
        if self.multiplicity[i] == 1:
            j = int(np.argmax(np.abs(v)))
            out = np.real(v * np.conj(v[j]) / abs(v[j]))[:, None]
        else:
            out = np.column_stack([v.real, v.imag])
        return out / np.sqrt(np.sum(out**2 * w, axis=0))

    def n_unstable_in(self, b) -> int:
        """Unstable eigenvalues of sector ``b`` (with multiplicity)."""
        m = self.unstable & (self.sector == b)
        return int(np.sum(self.multiplicity[m]))


def _deflated_basis(Q, R, w):
    """Orthonormal basis of ``V_b`` minus the component of ``span R`` in it."""
    if R.shape[0] == 0:
        return Q
    C = Q.conj().T @ (w[:, None] * R.T)  # (q, m): coordinates of R's sector parts
    U, s, _ = np.linalg.svd(C, full_matrices=True)
    r = int(np.sum(s > 1e-8 * max(1.0, float(np.max(s, initial=0.0)))))
    return Q @ U[:, r:]


def _apply_complex(si, X):
    w = si.op.w[:, None]
    return si.solve(w * X.real) + 1j * si.solve(w * X.imag)


def _sector_dense(si, B, sigma, w):
    X = _apply_complex(si, B)
    Kc = B.conj().T @ (w[:, None] * X)
    nu, Y = np.linalg.eigh(0.5 * (Kc + Kc.conj().T))
    keep = nu != 0
    return sigma + 1.0 / nu[keep], B @ Y[:, keep]


def _sector_arpack(si, B, k, sigma, w, seed=0):
    """The ``k`` eigenvalues nearest ``sigma`` in ``span B`` (complex ARPACK on the inverse)."""
    n = B.shape[0]
    BW = B.conj().T * w[None, :]

    def op(x):
        y = _apply_complex(si, x.reshape(n, -1))
        return (B @ (BW @ y)).reshape(x.shape)

    A = spla.LinearOperator((n, n), matvec=op, dtype=complex)
    rng = np.random.default_rng(seed)
    v0 = B @ (rng.standard_normal(B.shape[1]) + 1j * rng.standard_normal(B.shape[1]))
    nu, V = spla.eigs(A, k=k, which="LM", v0=v0)
    nu = nu.real
    return sigma + 1.0 / nu, V


def _real_parts(vecs, w):
    """One real ``<.,.>``-unit eigenvector per Bloch eigenvector (the dephased real part)."""
    j = np.argmax(np.abs(vecs), axis=0)
    ph = vecs[j, np.arange(vecs.shape[1])]
    r = np.real(vecs * (np.conj(ph) / np.abs(ph))[None, :])
    return r / np.sqrt(np.sum(w[:, None] * r * r, axis=0))


def sector_spectrum(energy, curve: Curve, symmetry=None, k=None, sigma=0.0, sectors=None,
                    lagrange=None, constraints=None) -> SectorSpectrum:
    """Eigenvalues of ``J`` per Bloch sector from the factored operator (see the module docstring).

    Parameters
    ----------
    energy : Energy
    curve : Curve
        An equilibrium (the rigid modes are deflated).
    symmetry : BlochSymmetry, optional
        Default :func:`detect_symmetry`.
    k : int, optional
        Eigenvalues per sector nearest ``sigma``; default all of them (dense sectors;
        sectors larger than :data:`DENSE_SECTOR_LIMIT` need ``k``).
    sigma : float
        Shift of the factorization.
    sectors : sequence of int, optional
        Bloch indices to compute (default all, ``0..floor(n/2)``).
    lagrange : LagrangeHessian, optional
        Of ``energy`` at ``curve`` with the same ``constraints``.
    constraints : sequence of Constraint, optional
        Length / area constraints: the spectrum is that of the constrained operator.

    Returns
    -------
    SectorSpectrum

    Raises
    ------
    ValueError
        Bad ``energy``/``curve``/``symmetry``/``k``/``sectors``.

    Examples
    --------
    A circle's sectors are its Fourier modes; mode 2 of Faceting(0.1, 5) + Perimeter at
    R = 1 is the double eigenvalue ``-9 (0.04 + 0.5) = -4.86``:

    >>> from qsa.equilibria import circle
    >>> eq = circle(1.0, 0.1, grid=33)
    >>> s = sector_spectrum(eq.energy, eq.curve)
    >>> i = list(s.sector).index(2)
    >>> round(float(s.eigenvalues[i]), 8), int(s.multiplicity[i]), s.n_unstable
    (-4.86, 2, 0)
    """
    check_input(energy, curve)
    sym = detect_symmetry(curve) if symmetry is None else symmetry
    if not isinstance(sym, BlochSymmetry) or sym.N != curve.N or curve.N % sym.order:
        raise ValueError("symmetry must be a BlochSymmetry of this curve's grid "
                         "(from detect_symmetry(curve))")
    todo = sym.sectors if sectors is None else tuple(int(b) for b in sectors)
    if any(b < 0 or b > sym.order // 2 for b in todo):
        raise ValueError(f"sectors must lie in 0..{sym.order // 2}, got {sectors!r}")
    q = sym.shift
    if k is None and q > DENSE_SECTOR_LIMIT:
        raise ValueError(f"sectors of dimension {q} > {DENSE_SECTOR_LIMIT}: pass k "
                         "(eigenvalues per sector nearest sigma)")
    if k is not None and (isinstance(k, bool) or int(k) != k or k < 1):
        raise ValueError(f"k must be a positive integer, got {k!r}")
    cons = bind_constraints(constraints, curve)
    LH = lagrange if lagrange is not None else lagrange_hessian(energy, curve, constraints=cons)
    op = FactoredNormalOperator.from_lagrangian(curve, LH.matrix, LH.energy_hessian)
    R, Rc = constraint_bases(curve, cons)
    w = curve.dsigma
    si = _shift(op, float(sigma), R, np.append(op.ritz_values(R), 0.0), Rc)
    kvals, _, kerr = si.kernel_ritz(R)
    vals, vecs, secs = [], [], []
    complete = True
    for b in todo:
        B = _deflated_basis(sector_basis(sym, b, w), np.vstack([R, Rc]), w)
        if B.shape[1] == 0:
            continue
        if k is None or (B.shape[1] <= DENSE_SECTOR_LIMIT and k >= B.shape[1] // 2):
            lam, V = _sector_dense(si, B, si.sigma, w)
            if k is not None:
                order = np.argsort(np.abs(lam - sigma))[: int(k)]
                lam, V = lam[order], V[:, order]
                complete = complete and lam.size == B.shape[1]
        else:
            lam, V = _sector_arpack(si, B, min(int(k), B.shape[1] - 2), si.sigma, w)
            complete = False
        V = V / np.sqrt(np.sum(w[:, None] * np.abs(V) ** 2, axis=0))
        vals.append(lam)
        vecs.append(V)
        secs.append(np.full(lam.size, b))
    lam = np.concatenate(vals) if vals else np.zeros(0)
    V = np.hstack(vecs) if vecs else np.zeros((curve.N, 0), complex)
    sec = np.concatenate(secs).astype(int) if secs else np.zeros(0, int)
    err = si.errors(lam, _real_parts(V, w)).total if lam.size else np.zeros(0)
    order = np.argsort(-lam, kind="stable")
    mult = np.array([sym.multiplicity(b) for b in sec[order]], dtype=int)
    return SectorSpectrum(lam[order], err[order], sec[order], mult, V[:, order], kvals, kerr,
                          sym, w, complete, float(sigma))
