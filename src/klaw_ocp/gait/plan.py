"""The high-level plan of a walk, step by step (section 2.4 principle 1, section 3, section 5).

The high-level concepts run before each step (principle 1): eq. 1 completes the locomotion
parameters, eq. 2 gives the timings and eq. 3 the final conditions. Changes of the parameters
take effect "with a granularity of one step" (section 5), which is what lets KLAW accelerate and
decelerate. :func:`plan_steps` applies this to a whole walk.

Schedule semantics (our reading of section 5; see docs/paper-map.md):

* An entry ``{step: k, ...}`` with any non-empty subset of ``speed`` (km/h), ``step_length`` (m)
  and ``step_frequency`` (steps/min) is completed with eq. 1 to a full parameter set at step k.
* Between two entries k_a < k_b, speed and step length are interpolated linearly per step and
  ``sf = v/sl``, so a walk speeds up or slows down smoothly. sf is then a ratio of two linear
  functions, monotone between the entries, so it never leaves the range the two entries span.
* Entries are listed in increasing step order (an entry out of order is refused, not sorted).
* Before the first entry the base walk parameters hold; after the last entry its values hold.
* Steps are numbered from 0. Step i starts where step i-1 ended: its stance origin is the
  previous step's ``next_ankle_x`` (the first starts at x = 0) and its start time is the sum of the
  previous steps' t_step.
* A duration becomes a number of steps by adding steps until their summed t_step reaches it
  (at least one step).
* A walk is at most :data:`MAX_STEPS` steps and :data:`MAX_WALK_S` seconds long.
"""
from __future__ import annotations

import math
import numbers
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

from ..body import Body
from ..errors import ConfigError, finite_real, out_of_range
from .attributes import ATTRIBUTES, STEP_ATTRIBUTES, LocomotionAttributes, resolve
from .envelope import check_body, check_step_changes, check_step_length
from .parameters import KMH_TO_M_PER_MIN, LocomotionParameters, complete_parameters, natural_step_length
from .symmetry import StepConstraints, step_constraints
from .timings import StateTimings, state_phase_timings

#: Keys of a request or schedule entry that carry locomotion parameters.
PARAMETER_KEYS = ("speed", "step_length", "step_frequency")
#: The longest walk accepted: at most this many steps ...
MAX_STEPS = 1000
#: ... and at most this many seconds of walking (the closing step of a walk that ends at rest
#: comes on top). Measured (docs/limits.md): the slowest walks to solve (fast cadence, short
#: steps) take about 0.15 s of CPU a step, so the longest walk is solved in a few minutes; its
#: memory and result files stay within a few hundred MB.
MAX_WALK_S = 600.0


def stance_leg(index: int) -> str:
    """Which leg is the stance leg of step ``index``: step 0's is the right leg, then they alternate."""
    return "right" if index % 2 == 0 else "left"


@dataclass(frozen=True)
class StepPlan:
    """Everything the low level needs to execute step ``index`` (the step constraints).

    ``t_start`` is the time (s) of the heel strike that begins the step, from the start of the walk.
    """

    index: int
    parameters: LocomotionParameters
    timings: StateTimings
    constraints: StepConstraints
    t_start: float = 0.0
    #: the step's locomotion attributes: the walk's, with a schedule's values of the
    #: :data:`~klaw_ocp.gait.attributes.STEP_ATTRIBUTES` at this step
    attributes: LocomotionAttributes = field(default_factory=LocomotionAttributes.defaults)

    def as_dict(self) -> dict:
        """A flat, JSON-ready dict; keys carry their unit (``_s``, ``_m``, ``_rad``, ...)."""
        c = self.constraints
        return {
            "index": self.index,
            "t_start_s": self.t_start,
            **self.parameters.as_dict(),
            **self.timings.as_dict(),
            "w_m": c.w, "theta1_rad": c.theta1, "theta3_rad": c.theta3,
            "hip_x_m": c.hip_x, "hip_y_m": c.hip_y,
            "ankle_x_m": c.ankle_x, "ankle_y_m": c.ankle_y,
            "heel_x_m": c.heel_x, "next_ankle_x_m": c.next_ankle_x,
            "r_m": c.r, "omega3_rad": c.omega3, "theta5_impact_rad": c.theta5,
            "hip_lead_m": c.hip_lead,
        }


def _request_values(request, field: str) -> dict:
    """The parameter values of a request (mapping or LocomotionParameters), None when absent."""
    if request is None:
        return {k: None for k in PARAMETER_KEYS}
    if isinstance(request, LocomotionParameters):
        return {"speed": request.speed_kmh, "step_length": request.step_length_m,
                "step_frequency": request.step_frequency_spm}
    if not isinstance(request, Mapping):
        raise ConfigError(out_of_range(field, request, "a mapping of speed, step_length, step_frequency"))
    return {k: request.get(k) for k in PARAMETER_KEYS}


def _complete(body, values: dict, attrs, prefix: str) -> LocomotionParameters:
    return complete_parameters(body, speed_kmh=values["speed"], step_length=values["step_length"],
                               step_frequency=values["step_frequency"], attributes=attrs,
                               field_prefix=prefix)


def _step_attributes(entry: Mapping, field: str) -> dict:
    """A schedule entry's ``attributes``: names among STEP_ATTRIBUTES, values in their ranges."""
    values = entry.get("attributes")
    if values is None:
        return {}
    if not isinstance(values, Mapping):
        raise ConfigError(out_of_range(f"{field}.attributes", values, "a mapping of attribute name to number"))
    checked = {}
    for name, value in values.items():
        if name not in STEP_ATTRIBUTES:
            raise ConfigError(out_of_range(f"{field}.attributes.{name}", value,
                                           "an attribute that may change per step: " + ", ".join(STEP_ATTRIBUTES)))
        checked[name] = ATTRIBUTES[name].check(value, f"{field}.attributes.{name}")
    return checked


def _parse_schedule(body, schedule, attrs) -> tuple[list[tuple[int, LocomotionParameters]], dict, dict]:
    """Completed entries in step order, each step's position in the user's list, and the
    attributes' keys: {name: [(step, value), ...]} in step order. Entries must come in increasing
    step order; one may set attributes only."""
    if schedule is None:
        return [], {}, {}
    if isinstance(schedule, (str, bytes, Mapping)) or not isinstance(schedule, Sequence):
        raise ConfigError(out_of_range("walk.schedule", schedule, "a list of {step, speed?, "
                                       "step_length?, step_frequency?} entries"))
    if len(schedule) > MAX_STEPS:
        raise ConfigError(f"walk.schedule: got {len(schedule)} entries, allowed at most {MAX_STEPS} "
                          f"(one per step)")
    entries: dict[int, LocomotionParameters] = {}
    positions: dict[int, int] = {}
    keyed: dict[str, list] = {}
    for j, entry in enumerate(schedule):
        field = f"walk.schedule[{j}]"
        if not isinstance(entry, Mapping):
            raise ConfigError(out_of_range(field, entry, "a mapping {step, speed?, step_length?, "
                                           "step_frequency?}"))
        extra = sorted(set(entry) - {"step", *PARAMETER_KEYS, "attributes"})
        if extra:
            raise ConfigError(out_of_range(f"{field}.{extra[0]}", entry[extra[0]],
                                           "only the keys step, speed, step_length, step_frequency, attributes"))
        k = entry.get("step")
        if isinstance(k, bool) or not isinstance(k, numbers.Integral) or k < 0:
            raise ConfigError(out_of_range(f"{field}.step", k, "an integer >= 0"))
        k = int(k)
        if k in positions:
            raise ConfigError(out_of_range(f"{field}.step", k, "a step not already in the schedule"))
        if positions and k < max(positions):
            last = max(positions)
            raise ConfigError(out_of_range(f"{field}.step", k, f"a step after {last} (walk.schedule"
                                           f"[{positions[last]}].step): entries in increasing step order"))
        values = _request_values(entry, field)
        step_attrs = _step_attributes(entry, field)
        if all(values[key] is None for key in PARAMETER_KEYS) and not step_attrs:
            raise ConfigError(out_of_range(field, dict(entry), "at least one of speed, step_length, "
                                           "step_frequency, attributes"))
        if any(values[key] is not None for key in PARAMETER_KEYS):
            entries[k] = _complete(body, values, attrs, field)
        for name, value in step_attrs.items():
            keyed.setdefault(name, []).append((k, value))
        positions[k] = j
    return sorted(entries.items()), positions, keyed


def _parameters_at(i: int, base: LocomotionParameters | None,
                   entries: list[tuple[int, LocomotionParameters]], body, attrs) -> LocomotionParameters:
    """The locomotion parameters of step ``i`` under the schedule semantics of this module."""
    if not entries or i < entries[0][0]:
        return base
    for (ka, pa), (kb, pb) in zip(entries, entries[1:]):
        if ka <= i < kb:
            if i == ka:
                return pa
            f = (i - ka) / (kb - ka)
            v = pa.speed_kmh + f * (pb.speed_kmh - pa.speed_kmh)
            sl = pa.step_length_m + f * (pb.step_length_m - pa.step_length_m)
            # sf = v/sl through eq. 1's v+sl branch, which also re-checks the limits.
            return complete_parameters(body, speed_kmh=v, step_length=sl, attributes=attrs,
                                       field_prefix=f"walk.step[{i}]")
    return entries[-1][1]


def _attributes_at(i: int, attrs: LocomotionAttributes, keyed: dict) -> LocomotionAttributes:
    """Step ``i``'s attributes: each scheduled one as a schedule's parameters are (the walk's
    before its first entry, linear between two entries, its last entry's after), the others the
    walk's; the walk's own object where nothing is scheduled."""
    if not keyed:
        return attrs
    values = {}
    for name, keys in keyed.items():
        if i < keys[0][0]:
            continue
        values[name] = keys[-1][1]
        for (ka, va), (kb, vb) in zip(keys, keys[1:]):
            if ka <= i < kb:
                values[name] = va + (i - ka) / (kb - ka) * (vb - va)
                break
    return attrs.with_overrides(values) if values else attrs


def _start_ramp(i: int, p: LocomotionParameters, body: Body, attrs) -> LocomotionParameters:
    """Step ``i`` of a walk from rest: no faster than ``start_speed_max + i·max_speed_change_per_step``.

    The first stance carries the body from standing to the step's heel-strike posture: at 9 km/h
    that is about 5 m/s² of forward acceleration, under which the swing leg trails so far that its
    toe can only clear the ground with an unnatural hip flexion. People reach a brisk pace over a
    few steps; so does the plan. A step above the ramp keeps its ratio to eq. 1's natural step
    (which grows with the square root of the speed), so the ramp runs smoothly into the steps asked for.
    """
    cap = attrs.start_speed_max + i * attrs.max_speed_change_per_step
    if p.speed_kmh <= cap:
        return p
    natural = lambda kmh: natural_step_length(body.height, kmh * KMH_TO_M_PER_MIN)  # noqa: E731
    step_length = p.step_length_m * natural(cap) / natural(p.speed_kmh)
    return complete_parameters(body, speed_kmh=cap, step_length=step_length, attributes=attrs,
                               field_prefix=f"walk.step[{i}]")


def plan_steps(body: Body, base_request=None, schedule=None, n_steps: int | None = None,
               duration: float | None = None,
               attributes: LocomotionAttributes | Mapping | None = None,
               start_from_rest: bool = False) -> list[StepPlan]:
    """Plan every step of a walk: parameters (eq. 1), timings (eq. 2) and constraints (eq. 3).

    Args:
        body: anthropometry.
        base_request: a mapping with any of ``speed`` (km/h), ``step_length`` (m),
            ``step_frequency`` (steps/min), or a :class:`LocomotionParameters`; may be empty only
            when the schedule has an entry at step 0.
        schedule: a list of mappings ``{step: k, speed?, step_length?, step_frequency?}``.
        n_steps: the number of steps (give this or ``duration``).
        duration: the walk's duration in s; steps are added until their t_step sum reaches it.
        attributes: locomotion attributes (defaults if None).
        start_from_rest: the walk starts standing; its speed then rises from at most
            ``start_speed_max`` by at most ``max_speed_change_per_step`` a step (:func:`_start_ramp`).

    Raises:
        ConfigError: malformed arguments, both or neither of n_steps/duration, a schedule entry
            beyond the last step.
        GaitLimitError: a step's parameters are outside the limits.
    """
    attrs = resolve(attributes)
    if (n_steps is None) == (duration is None):
        raise ConfigError(out_of_range("walk", f"steps={n_steps}, duration={duration}",
                                       "exactly one of steps or duration"))
    if n_steps is not None and (isinstance(n_steps, bool) or not isinstance(n_steps, numbers.Integral)
                                or not 1 <= n_steps <= MAX_STEPS):
        raise ConfigError(out_of_range("walk.steps", n_steps, f"an integer from 1 to {MAX_STEPS}"))
    if duration is not None and (isinstance(duration, bool) or not isinstance(duration, numbers.Real)
                                 or finite_real(duration) is None or not 0 < duration <= MAX_WALK_S):
        raise ConfigError(out_of_range("walk.duration", duration, f"a number > 0 and <= {MAX_WALK_S:g} s"))

    base_values = _request_values(base_request, "walk")
    check_body(body)
    entries, positions, keyed = _parse_schedule(body, schedule, attrs)
    if any(v is not None for v in base_values.values()):
        base = _complete(body, base_values, attrs, "walk")
    elif entries and entries[0][0] == 0:
        base = None  # never used: the schedule defines step 0 onwards
    else:
        raise ConfigError(out_of_range("walk", "no speed, step_length or step_frequency",
                                       "at least one of them, or a schedule entry at step 0"))

    plans: list[StepPlan] = []
    t, x = 0.0, 0.0
    while True:
        i = len(plans)
        if n_steps is not None and i >= n_steps:
            break
        if duration is not None and i >= 1 and t >= duration - 1e-9:
            break  # the tolerance keeps an exact multiple of t_step from adding a step
        if i >= MAX_STEPS:
            raise ConfigError(f"walk.duration: got {duration:g} s, which takes more than {MAX_STEPS} "
                              f"steps, allowed at most {MAX_STEPS} steps (docs/limits.md)")
        plan = plan_step(body, _attributes_at(i, attrs, keyed), i, _parameters_at(i, base, entries, body, attrs),
                         t, x, start_from_rest)
        plans.append(plan)
        t += plan.timings.t_step
        x = plan.constraints.next_ankle_x
        if n_steps is not None and t > MAX_WALK_S + 1e-9:
            raise ConfigError(f"walk.steps: got {n_steps} steps, which last more than {MAX_WALK_S:g} s "
                              f"({i + 1} steps take {t:.4g} s), allowed at most {MAX_WALK_S:g} s of "
                              f"walking (docs/limits.md)")

    # An entry the walk never reaches would be silently ignored; say so instead.
    last_step = max(positions) if positions else -1
    if last_step >= len(plans):
        raise ConfigError(out_of_range(f"walk.schedule[{positions[last_step]}].step", last_step,
                                       f"0 to {len(plans) - 1} (the walk has {len(plans)} steps)"))
    check_step_changes(body, [p.parameters for p in plans], attrs)
    return plans


def plan_step(body: Body, attrs, i: int, p: LocomotionParameters, t_start: float, ankle_x: float,
              start_from_rest: bool = False) -> StepPlan:
    """Step ``i`` with the parameters ``p`` (eq. 1 completed) starting at walk time ``t_start``
    with its stance ankle at ``ankle_x``: the start ramp of a walk from rest, the timings (eq. 2),
    the envelope's step check and the constraints (eq. 3). :func:`plan_steps` plans every step
    with it, and so does a walk planned step by step (:mod:`klaw_ocp.stepwise`)."""
    if start_from_rest:
        p = _start_ramp(i, p, body, attrs)
    timings = state_phase_timings(p.step_frequency_spm, attrs, field=f"walk.step[{i}].step_frequency")
    check_step_length(body, p, i)
    constraints = step_constraints(body, p.step_length_m, attrs, ankle_x=ankle_x,
                                   hip_shift=landing_hip_shift(body, attrs),
                                   hip_lead=heel_strike_hip_lead(body, attrs, p.speed_kmh))
    return StepPlan(index=i, parameters=p, timings=timings, constraints=constraints, t_start=t_start,
                    attributes=resolve(attrs))


#: the dimensionless speed v / sqrt(g (l1 + l9)) from which the hip leads by the whole attribute
#: ``heel_strike_hip_lead`` (0.45: 5 km/h on a 1.8 m body, about Schwartz et al.'s free speed);
#: slower steps lead in proportion. People's trailing heel is up at the other heel strike because
#: they push off; walking slowly they push off later and less. With the whole lead, a slow step's
#: stance leg must extend again after it has locked at l1 (w > l1 at its heel strike), which left
#: plain shooting's stance without a solution at 1 km/h on a 1.5 m body.
HIP_LEAD_FULL_SPEED = 0.45


def dimensionless_speed(body: Body, speed_kmh: float) -> float:
    """v / sqrt(g L), L = l1 + l9 the standing hip height: the speed of Schwartz et al.'s classes
    (:mod:`klaw_ocp.human_gait`) and of the hip's lead."""
    return speed_kmh / 3.6 / math.sqrt(body.g * (body.l1 + body.l9))


def heel_strike_hip_lead(body: Body, attrs, speed_kmh: float) -> float:
    """How far the hip is ahead of half-way along the step at heel strike, as a fraction of the
    step (eq. 3 with our deviation, :mod:`klaw_ocp.gait.symmetry`): the attribute
    ``heel_strike_hip_lead``, in proportion to the dimensionless speed below
    :data:`HIP_LEAD_FULL_SPEED`."""
    return attrs.heel_strike_hip_lead * min(1.0, dimensionless_speed(body, speed_kmh) / HIP_LEAD_FULL_SPEED)


def landing_hip_shift(body: Body, attrs) -> float:
    """How far the landing leg's hip is ahead of the stance hip at heel strike (m): the pelvis's
    width turned by the pelvic rotation (§4.2; :mod:`klaw_ocp.kinematics.pelvis`)."""
    return body.l0 * math.sin(attrs.rad("pelvic_rotation"))


def closing_step(body: Body, attributes, last: StepPlan) -> StepPlan:
    """The step that ends a walk at rest (section 5, fig. 8): the swing foot lands beside the
    stance foot (eq. 3 with sl = 0, so theta1 = 0 and w = l1 at the end) at the last step's
    frequency, timings and attributes; it starts where ``last`` ends. (``attributes``, the walk's,
    is kept in the signature for callers that plan a walk's steps and its close alike.)"""
    attributes = last.attributes
    params = LocomotionParameters(0.0, 0.0, last.parameters.step_frequency_spm)
    con = step_constraints(body, 0.0, attributes, ankle_x=last.constraints.next_ankle_x, closing=True)
    return StepPlan(last.index + 1, params, last.timings, con, last.t_start + last.timings.t_step, attributes)
