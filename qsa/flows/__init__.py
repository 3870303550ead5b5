"""Curve flows: the paper's DAE models (``dae``), implicit steppers (``stepper``) and the
driver ``solve_flow`` (``solve``)."""

from qsa.flows.dae import (
    CHA,
    FacetingFlow,
    SecondOrderFlow,
    equalize_chords,
    flow_model,
    self_intersections,
)
from qsa.flows.solve import FlowInterrupted, FlowResult, solve_flow

__all__ = ["CHA", "FacetingFlow", "SecondOrderFlow", "FlowInterrupted", "FlowResult",
           "solve_flow", "flow_model",
           "equalize_chords", "self_intersections"]
