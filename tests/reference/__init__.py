"""Reference numbers the tests compare against, each with where it comes from.

* ``paper_appendix.json`` -- the paper's Table ap:t1 and time-step counts, transcribed
  from the appendix of ``quasisteady-patterns.tex``.
* ``closed_forms.json`` -- closed-form values evaluated in mpmath.
* :mod:`tests.reference.circle_spectra` -- closed-form circle spectra (faceting,
  Canham-Helfrich) and the paper-gauge regression value.
* :mod:`tests.reference.orbits` -- mpmath (60-digit) periods of the periodic orbits of
  the front equation.
* ``cha_trillium_equilibrium.json`` -- a CHA (adhesion) equilibrium polished on a
  Fourier grid, the starting point of the two-point polish tests (provenance in its
  ``description``).

:func:`load` reads a JSON file; keys starting with ``_`` are provenance notes, and
numeric keys of a table (``"50"``, ``"1e-3"``) are returned as numbers.
"""

import json
from pathlib import Path

HERE = Path(__file__).parent


def _numbers(d):
    out = {}
    for k, v in d.items():
        if k.startswith("_"):
            continue
        try:
            key = int(k)
        except ValueError:
            try:
                key = float(k)
            except ValueError:
                key = k
        out[key] = _numbers(v) if isinstance(v, dict) else v
    return out


def load(name):
    """The tables of ``<name>.json`` without their notes.

    Examples
    --------
    >>> load("paper_appendix")["time_steps"][1e-3]
    65
    """
    return _numbers(json.loads((HERE / f"{name}.json").read_text()))
