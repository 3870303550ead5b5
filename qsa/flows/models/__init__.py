"""Flow models: the paper's DAE systems (one module per model)."""

from qsa.flows.models.cha import CHA, CHASystem
from qsa.flows.models.curve_dae import CurveDAE, equalize_chords, self_intersections
from qsa.flows.models.faceting import FacetingFlow, FacetingSystem

__all__ = ["CHA", "CHASystem", "CurveDAE", "FacetingFlow", "FacetingSystem", "equalize_chords",
           "self_intersections"]
