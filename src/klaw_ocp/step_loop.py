"""The middle level's state machine one step at a time (sections 2.2, 2.4, 5): each step solved
from its plan and the state the previous heel strike left, the next step's input made by the
heel-strike map (:func:`klaw_ocp.dynamics.heel_strike_map`), the stance leg handed on as the next
step's hind leg. :func:`klaw_ocp.walk.simulate_walk` runs it over a config's plans;
:class:`klaw_ocp.stepwise.StepwiseWalk` over plans it decides as the walk goes, and may revise the
next step's plan after the step before it was solved (:meth:`StepLoop.revise_next`).
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from .body import Body
from .control.periodic_start import periodic_start
from .control.step import StanceStage, StepController, StepInput, StepResult
from .control.step_stages import landing_stance_foot, stance_leg_rules
from .dynamics import heel_strike_map, stance_hips
from .kinematics.virtual_leg import StanceFoot, hind_foot_at_rest


def _first_input(controller: StepController, spec) -> StepInput:
    b, plan = spec.body, spec.plans[0]
    con = plan.constraints
    attrs = spec.attributes
    if spec.start_from_rest:
        x0 = np.array([b.l1, 0.0, controller.gains.theta2_ref, 0.0, 0.0, 0.0])
        return StepInput(x0, con.ankle_x, con.ankle_x, b.l1, 0.0, stance_standing=True)
    inp = StepInput(None, con.ankle_x, con.ankle_x - con.step_length, con.hip_y - b.l9,
                    _excursion(b, attrs, con.hip_y - b.l9, con.hip_y - b.l9))
    inp.x0 = periodic_start(controller, plan, inp)
    return inp


def _excursion(body: Body, attrs, y_start: float, y_end: float) -> float:
    """Height of the hip's mid-step bump above the higher heel-strike height (§4.2, Inman)."""
    midstance = body.l1 * (1 - attrs.midstance_leg_shortening)
    return max(midstance - max(y_start, y_end), attrs.min_hip_excursion_rel * body.l1)


class StepLoop:
    """The state machine one step at a time, shared by :func:`klaw_ocp.walk.simulate_walk` and
    :class:`klaw_ocp.stepwise.StepwiseWalk`, so that both give the same numbers for the same plans.

    ``plan_of(k)`` gives step k's plan and whether it is the closing step that ends at rest, or
    None when the walk has no step k. It is asked for step k + 1 before step k is solved (principle
    1: the high level before the step): this stance leg's toe-off ends the next step's double
    support, so its knee schedule needs that step's t_ds, and the heel-strike map its plan. A
    caller that decides the plans as the walk goes (the live playground) decides each one a step
    ahead."""

    def __init__(self, spec, controller: StepController, plan_of):
        self.spec, self.controller, self.plan_of = spec, controller, plan_of
        self.k = 0
        self.current = plan_of(0)
        first = self.current[0]
        inp = _first_input(controller, spec)
        self.initial_state = inp.x0
        # the kinematics meet the dynamics here: the virtual leg of each stance (§4.2) becomes
        # the next step's hind leg, whose toe-off starts that step's swing1
        inp.hind_foot = hind_foot_at_rest(spec.body, spec.attributes, inp.hind_ankle_x, spec.start_from_rest,
                                          first.timings.t_cycle, first.timings.t_ds)
        self.inp = inp
        #: the step solved last, and the stance half of the one begun after it (its swings not yet solved)
        self.last: StepResult | None = None
        self.pending: tuple | None = None     # (its StanceStage, plan_of's answer for the step after it)

    def solve_next(self) -> StepResult | None:
        """Solve the next step and return it; None once the walk has no step left."""
        if self.current is None:
            return None
        (plan, at_rest), k, following = self._begin()
        return self._advance(self.controller.solve_step(plan, self.inp, k, at_rest=at_rest), following)

    def begin_next(self) -> StanceStage | None:
        """Solve the next step's stance half (:class:`~klaw_ocp.control.step.StanceStage`), what the
        body of the step before reads of it; None once the walk has no step left. :meth:`finish_next`
        solves the rest of it (the same numbers as :meth:`solve_next`) before any further step."""
        if self.current is None:
            return None
        (plan, at_rest), k, following = self._begin()
        self.pending = (self.controller.solve_stance_stage(plan, self.inp, k, at_rest=at_rest), following)
        return self.pending[0]

    def finish_next(self) -> StepResult:
        """Solve the rest of the step begun last (:meth:`begin_next`: its swings) and return it."""
        if self.pending is None:
            raise ValueError("finish_next: no step begun")
        stage, following = self.pending
        self.pending = None
        return self._advance(self.controller.solve_swing_stage(stage), following)

    def next_landing(self) -> StanceFoot | None:
        """The foot the step solved last lands on: the next step's stance foot as its heel strike
        fixes it (``landing_foot`` of :meth:`begin_next`'s stance stage), from that step's plan and
        input as they stand; None when no step follows, or one is begun. Known before the next
        stance is solved (its first state is the heel-strike map's, which the solvers keep to the
        bit): the live playground builds the body of the step solved last with it while the page
        shows the step before, and checks it against the stance stage's once that is solved (the
        plan may be revised in between: docs/serve.md)."""
        if self.current is None or self.pending is not None:
            return None
        plan, body, inp = self.current[0], self.controller.body, self.inp
        origin = np.array([inp.origin_x, body.l9])
        hip = stance_hips(body, inp.x0[None], origin)[0][0]       # (solve_stance_stage's hips[0], one row)
        return landing_stance_foot(body, plan.attributes, plan, inp.x0, hip, inp.origin_x, inp.stance_standing,
                                   inp.next_t_ds)

    def _begin(self):
        """The next step's plan, index and the plan after it (principle 1: the high level before
        the step), which its stance leg's knee schedule reads."""
        if self.pending is not None:
            raise ValueError(f"step {self.pending[0].index}'s swings are not solved yet")
        following = self.plan_of(self.k + 1)
        next_plan = following[0] if following is not None else None
        # this stance leg's toe-off ends the next step's double support: its knee schedule
        # runs to that toe-off (this step's own where there is no next step)
        self.inp.next_t_ds = next_plan.timings.t_ds if next_plan is not None else None
        return self.current, self.k, following

    def _advance(self, result: StepResult, following) -> StepResult:
        # the step's stance leg is the next step's hind leg, whose double support completes it
        self.inp = _next_input(self.spec, result.plan, result, following[0] if following is not None else None)
        self.current, self.k, self.last = following, self.k + 1, result
        return result

    def revise_next(self, following) -> StepResult:
        """Give the next step, not yet solved, another plan (``(plan, at_rest)``, as ``plan_of``
        gives), and return the step solved last as it is with that plan after it
        (:func:`with_next_plan`): the walk is then the one whose plans were these from the start,
        to the bit (tests/test_stepwise.py). The live playground moves a change one step earlier
        so."""
        if self.current is None or self.last is None or self.pending is not None:
            raise ValueError("revise_next: no step solved yet, a step begun, or the walk has ended")
        self.last = with_next_plan(self.controller, self.spec, self.last, following[0])
        self.inp = _next_input(self.spec, self.last.plan, self.last, following[0])
        self.current = following
        return self.last


def with_next_plan(controller: StepController, spec, result: StepResult, next_plan) -> StepResult:
    """The solved step ``result`` as it is with ``next_plan`` after it (None: as the walk's last
    step, which a walk of its steps so far ends with).

    A step reads its successor's plan in two places only, neither of them its dynamics: its stance
    leg's virtual-leg rules (the knee's schedule runs to the toe-off that ends the next step's
    double support, whose length the plan fixes) and the heel-strike map's next input
    (:func:`_next_input`, the next stance's hip sinusoid). This makes the first again."""
    standing = result.index == 0 and spec.start_from_rest      # as _first_input starts it
    foot = stance_leg_rules(controller.body, result.plan.attributes, result.plan, result.subphase("stance"),
                            result.stance_hips, result.origin_x, standing,
                            next_plan.timings.t_ds if next_plan is not None else None)
    return replace(result, stance_foot=foot)


def _next_input(spec, plan, result: StepResult, next_plan) -> StepInput | None:
    """Heel strike: the swing leg lands at the next stance origin; map the stance state onto it."""
    if next_plan is None:
        return None
    b, con = spec.body, plan.constraints
    # the new stance starts from the landing leg's own hip, the pelvis's other one (§4.2): the
    # one-hip stance model's hip passes from one hip of the pelvis to the other, whose velocities
    # agree there (the pelvis turns with zero rate at heel strike)
    x_post = heel_strike_map(b, result.final_stance_state, np.array([con.step_length, 0.0]),
                             hip_shift=np.array([con.hip_shift, 0.0]))
    y_start = con.hip_y - b.l9
    y_end = next_plan.constraints.hip_y - b.l9
    excursion = 0.0 if next_plan.constraints.closing else _excursion(b, spec.attributes, y_start, y_end)
    # the next pelvis turns on from the rotation this one ended with, the one eq. 3 split this
    # step by (con.hip_shift = l0 sin of it; kinematics/pelvis.py)
    return StepInput(x_post, con.next_ankle_x, con.ankle_x, y_start, excursion, hind_foot=result.stance_foot,
                     pelvis_rotation=plan.attributes.rad("pelvic_rotation"))
