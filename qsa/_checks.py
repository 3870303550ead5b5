"""Validation of scalar arguments shared by every layer (bad input -> ``ValueError``).

Examples
--------
>>> real_number("0.5", "alpha", positive=True)
0.5
>>> real_number(float("nan"), "tol", positive=True)
Traceback (most recent call last):
...
ValueError: tol must be a positive finite number, got nan
"""

from __future__ import annotations

import math

__all__ = ["real_number"]


def real_number(value, name, *, positive=False, nonnegative=False, allow_inf=False) -> float:
    """``float(value)``, or a ``ValueError`` naming ``name`` that says what is wrong.

    Parameters
    ----------
    value : object
        Anything ``float`` accepts.
    name : str
        The argument's name, used in the message.
    positive, nonnegative : bool
        Require ``value > 0`` / ``value >= 0``.
    allow_inf : bool
        Accept ``+inf`` (NaN is never accepted).

    Returns
    -------
    float
    """
    kind = "positive " if positive else "non-negative " if nonnegative else ""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a {kind}number, got {value!r}") from None
    if math.isnan(v) or (math.isinf(v) and not allow_inf):
        raise ValueError(f"{name} must be a {kind}finite number, got {value!r}")
    if (positive and not v > 0) or (nonnegative and not v >= 0):
        raise ValueError(f"{name} must be {kind.strip()}, got {value!r}")
    return v
