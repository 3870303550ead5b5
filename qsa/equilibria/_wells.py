"""Deprecated location of the double wells: they live in :mod:`qsa.energies.wells`.

Re-exports ``QuarticWell``, ``resolve_well`` and ``is_quartic`` (and the scalar
check ``_positive``) for modules that still import them from here.
"""

from __future__ import annotations

from qsa._checks import real_number
from qsa.energies.wells import QuarticWell, is_quartic, resolve_well

__all__ = ["QuarticWell", "resolve_well", "is_quartic"]


def _positive(x, name):
    """``real_number(x, name, positive=True)`` under its old name."""
    return real_number(x, name, positive=True)
