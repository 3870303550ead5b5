"""Flow models: the paper's DAE systems (one module per model)."""

from qsa.flows.models.cha import CHA, CHASystem
from qsa.flows.models.curve_dae import CurveDAE, equalize_chords, self_intersections
from qsa.flows.models.faceting import FacetingFlow, FacetingSystem
from qsa.flows.models.second_order import SecondOrderFlow, SecondOrderSystem, flow_model

__all__ = ["CHA", "CHASystem", "CurveDAE", "FacetingFlow", "FacetingSystem", "SecondOrderFlow",
           "SecondOrderSystem", "equalize_chords", "flow_model", "self_intersections"]
