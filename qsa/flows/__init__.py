"""Curve flows: the paper's DAE models (``dae``), implicit steppers (``stepper``) and the
driver ``solve_flow`` (``solve``)."""

from qsa.flows.dae import CHA, FacetingFlow, equalize_chords, self_intersections
from qsa.flows.solve import FlowInterrupted, FlowResult, solve_flow

__all__ = ["CHA", "FacetingFlow", "FlowInterrupted", "FlowResult", "solve_flow",
           "equalize_chords", "self_intersections"]
