"""All of qsa's figures (the only package that imports matplotlib).

Figures are built with ``matplotlib.figure.Figure`` and the Agg canvas, so no
global backend is switched and nothing needs a display; pass ``ax`` to draw into
an existing figure (e.g. in a notebook).

One module per topic (``_core`` curves, ``spectra``, ``flows``, ``fronts``,
``simulations``, ``sweep``, ``bifurcation``, ``animation``); every public name is
re-exported here, so ``from qsa.plotting import plot_spectrum`` works whatever module
draws it.
"""

from __future__ import annotations

import importlib

from qsa.plotting._core import (  # noqa: F401
    new_figure,
    plot_curvature,
    plot_curve,
    plot_curve_and_curvature,
    save,
)

__all__ = ["new_figure", "plot_curve", "plot_curvature", "plot_curve_and_curvature", "save"]

#: Topic modules whose ``__all__`` is re-exported (missing ones are skipped).
_TOPICS = ("spectra", "flows", "fronts", "simulations", "sweep", "bifurcation", "animation")

for _topic in _TOPICS:
    try:
        _module = importlib.import_module(f"qsa.plotting.{_topic}")
    except ModuleNotFoundError as _exc:
        if _exc.name != f"qsa.plotting.{_topic}":
            raise
        continue
    for _name in _module.__all__:
        if _name in globals() and globals()[_name] is not getattr(_module, _name):
            raise ImportError(f"qsa.plotting.{_topic}.{_name} shadows another topic's {_name}")
        globals()[_name] = getattr(_module, _name)
        __all__.append(_name)
