"""A walk solved one step at a time, its locomotion parameters changed between steps (section 2.4
principle 1, section 5: "KLAW is able to adapt to changes in the locomotion parameters from step
to step"; docs/serve.md).

:class:`StepwiseWalk` runs the same state machine as :func:`klaw_ocp.walk.simulate_walk`
(:class:`klaw_ocp.walk.StepLoop`), but decides each step's plan as the walk goes: before a step is
solved, the plan of the step after it is made from the parameters asked for by then. A change
larger than the envelope's per-step limits (``max_speed_change_per_step``,
``max_step_length_change_rel``) is spread over as many steps as it needs, as a schedule's ramp is.

Every step's plan comes from (speed, step length) through eq. 1 (:func:`klaw_ocp.gait.plan.plan_step`),
so the walk is a schedule with an entry at every step from its first change to its last:
:meth:`StepwiseWalk.reproducing_config` writes that schedule, and ``klaw-ocp run`` of it solves the same
steps, to the bit.

Each step's body frames (the root and the 56 angles at the walk's fps) are computed when the step
after it is solved, on a window of those few steps (:func:`klaw_ocp.step_body.step_frames`): a
step's stance leg is completed by the next step's double support, so a step's frames are final
one step later; all the rest of them is built before (:func:`klaw_ocp.step_body.prepare_step_frames`).
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace

from .body_motion.motion import BodyMotion, prepare_kernels
from .config import ExperimentConfig, check_stance_method, check_walk_size
from .config import MAX_FRAMES
from .control.gains import control_gains
from .control.step import StanceStage, StepController, StepResult
from .errors import ConfigError, GaitLimitError, out_of_range
from .gait import closing_step
from .gait.envelope import check_step_changes, check_step_length
from .gait.parameters import complete_parameters
from .gait.attributes import ATTRIBUTES, STEP_ATTRIBUTES
from .gait.plan import MAX_STEPS, MAX_WALK_S, PARAMETER_KEYS, plan_step
from .results import step_table
from .solvers import make_solver
from .solvers.thread_safety import solving
from .step_body import PreparedStep, prepare_step_frames, step_frames
from .step_loop import StepLoop, with_next_plan
from .walk import Walk, walk_spec


@dataclass(frozen=True)
class ReadyStep:
    """A solved step with its body: ``result`` (the step's solution), ``dynamics`` (its rows of
    dynamics.csv, :func:`klaw_ocp.results.step_table`), ``frames`` (its body frames) and
    ``solve_s`` (the seconds :meth:`StepwiseWalk.next_step` took to make it ready: the next step's
    stance half solved, and this step's swings where they were not solved before, and its frames
    finished, or built whole where they were not prepared: :func:`~klaw_ocp.step_body.step_frames`)."""
    index: int
    result: StepResult
    dynamics: dict
    frames: BodyMotion
    solve_s: float
    closing: bool


class StepwiseWalk:
    """A walk solved step by step from an experiment configuration (its body, attributes, solver,
    first parameters, start from rest or not), whose parameters can change before any step.

    - :meth:`request` asks for new locomotion parameters (any of speed km/h, step_length m,
      step_frequency steps/min, completed with eq. 1), refused with one line if outside the
      envelope; the walk moves to them as fast as the per-step limits allow;
    - :meth:`stop` ends the walk at rest (the paper's closing step) after the steps already planned;
    - :meth:`next_step` solves one more step and returns the previous one with its body frames
      (:class:`ReadyStep`), None once the walk has ended.

    One thread at a time calls :meth:`next_step` (the server: a worker thread per step);
    :meth:`request` and :meth:`stop` may be called from another thread meanwhile, as they only set
    what the next plan reads (one assignment each)."""

    def __init__(self, config: ExperimentConfig, method: str | None = None):
        if not isinstance(config, ExperimentConfig):
            raise ConfigError(out_of_range("config", config, "a klaw_ocp.config.ExperimentConfig"))
        self.config = config
        spec = walk_spec(config, method)
        check_stance_method(spec.stance, spec.method)
        self.body, self.attributes = spec.body, spec.attributes
        request = config.walk.request()
        # the walk asked for, before a start from rest's ramp caps its first steps (plan_step
        # applies that ramp to every step, as plan_steps does)
        p0 = (complete_parameters(self.body, speed_kmh=request["speed"], step_length=request["step_length"],
                                  step_frequency=request["step_frequency"], attributes=self.attributes)
              if any(v is not None for v in request.values()) else spec.plans[0].parameters)
        #: the walk's base request: the first step's speed and step length, as every step's are
        self._base = (p0.speed_kmh, p0.step_length_m)
        #: each planned step's (v, sl) as given to eq. 1 (the completed speed may differ from it
        #: in the last bit, so the schedule carries these, not the completed ones)
        self._requested = [self._base]
        #: each planned step's values of the attributes that may change per step (STEP_ATTRIBUTES)
        self._step_attributes = [self._step_values(self.attributes)]
        self._parameters = [self._complete(*self._base, "walk")]
        #: what was asked for last: the (v, sl) to move to and the per-step attributes' values, one
        #: tuple so that a request from another thread is taken whole by the next plan
        self._asked = (self._base, self._step_attributes[0])
        self._plans = [plan_step(self.body, self.attributes, 0, self._parameters[0], 0.0, 0.0,
                                 spec.start_from_rest)]
        self._stop_asked = False
        self._closing_at: int | None = None
        self.spec = replace(spec, plans=list(self._plans), end_at_rest=False)
        self.walk = Walk(self.spec)
        self.refusals: list[str] = []
        with solving():
            solver = make_solver(spec.method, intervals=spec.intervals, tolerance=spec.tolerance,
                                 max_iterations=spec.max_iterations, nlp=spec.nlp)
            controller = StepController(spec.body, spec.attributes, control_gains(spec.body, spec.attributes),
                                        solver, spec.lock_rule, spec.stance)
            self._loop = StepLoop(self.spec, controller, self._plan_of)
        self.walk.initial_state = self._loop.initial_state.copy()
        prepare_kernels()        # the body's (compiled or loaded now, not at the first step's frames)
        self._shown = 0          # the next step to hand out with its frames
        #: the stance half of the step after the last one solved whole (:meth:`finish_ahead`)
        self._ahead: StanceStage | None = None
        #: the body of the last step solved whole, built before the next step's stance half
        #: (:meth:`finish_ahead`): next_step finishes it (:func:`step_frames`)
        self._prepared: PreparedStep | None = None
        #: each solved step's rows of dynamics.csv until it is handed out
        self._rows: dict = {}
        #: the error of the step that failed, which ended the walk (None while it goes on)
        self.failed: Exception | None = None
        self.ended = False

    # -- the high level, one step ahead --------------------------------------------------------
    def _complete(self, v: float, sl: float, field: str):
        return complete_parameters(self.body, speed_kmh=v, step_length=sl, attributes=self.attributes,
                                   field_prefix=field)

    def request(self, attributes: dict | None = None, **values) -> dict:
        """Ask for new locomotion parameters (a subset of speed km/h, step_length m and
        step_frequency steps/min, completed with eq. 1) and new values of the ``attributes`` that
        may change per step (STEP_ATTRIBUTES: the determinants of gait and the toe clearance; the
        others are the walker's), from the next step that can change. Returns the completed target
        {speed, step_length, step_frequency} (with "attributes": every per-step one as it will be,
        when some were asked for); raises ConfigError / GaitLimitError (one line) outside the
        envelope or their ranges, the walk going on as before: nothing is taken unless all is."""
        extra = sorted(set(values) - set(PARAMETER_KEYS))
        if extra:
            raise ConfigError(out_of_range(extra[0], values[extra[0]], "one of speed, step_length, step_frequency"))
        if attributes is not None and not isinstance(attributes, dict):
            raise ConfigError(out_of_range("attributes", attributes, "a mapping of attribute name to number"))
        target = {}
        if values:
            p = complete_parameters(self.body, speed_kmh=values.get("speed"), step_length=values.get("step_length"),
                                    step_frequency=values.get("step_frequency"), attributes=self.attributes,
                                    field_prefix="walk")
            check_step_length(self.body, p, len(self._plans))
            target = {"speed": p.speed_kmh, "step_length": p.step_length_m, "step_frequency": p.step_frequency_spm}
        asked_target, asked_values = self._asked
        step_values = dict(zip(STEP_ATTRIBUTES, asked_values))
        for name, value in (attributes or {}).items():
            if name not in STEP_ATTRIBUTES:
                raise ConfigError(out_of_range(f"attributes.{name}", value, "an attribute that may change per "
                                               "step: " + ", ".join(STEP_ATTRIBUTES)))
            step_values[name] = ATTRIBUTES[name].check(value)
        if attributes:
            target["attributes"] = step_values
        self._asked = ((target["speed"], target["step_length"]) if values else asked_target,
                       tuple(step_values[name] for name in STEP_ATTRIBUTES))
        return target

    @staticmethod
    def _step_values(attrs) -> tuple:
        return tuple(attrs.get(name) for name in STEP_ATTRIBUTES)

    def _attributes_of(self, values: tuple):
        """The walk's attributes with these values of STEP_ATTRIBUTES (the walk's own object where
        they are its own, as a schedule without attributes plans)."""
        if values == self._step_values(self.attributes):
            return self.attributes
        return self.attributes.with_overrides(dict(zip(STEP_ATTRIBUTES, values)))

    def stop(self) -> None:
        """End the walk at rest: the next step planned is the closing step (sl = 0)."""
        self._stop_asked = True

    def _ramped(self, previous: tuple, target: tuple) -> tuple:
        """The next step's (v, sl): the target, or as far towards it as the per-step limits allow
        (speed and step length moving together, a straight line as a schedule's ramp)."""
        dv, dsl = target[0] - previous[0], target[1] - previous[1]
        dv_max = self.attributes.max_speed_change_per_step
        dsl_max = self.attributes.max_step_length_change_rel * self.body.l1
        steps = max(abs(dv) / dv_max, abs(dsl) / dsl_max)
        if steps <= 1.0:
            return target
        # a hair inside the limit, so that rounding never puts a step over it
        n = math.ceil(steps * (1 + 1e-9))
        return previous[0] + dv / n, previous[1] + dsl / n

    def _plan_next(self, i: int):
        """Step i's plan (i >= 1) from the target as it stands now, or None when the walk ends."""
        last = self._plans[-1]
        t, x = last.t_start + last.timings.t_step, last.constraints.next_ankle_x
        if self._closing_at is not None:
            return None
        long_enough = i >= MAX_STEPS - 1 or t + last.timings.t_step > MAX_WALK_S
        too_many_frames = (t + 2 * last.timings.t_step) * self.spec.fps > MAX_FRAMES
        if self._stop_asked or long_enough or too_many_frames:
            self._closing_at = i
            return closing_step(self.body, self.attributes, last)
        previous = self._requested[-1]
        target, step_values = self._asked
        wanted = self._ramped(previous, target)
        attrs = self._attributes_of(step_values)
        try:
            p = self._complete(*wanted, f"walk.schedule[{i}]") if wanted != previous else self._parameters[-1]
            plan = plan_step(self.body, attrs, i, p, t, x, self.spec.start_from_rest)
            check_step_changes(self.body, [last.parameters, plan.parameters], self.attributes)
        except GaitLimitError as err:     # not reachable from a checked target; kept safe all the same
            self.refusals.append(str(err))
            self._asked, wanted, p = (previous, step_values), previous, self._parameters[-1]
            plan = plan_step(self.body, attrs, i, p, t, x, self.spec.start_from_rest)
        self._step_attributes.append(step_values)
        self._requested.append(wanted)
        self._parameters.append(p)
        self._plans.append(plan)
        return plan

    def _revise_next_plan(self) -> None:
        """Plan the next step again from the target as it stands now, if it has changed since
        that plan was made (or a stop was asked): the step before it is solved, but its frames,
        which read this plan, are not made yet (:meth:`StepLoop.revise_next`). A change then
        reaches the second step after the one on screen, not the third."""
        k = self._loop.k
        if k == 0 or self._loop.current is None or k != len(self._plans) - 1 or self._closing_at is not None:
            return
        plan, requested, parameters = self._plans.pop(), self._requested.pop(), self._parameters.pop()
        step_values = self._step_attributes.pop()
        refusals = len(self.refusals)
        revised = self._plan_next(k)
        if self._closing_at is None and self._requested[-1] == requested and self._step_attributes[-1] == step_values:
            # nothing asked since: the plan made before stands
            self._plans[-1], self._requested[-1], self._parameters[-1] = plan, requested, parameters
            del self.refusals[refusals:]
            return
        self.walk.steps[-1] = self._loop.revise_next((revised, self._closing_at == k))

    def _plan_of(self, k: int):
        if k < len(self._plans):
            return self._plans[k], self._closing_at == k
        plan = self._plan_next(k)
        return None if plan is None else (plan, self._closing_at == k)

    # -- the middle and low levels -------------------------------------------------------------
    def next_step(self) -> ReadyStep | None:
        """Return the oldest step not yet handed out, with its frames, solving what they need: the
        step itself whole (its swings, unless :meth:`finish_ahead` solved them after the step before
        was handed out) and the next step's stance half (:meth:`StepLoop.begin_next`), whose swings
        the frames do not read; None once every step has been handed out. Raises
        :class:`~klaw_ocp.errors.ConvergenceError` if a step does not converge, which ends the
        walk (``failed``): nothing more is handed out."""
        t0 = time.perf_counter()
        k = self._shown
        if self.failed is not None:
            return None
        self.finish_ahead()
        while not self.ended and len(self.walk.steps) <= k:
            self._begin_next()
            self.finish_ahead()
        if k >= len(self.walk.steps):
            return None
        if not self.ended and len(self.walk.steps) == k + 1:
            self._begin_next()
        frames = step_frames(self.walk, k, self.spec.fps, self._ahead, self._prepared)
        self._prepared = None
        result = self.walk.steps[k]
        self._shown += 1
        return ReadyStep(k, result, self._rows.pop(k), frames, time.perf_counter() - t0, closing=self._closing_at == k)

    def _fail(self, err: Exception) -> None:
        """A step that did not converge (or any fault of it) ends the walk: nothing more is handed
        out (the step before it would otherwise go out as a last step it is not)."""
        self.failed, self.ended, self._ahead = err, True, None

    def _begin_next(self) -> None:
        """The next step's stance half, from its plan as it stands now (:meth:`_revise_next_plan`)."""
        try:
            self._revise_next_plan()
            with solving():
                self._ahead = self._loop.begin_next()
        except Exception as err:
            self._fail(err)
            raise
        if self._ahead is None:
            self.ended = True

    def finish_ahead(self) -> StepResult | None:
        """Solve the swings of the step whose stance half was solved ahead (the frames of the step
        before it needed that half alone), if any, and return that step. The server calls it once
        it has sent a step, while the page shows the one before; :meth:`next_step` calls it first
        otherwise. Either way the steps are solved in the same order, to the same numbers. The
        step's rows of dynamics.csv are made here too (they read that step alone), and its body as
        far as it does not wait for the next step's stance half (:func:`prepare_step_frames`)."""
        if self._ahead is None:
            return None
        self._ahead = None
        try:
            with solving():
                result = self._loop.finish_next()
        except Exception as err:
            self._fail(err)
            raise
        self.walk.steps.append(result)
        # its rows of dynamics.csv read the step alone (not the plan after it, which may still
        # change the stance leg's rules): final now
        self._rows[result.index] = step_table(result, self.body)
        # and its body as far as the steps solved fix it, the next step's stance foot as its plan
        # stands: the ask then waits only for what that step's stance half completes
        landing = self._loop.next_landing()
        if landing is not None:
            self._prepared = prepare_step_frames(self.walk, result.index, self.spec.fps, landing,
                                                 self._loop.current[0].t_start)
        return result

    def rows(self, k: int) -> dict:
        """Step k's rows of dynamics.csv, made when it was solved whole, until it is handed out
        (then they are its :class:`ReadyStep`'s ``dynamics``)."""
        return self._rows[k]

    @property
    def last_planned(self):
        """The plan made last (:class:`~klaw_ocp.gait.StepPlan`): the step the next change can reach
        is the one after it."""
        return self._plans[-1]

    def _steps_so_far(self, steps: int | None) -> int:
        """How many steps an export holds: ``steps``, or every step once the walk has ended, else
        the steps handed out; at least one, at most those solved."""
        n = (len(self.walk.steps) if self.ended else self._shown) if steps is None else steps
        if isinstance(n, bool) or not isinstance(n, int) or not 1 <= n <= len(self.walk.steps):
            raise ConfigError(out_of_range("session.steps", n, f"a whole number of steps from 1 to the "
                                           f"{len(self.walk.steps)} solved (a walk's first step handed out)"))
        return n

    def walk_so_far(self, steps: int | None = None) -> Walk:
        """The walk of its first ``steps`` steps (default: as :meth:`reproducing_config`), the last
        of them as the last step of a walk that ends there has it (its stance leg's knee schedule
        runs to its own double support's length, not the next step's: :func:`~klaw_ocp.step_loop.
        with_next_plan`): the walk ``klaw-ocp run`` of :meth:`reproducing_config` solves, to the bit."""
        n = self._steps_so_far(steps)
        last = with_next_plan(self._loop.controller, self.spec, self.walk.steps[n - 1], None)
        walk = Walk(self.spec, [*self.walk.steps[:n - 1], last])
        walk.initial_state = self.walk.initial_state
        return walk

    def reproducing_config(self, steps: int | None = None) -> ExperimentConfig:
        """The experiment that ``klaw-ocp run`` solves into this walk's first ``steps`` steps
        (default: the whole walk once it has ended, else the steps handed out so far), step for
        step (:meth:`walk_so_far`): the first step's speed and step length, a schedule entry at
        every step whose (v, sl) differs from the base (eq. 1 would complete a speed interpolated
        between two entries from its completed value, a bit off the one asked for, so every step
        from the first change to the last has its own entry), and the number of steps; ending at
        rest if the closing step is among them."""
        n = self._steps_so_far(steps)
        at_rest = self._closing_at is not None and n > self._closing_at
        regular = self._closing_at if at_rest else n
        # each step's (v, sl) and its values of the attributes that may change per step
        requested = list(zip(self._requested[:regular], self._step_attributes[:regular]))
        base = (self._base, self._step_values(self.attributes))
        changes = [i for i in range(1, len(requested)) if requested[i] != requested[i - 1]]
        first = next((i for i, r in enumerate(requested) if r != base), None)
        span = range(first, changes[-1] + 1) if first is not None else range(0)
        # the attributes that differ from the walk's at some step, in every entry
        moved = [j for j, name in enumerate(STEP_ATTRIBUTES) if any(r[1][j] != base[1][j] for r in requested)]
        schedule = [{"step": i, "speed": requested[i][0][0], "step_length": requested[i][0][1],
                     **({"attributes": {STEP_ATTRIBUTES[j]: requested[i][1][j] for j in moved}} if moved else {})}
                    for i in span]
        data = self.config.model_dump(mode="json")
        data["walk"] = {"speed": self._base[0], "step_length": self._base[1], "steps": regular,
                        "schedule": schedule, "start_from_rest": self.spec.start_from_rest,
                        "end_at_rest": at_rest}
        data["solver"]["method"] = self.spec.method
        data["attributes"] = self.attributes.as_dict()
        check_walk_size(regular, self.spec.intervals)
        return ExperimentConfig.from_mapping(data)
