"""Parameter grids of a sweep: specs like ``"alpha=0.05:0.3:11"``, points and their file keys."""

from __future__ import annotations

import hashlib
import itertools
import json
import math
from dataclasses import dataclass

import numpy as np

__all__ = ["ParameterGrid", "parse_param", "point_key"]

_NAME_OK = set("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_")


def _scalar(text: str):
    """``"3"`` -> 3, ``"0.5"`` -> 0.5, ``"true"`` -> True, anything else -> the string."""
    t = text.strip()
    if t.lower() in ("true", "false"):
        return t.lower() == "true"
    for conv in (int, float):
        try:
            return conv(t)
        except ValueError:
            pass
    return t


def parse_param(spec: str):
    """Parse one grid specification into ``(name, values)``.

    Parameters
    ----------
    spec : str
        ``"name=start:stop:num"`` (``num`` equally spaced floats, both ends
        included, as :func:`numpy.linspace`), ``"name=v1,v2,..."`` (a list; ints stay
        ints), or ``"name=v"`` (one value).

    Returns
    -------
    name : str
    values : list
        Python scalars (``int``, ``float``, ``bool`` or ``str``).

    Raises
    ------
    ValueError
        Malformed spec; the message quotes it.

    Examples
    --------
    >>> parse_param("alpha=0.05:0.3:6")
    ('alpha', [0.05, 0.1, 0.15, 0.2, 0.25, 0.3])
    >>> parse_param("N=2,3,4")
    ('N', [2, 3, 4])
    """
    if not isinstance(spec, str) or "=" not in spec:
        raise ValueError(f"param spec {spec!r}: expected NAME=start:stop:num or NAME=v1,v2,...")
    name, _, rhs = spec.partition("=")
    name = name.strip()
    if not name or not set(name) <= _NAME_OK or name[0].isdigit():
        raise ValueError(f"param spec {spec!r}: {name!r} is not a valid parameter name")
    if not rhs.strip():
        raise ValueError(f"param spec {spec!r}: no values")
    if ":" in rhs:
        parts = rhs.split(":")
        if len(parts) != 3:
            raise ValueError(f"param spec {spec!r}: a range is start:stop:num")
        try:
            start, stop = float(parts[0]), float(parts[1])
            num = int(parts[2])
        except ValueError:
            raise ValueError(f"param spec {spec!r}: start and stop must be numbers and "
                             "num an integer") from None
        if num < 1 or not (math.isfinite(start) and math.isfinite(stop)):
            raise ValueError(f"param spec {spec!r}: need finite ends and num >= 1")
        # round away the last-bit noise of linspace so "0.1" reads back as 0.1
        values = [float(f"{v:.12g}") for v in np.linspace(start, stop, num)]
        return name, values
    values = [_scalar(v) for v in rhs.split(",")]
    if any(v == "" for v in values):
        raise ValueError(f"param spec {spec!r}: empty value in the list")
    return name, values


@dataclass(frozen=True)
class ParameterGrid:
    """The Cartesian product of named value lists (the first name varies slowest).

    Parameters
    ----------
    axes : tuple of (name, tuple of values)
    """

    axes: tuple

    def __post_init__(self):
        names = [n for n, _ in self.axes]
        if len(set(names)) != len(names):
            raise ValueError(f"params: a name is given twice in {names}")
        for n, vals in self.axes:
            if len(vals) == 0:
                raise ValueError(f"params: {n!r} has no values")

    @classmethod
    def parse(cls, specs) -> ParameterGrid:
        """Build from ``["alpha=0.05:0.3:11", "n_pulses=2,3"]`` (see :func:`parse_param`)."""
        if isinstance(specs, str):
            specs = [specs]
        return cls(tuple((n, tuple(v)) for n, v in map(parse_param, specs)))

    @classmethod
    def from_dict(cls, params: dict) -> ParameterGrid:
        """Build from ``{"alpha": [0.1, 0.2], "n_pulses": 3}`` (scalars become one value)."""
        axes = []
        for n, v in params.items():
            vals = [v] if np.isscalar(v) else list(v)
            axes.append((n, tuple(_python(x) for x in vals)))
        return cls(tuple(axes))

    @property
    def names(self) -> list:
        return [n for n, _ in self.axes]

    def points(self) -> list:
        """All points as dicts, in grid order."""
        return [dict(zip(self.names, combo, strict=True))
                for combo in itertools.product(*(v for _, v in self.axes))]

    def __len__(self):
        return math.prod(len(v) for _, v in self.axes)

    def to_json(self) -> dict:
        return {n: list(v) for n, v in self.axes}


def _python(x):
    """NumPy scalars -> Python scalars (JSON-able, picklable by value)."""
    if isinstance(x, np.generic):
        return x.item()
    return x


def point_key(study_name: str, params: dict) -> str:
    """Stable file key of a point: SHA-1 of the study name and its sorted parameters."""
    text = json.dumps([study_name, sorted((k, _python(v)) for k, v in params.items())])
    return hashlib.sha1(text.encode()).hexdigest()[:20]
