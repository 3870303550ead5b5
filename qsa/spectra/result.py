"""Result types of the spectral analysis: :class:`Spectrum` and :class:`KernelReport`."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = ["Spectrum", "KernelReport", "MESSAGES"]

#: Meaning of :attr:`Spectrum.status` (0 success, positive: computed with a warning,
#: negative: failure).
MESSAGES = {
    0: "eigenvalues computed and certified",
    1: "the curve is not an equilibrium: the eigenvalues are those of the operator at it",
    2: "some eigenvalues are unresolved (failed the accuracy test): see Spectrum.unresolved",
    -1: "the eigen-solver failed",
}


@dataclass(frozen=True, eq=False)
class KernelReport:
    """Residuals of the exact kernel relations at a curve.

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
        ``d_kE = Lambda_3`` at equilibrium (Conventions and errata, section 4).
    energy_kernel_predicted : float
        The relative size of ``Lambda_3 nabla^2 C_3 (nabla_s kappa, 0) =
        (0, Lambda_3 nabla_s kappa / g)``, which ``energy_kernel`` should equal.
    rigid : ndarray, shape (3,)
        ``|M r_j| / (|M| |r_j|)`` for the rigid motions (lem:kerM).
    psi : ndarray, shape (3,)
        ``|M-dagger Psi_j| / (|M| |Psi_j|)`` (``ker M-dagger``).
    reparameterization : float
        ``|L_Lambda M(0, v)| / (|L_Lambda| |M(0, v)|)`` for a random smooth ``v``
        (Fourier modes 1..8 with normal random coefficients, fixed seed), with the
        part of ``L_Lambda M(0, v)`` in ``span(Psi, nabla_I c)`` removed: the area and
        ``C_1, C_2`` are reparameterization invariant on the closed manifold only, so
        their Hessians leave such a part, which ``M-dagger`` (the flow) removes.
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
    constraint_multipliers : ndarray, shape (m,)
        Multipliers of the length / area constraints (empty without).
    two_point : dict or None
        For an energy with a two-point term, the relative residuals of its rigid-motion
        invariants (``TwoPointInvariants.summary()`` of
        :func:`qsa.energies.adhesion_invariants`: per level set, force and curvature
        forms); None otherwise.

    Parameters
    ----------
    Constructed by :func:`kernel_report` (and :func:`spectrum`); the fields are the
    attributes above.

    Examples
    --------
    >>> from qsa.equilibria import circle
    >>> from qsa.spectra import kernel_report
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
    constraint_multipliers: np.ndarray = field(default_factory=lambda: np.zeros(0))
    two_point: dict | None = None

    def summary(self) -> dict:
        """JSON-serialisable dict.

        Returns
        -------
        dict
        """
        out: dict[str, Any] = {}
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
    errors : ndarray, shape (m,)
        Absolute error estimate of each eigenvalue as an eigenvalue of the discrete
        operator (:mod:`qsa.spectra.factored`: residual of the inverse problem, the
        solve's forward error and the rounding of the factors; ``eps |J|`` for values
        taken from the formed matrix). Every reported eigenvalue satisfies
        ``errors <= rtol |lambda|`` or is a deflated rigid (kernel) mode; the
        discretization error is not included (see ``drift``).
    is_kernel : ndarray of bool, shape (m,)
        The deflated rigid motions (their Ritz values, ``n_kernel`` of them unless a
        further eigenvalue is zero within its error).
    unresolved : ndarray
        Eigenvalue estimates that failed the ``rtol`` test (not reported as eigenvalues;
        a warning is issued when there are any).
    unresolved_errors : ndarray
        Their error estimates.
    eigenvectors : ndarray, shape (n, m)
        Columns, normalised in ``<.,.>`` (``"normal"``: nodal ``phi``, dsigma weights;
        ``"comoving"``/``"paper"``: stacked ``(kappa1, g1)``; ``"scaled"``:
        ``(kappa1, g1)`` with weights ``(dsigma, L)``).
    n_unstable : int
        Number of eigenvalues with ``Re lambda > kernel_tol`` (with ``k``: among the k
        computed ones).
    n_kernel : int
        The deflated rigid modes plus the eigenvalues that are zero within their error.
    kernel_tol : float
        The size of the kernel eigenvalues (the rigid Ritz values and their errors):
        ``|lambda| <= kernel_tol`` holds for the kernel.
    n_small : int
        Size of the cluster of small eigenvalues: the ``m >= max(n_kernel, 1)``
        maximising ``gap_ratio = |lambda|_(m) / |lambda|_(m-1)`` over the ``|lambda|``
        sorted increasingly (floored at the round-off level ``10 eps |J|``), among
        the smallest ``N // 4``. For a splice of 2N fronts (N corners) well apart,
        ``n_small = 2N - 1``: the 2N front positions less the total-turning
        constraint, i.e. the 2N - 4 free splice parameters (Conventions and errata, section 5) plus
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
        ``eps |J|`` (``|J|`` the ``<.,.>`` operator norm): the round-off level of
        eigenvalues computed from the formed matrix. ``J`` is of order 6 for the
        faceting energy (4 for Canham-Helfrich), so this grows like ``N^6``; the
        eigenvalues below ``roundoff / rtol`` are computed from the factors instead
        (:mod:`qsa.spectra.factored`), whose errors are in ``errors``.
    max_imag : float
        ``max |Im lambda| / max(|lambda|)`` before taking real parts (0 for ``"normal"``).
    asymmetry : float
        Relative non-self-adjointness of ``J`` as assembled (``"normal"`` only; NaN otherwise).
    multipliers : ndarray, shape (3,)
    projection_residual, relative_residual : float
        Distance from a constrained critical point (see :class:`KernelReport`).
    rtol : float
        The relative accuracy required of a reported eigenvalue.
    success : bool
    status : int
        A key of :data:`MESSAGES`: 0 ok, 1 not an equilibrium (warning issued),
        2 some eigenvalues unresolved (warning issued), -1 eigen-solver failure.
    message : str
    constraints : tuple of Constraint
        The length / area constraints of the constrained linearization (empty without):
        the spectrum is that of ``P J P`` on the complement of their normal variations.
    constraint_multipliers : ndarray, shape (m,)
        Their multipliers ``mu_c``.

    Parameters
    ----------
    Constructed by :func:`spectrum`; the fields are the attributes above.

    Examples
    --------
    >>> import numpy as np
    >>> from qsa.equilibria import circle
    >>> from qsa.spectra import spectrum
    >>> eq = circle(1.0, 0.1, grid=17, kstar=5.0)
    >>> s = spectrum(eq.energy, eq.curve)
    >>> s.n_unstable, s.n_kernel, np.round(s.eigenvalues[2:4], 6).tolist()
    (0, 2, [-4.86, -4.86])
    >>> s.unstable.size, s.summary()["n_eigenvalues"]
    (0, 17)
    """

    eigenvalues: np.ndarray
    eigenvectors: np.ndarray
    errors: np.ndarray
    is_kernel: np.ndarray
    unresolved: np.ndarray
    unresolved_errors: np.ndarray
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
    rtol: float = 1e-6
    success: bool = True
    status: int = 0
    message: str = ""
    constraints: tuple = ()
    constraint_multipliers: np.ndarray = field(default_factory=lambda: np.zeros(0))

    def __repr__(self):
        return (f"Spectrum(gauge={self.gauge!r}, method={self.method!r}, N={self.N}, "
                f"n_eigenvalues={self.eigenvalues.size}, n_unstable={self.n_unstable}, "
                f"n_kernel={self.n_kernel}, n_small={self.n_small}, "
                f"n_spurious={self.spurious.size}, n_unresolved={self.unresolved.size}, "
                f"status={self.status})")

    @property
    def unstable(self) -> np.ndarray:
        """The eigenvalues counted by ``n_unstable``.

        Returns
        -------
        ndarray, shape (n_unstable,)
        """
        return self.eigenvalues[self._unstable_mask()]

    def _unstable_mask(self):
        re = np.real(self.eigenvalues)
        return (~self.is_kernel) & (re > self.errors) & (re > 0)

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
            "eigenvalues": num(ev), "errors": [float(e) for e in self.errors[:max_eigenvalues]],
            "n_unresolved": int(self.unresolved.size), "unresolved": num(self.unresolved),
            "rtol": self.rtol, "n_unstable": self.n_unstable, "n_kernel": self.n_kernel,
            "kernel_tol": self.kernel_tol, "n_small": self.n_small,
            "gap_ratio": self.gap_ratio, "n_spurious": int(self.spurious.size),
            "roundoff": self.roundoff, "max_imag": self.max_imag, "asymmetry": self.asymmetry,
            "multipliers": [float(x) for x in self.multipliers],
            "projection_residual": self.projection_residual,
            "relative_residual": self.relative_residual,
            "success": self.success, "status": self.status, "message": self.message,
            "kernel": self.kernel.summary(),
            "constraints": [k.params() for k in self.constraints],
            "constraint_multipliers": [float(m) for m in self.constraint_multipliers],
        }
