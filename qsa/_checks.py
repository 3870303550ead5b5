"""Validation of arguments shared by every layer (bad input -> one-line ``ValueError``).

Each checker returns the converted value or raises a ``ValueError`` whose message
names the argument, says what it must be, and shows what was given:

* :func:`real_number` -- a finite float, optionally positive / non-negative / inf allowed;
* :func:`integer` -- a Python or NumPy integer (not a bool), optionally ``>= minimum``;
* :func:`finite_array` -- a float array without NaN or inf, optionally of a given shape.

Examples
--------
>>> real_number("0.5", "alpha", positive=True)
0.5
>>> real_number(float("nan"), "tol", positive=True)
Traceback (most recent call last):
...
ValueError: tol must be a positive finite number, got nan
>>> integer(3.0, "maxiter", minimum=0)
Traceback (most recent call last):
...
ValueError: maxiter must be an integer >= 0, got 3.0
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["real_number", "integer", "finite_array"]


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

    Examples
    --------
    >>> real_number(-1, "beta", nonnegative=True)
    Traceback (most recent call last):
    ...
    ValueError: beta must be non-negative, got -1
    >>> real_number("inf", "t_final", positive=True, allow_inf=True)
    inf
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


def integer(value, name, *, minimum=None, what="", too_small=None) -> int:
    """``int(value)`` for a Python or NumPy integer (not a bool), or a ``ValueError``.

    Parameters
    ----------
    value : object
        An ``int`` or ``numpy.integer``; floats (even integral ones) and bools are
        rejected, so that a mistyped argument is not silently truncated.
    name : str
        The argument's name, used in the message.
    minimum : int, optional
        Smallest accepted value.
    what : str, optional
        What the integer counts (``"number of nodes"``), put in the message.
    too_small : str, optional
        Message when ``value < minimum``, a format string with the fields
        ``name``, ``value`` and ``minimum`` (it should say why); default
        ``"{name}={value}: need {name} >= {minimum}"``.

    Returns
    -------
    int

    Examples
    --------
    >>> integer(np.int64(5), "N", minimum=4)
    5
    >>> integer(True, "n_pulses")
    Traceback (most recent call last):
    ...
    ValueError: n_pulses must be an integer, got True
    >>> integer(1, "n_pulses", minimum=2,
    ...         too_small="{name}={value}: one pulse cannot close, need {name} >= {minimum}")
    Traceback (most recent call last):
    ...
    ValueError: n_pulses=1: one pulse cannot close, need n_pulses >= 2
    """
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
        bound = "" if minimum is None else f" >= {minimum}"
        what = f" {what}" if what else ""
        raise ValueError(f"{name} must be an integer{what}{bound}, got {value!r}")
    v = int(value)
    if minimum is not None and v < minimum:
        template = "{name}={value}: need {name} >= {minimum}" if too_small is None else too_small
        raise ValueError(template.format(name=name, value=v, minimum=minimum))
    return v


def finite_array(value, name, *, shape=None) -> np.ndarray:
    """``numpy.asarray(value, dtype=float)`` without NaN or inf, of the given shape.

    Parameters
    ----------
    value : array_like
    name : str
        The argument's name, used in the message.
    shape : tuple, optional
        Required shape; an entry ``None`` accepts any length along that axis.

    Returns
    -------
    ndarray
        A float array (a new one only if a conversion was needed).

    Examples
    --------
    >>> finite_array([1, 2, 3], "t_eval", shape=(None,)).tolist()
    [1.0, 2.0, 3.0]
    >>> finite_array([[1.0, np.nan]], "x")
    Traceback (most recent call last):
    ...
    ValueError: x must be finite; it contains NaN or inf
    >>> finite_array([1.0, 2.0], "origin", shape=(3,))
    Traceback (most recent call last):
    ...
    ValueError: origin has shape (2,), expected (3,)
    """
    try:
        a = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be an array of real numbers, got {value!r}") from None
    if shape is not None and (a.ndim != len(shape) or any(
            n is not None and m != n for m, n in zip(a.shape, shape, strict=True))):
        want = "(" + ", ".join("n" if n is None else str(n) for n in shape) \
            + ("," if len(shape) == 1 else "") + ")"
        raise ValueError(f"{name} has shape {a.shape}, expected {want}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be finite; it contains NaN or inf")
    return a
