"""The supported space of walks: what both solver modes promise to converge on (docs/envelope.md).

The paper checks the locomotion parameters "within anatomical limits defined by locomotion
attributes" (section 3). The solvers' promise is that envelope made explicit: inside it every walk
converges in both modes, from rest or on the periodic orbit, to rest or not; outside it the plan
is refused with a one-line :class:`~klaw_ocp.errors.GaitLimitError` before anything is solved.

- body height and mass: :data:`SUPPORTED_HEIGHT_M`, :data:`SUPPORTED_MASS_KG` (the body model
  itself accepts a wider human range, for the dynamics alone);
- speed, step length and step frequency: the limit attributes (``speed_min`` ... ``sf_max``),
  checked by eq. 1 (:mod:`.parameters`);
- a schedule changes speed and step length by at most ``max_speed_change_per_step`` (km/h) and
  ``max_step_length_change_rel`` (× l1) from one step to the next: the low level adapts with a
  granularity of one step (principle 1), and a step that has to absorb a larger jump has no
  solution in the paper's torque shapes. A start from rest and a stop at rest are not such jumps:
  the middle level has its own first and closing steps for them (docs/walk.md).
"""
from __future__ import annotations

from ..body import Body
from ..errors import GaitLimitError

#: Body heights (m) and masses (kg) inside which both solver modes are promised to converge.
SUPPORTED_HEIGHT_M = (1.4, 2.1)
SUPPORTED_MASS_KG = (40.0, 150.0)


def check_body(body: Body) -> None:
    """Raise GaitLimitError if the body is outside the supported envelope."""
    for field, value, (low, high), unit in (("body.height", body.height, SUPPORTED_HEIGHT_M, "m"),
                                            ("body.mass", body.mass, SUPPORTED_MASS_KG, "kg")):
        if not low <= value <= high:
            raise GaitLimitError(f"{field}: got {value:g} {unit}, allowed {low:g} to {high:g} {unit} "
                                 f"(the walks the solvers support, docs/envelope.md)")


def check_step_changes(body: Body, parameters: list, attrs) -> None:
    """Raise GaitLimitError if consecutive steps change speed or step length by more than the
    per-step limits (``parameters``: the LocomotionParameters of the steps, in order)."""
    dv_max = attrs.max_speed_change_per_step
    dsl_max = attrs.max_step_length_change_rel * body.l1
    for i in range(1, len(parameters)):
        a, b = parameters[i - 1], parameters[i]
        dv, dsl = b.speed_kmh - a.speed_kmh, b.step_length_m - a.step_length_m
        if abs(dv) > dv_max * (1 + 1e-9):
            raise GaitLimitError(
                f"walk.schedule: got a speed change of {dv:+.4g} km/h from step {i - 1} to step {i} "
                f"({a.speed_kmh:.4g} -> {b.speed_kmh:.4g} km/h), allowed at most {dv_max:g} km/h per step "
                f"(attributes.max_speed_change_per_step; spread the change over more steps)")
        if abs(dsl) > dsl_max * (1 + 1e-9):
            raise GaitLimitError(
                f"walk.schedule: got a step-length change of {dsl:+.4g} m from step {i - 1} to step {i} "
                f"({a.step_length_m:.4g} -> {b.step_length_m:.4g} m), allowed at most {dsl_max:.4g} m per step "
                f"(attributes.max_step_length_change_rel × l1; spread the change over more steps)")
