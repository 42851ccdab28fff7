"""The high level of KLAW (section 3): locomotion parameters (eq. 1) and their limits, state-phase
timings (eq. 2), step symmetry (eq. 3), locomotion attributes, and the per-step plan of a walk."""
from .attributes import ATTRIBUTES, AttributeSpec, LocomotionAttributes
from .parameters import LocomotionParameters, complete_parameters
from .plan import StepPlan, closing_step, plan_steps, stance_leg
from .symmetry import StepConstraints, landing_heel, step_constraints
from .timings import StateTimings, state_phase_timings

__all__ = [
    "ATTRIBUTES", "AttributeSpec", "LocomotionAttributes",
    "LocomotionParameters", "complete_parameters",
    "StateTimings", "state_phase_timings",
    "StepConstraints", "step_constraints", "landing_heel",
    "StepPlan", "plan_steps", "closing_step", "stance_leg",
]
