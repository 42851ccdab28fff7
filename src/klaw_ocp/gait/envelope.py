"""The supported space of walks: what both solver modes promise to converge on (docs/envelope.md).

The paper checks the locomotion parameters "within anatomical limits defined by locomotion
attributes" (section 3). The solvers' promise is that envelope made explicit: inside it every walk
converges in both modes, from rest or on the periodic orbit, to rest or not; outside it the plan
is refused with a one-line :class:`~klaw_ocp.errors.GaitLimitError` before anything is solved.

- body height and mass: :data:`SUPPORTED_HEIGHT_M`, :data:`SUPPORTED_MASS_KG` (the body model
  itself accepts a wider human range, for the dynamics alone);
- speed, step length and step frequency: the limit attributes (``speed_min`` ... ``sf_max``),
  checked by eq. 1 (:mod:`.parameters`);
- a step no longer than :data:`NATURAL_STEP_RATIO_MAX` times eq. 1's natural step for its speed
  (sl_nat = sqrt(0.004 · H · v)), and below :data:`SLOW_CADENCE_SPM` steps/min no longer than
  :data:`SLOW_CADENCE_RATIO_MAX` times it. Measured (docs/envelope.md): at 40-50 steps/min steps of
  1.74-1.94 × the natural one fail, at 30-36 steps/min 1.3 × fails; fig. 10's 0.65 × and 1.36 × and
  5 km/h at 1.57 × converge. "A more angular motion might result if the step length deviates
  significantly from the natural one" (§3): far enough, the paper's torque shapes have no solution;
- a schedule changes speed and step length by at most ``max_speed_change_per_step`` (km/h) and
  ``max_step_length_change_rel`` (× l1) from one step to the next: the low level adapts with a
  granularity of one step (principle 1), and a step that has to absorb a larger jump has no
  solution in the paper's torque shapes. A start from rest and a stop at rest are not such jumps:
  the middle level has its own first and closing steps for them (docs/walk.md).
"""
from __future__ import annotations

from ..body import Body
from ..errors import GaitLimitError
from .parameters import KMH_TO_M_PER_MIN, natural_step_length

#: Body heights (m) and masses (kg) inside which both solver modes are promised to converge.
SUPPORTED_HEIGHT_M = (1.4, 2.1)
SUPPORTED_MASS_KG = (40.0, 150.0)
#: The highest step frequency supported (steps/min): eq. 2's double support is then 13 ms long.
#: Measured: at 175 plain shooting fails some swing2s, at 180 (1 ms of double support) every
#: walk fails. The paper's anatomical limit sf_max = 182 is where the double support vanishes.
SUPPORTED_SF_MAX = 170.0
#: The longest step supported, as a multiple of eq. 1's natural step at the same speed.
NATURAL_STEP_RATIO_MAX = 1.6
#: Below this step frequency (steps/min) only near-natural steps are supported ...
SLOW_CADENCE_SPM = 40.0
#: ... up to this multiple of the natural step.
SLOW_CADENCE_RATIO_MAX = 1.2


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


def check_step_length(body: Body, parameters, index: int) -> None:
    """Raise GaitLimitError if step ``index`` is faster in cadence, or longer for its speed, than
    the envelope allows."""
    natural = natural_step_length(body.height, parameters.speed_kmh * KMH_TO_M_PER_MIN)
    if parameters.step_frequency_spm > SUPPORTED_SF_MAX * (1 + 1e-9):
        raise GaitLimitError(
            f"walk.step[{index}].step_frequency: got {parameters.step_frequency_spm:.4g} steps/min, allowed at most "
            f"{SUPPORTED_SF_MAX:g} steps/min (the walks the solvers support, docs/envelope.md: the double support "
            f"of eq. 2 is shorter than 13 ms above it)")
    slow = parameters.step_frequency_spm < SLOW_CADENCE_SPM
    ratio_max = SLOW_CADENCE_RATIO_MAX if slow else NATURAL_STEP_RATIO_MAX
    if parameters.step_length_m > ratio_max * natural * (1 + 1e-9):
        where = f" below {SLOW_CADENCE_SPM:g} steps/min" if slow else ""
        raise GaitLimitError(
            f"walk.step[{index}].step_length: got {parameters.step_length_m:.4g} m at "
            f"{parameters.speed_kmh:.4g} km/h and {parameters.step_frequency_spm:.4g} steps/min, allowed at most "
            f"{ratio_max:g} x eq. 1's natural step ({natural:.4g} m){where} (the walks the solvers support, "
            f"docs/envelope.md; shorten the step or raise the speed)")
