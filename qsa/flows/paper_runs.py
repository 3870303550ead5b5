"""Deprecated location of the paper's simulation runs: use :mod:`qsa.paper.runs`.

The names below are aliases of :mod:`qsa.paper` (kept so existing code keeps working).
"""

from qsa.paper._files import write_output
from qsa.paper.results import coarsening_events
from qsa.paper.runs import resolution_check, run_cha, run_facet

__all__ = ["run_facet", "run_cha", "resolution_check", "coarsening_events", "write_output"]
