"""The result type of every equilibrium construction: :class:`Equilibrium`."""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from qsa.curve import Curve
    from qsa.energies.base import Energy

__all__ = ["Equilibrium"]


@dataclass(frozen=True, eq=False)
class Equilibrium:
    """An (exact, semi-analytic or quasi-) equilibrium curve and how far it is from one.

    Attributes
    ----------
    curve : Curve
        The state ``U = (kappa, g)`` on the requested grid.
    energy : Energy
        The energy it is an equilibrium of (e.g. ``Faceting + Perimeter`` with the
        reported ``L_star``); pass it on to ``qsa.spectra``.
    params : dict
        Construction parameters: ``"nu1"``, ``"nu2"``, ``"L"``, ``"L_star"`` where
        they apply, plus ``"alpha"``, ``"beta"``, ``"kstar"``, ``"n_pulses"``, ...
    multipliers : ndarray, shape (3,)
        Lagrange multipliers ``Lambda`` with ``grad_I E = Lambda . Psi``
        (e:Abs-CP); ``(0, 0, -nu1)`` for faceting N-pulses (Conventions and errata, section 5).
    residual : float
        ``max |V^n|`` on the grid, V^n the energy's normal velocity.
    closure : float
        ``|C(U)|`` (Euclidean norm of the closure defect, e:C1-e:C2).
    residual_scale : float
        The largest single term of ``V^n`` (``max |G mu|`` and ``max |kappa g d_g E|``),
        so ``residual / residual_scale`` is the relative residual.
    kind : str
        ``"npulse"``, ``"circle"``, ``"splice"``, ``"polished"``, ``"cha"`` (a CHA
        state as read, saved by ``qsa equilibrium cha`` without ``--polish``).
    success : bool
        Whether the construction met its tolerances.
    message : str

    Parameters
    ----------
    Constructed by :func:`~qsa.equilibria.npulse`, :func:`~qsa.equilibria.circle`,
    :func:`~qsa.equilibria.splice` and :func:`~qsa.equilibria.polish`; the fields
    are the attributes above.

    Examples
    --------
    >>> from qsa.equilibria import circle
    >>> eq = circle(1.0, 0.1, kstar=5.0)
    >>> eq.kind, bool(eq.success), bool(eq.relative_residual < 1e-10)
    ('circle', True, True)
    >>> {"kind", "success", "residual", "params"} <= set(eq.summary())
    True
    """

    curve: Curve
    energy: Energy
    params: dict
    multipliers: np.ndarray
    residual: float
    closure: float
    residual_scale: float = np.nan
    kind: str = "equilibrium"
    success: bool = True
    message: str = ""
    extra: dict = field(default_factory=dict, repr=False)

    @property
    def relative_residual(self) -> float:
        """``residual / residual_scale``.

        Returns
        -------
        float
        """
        return self.residual / self.residual_scale

    def summary(self) -> dict:
        """JSON-serialisable summary (no arrays).

        Returns
        -------
        dict
            Kind, success, message, residuals, params and multipliers.
        """
        p = {k: (float(v) if isinstance(v, (float, np.floating)) else v)
             for k, v in self.params.items()}
        return {
            "kind": self.kind,
            "success": bool(self.success),
            "message": self.message,
            "grid": repr(self.curve.grid),
            "params": p,
            "multipliers": [float(x) for x in self.multipliers],
            "residual": float(self.residual),
            "residual_scale": float(self.residual_scale),
            "closure": float(self.closure),
            "energy": float(self.energy.energy(self.curve)),
        }

    def to_json(self) -> str:
        """:meth:`summary` as an indented JSON string."""
        return json.dumps(self.summary(), indent=2)
