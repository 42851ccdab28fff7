"""One locomotion step at the low level: stance, hind-leg double support, swing1-3 (section 4).

:class:`StepController` turns a step's constraints (eq. 2, eq. 3) into the four subphase problems,
solves them with whichever solver it was given, and carries each subphase's torque parameters
over to initialise the next step ("the F profiles from one step are carried over to initialize
the next", §4.1). Frames: world x forward, y up, ground y = 0; the stance state is relative to the
stance ankle at ``(origin_x, l9)``.
"""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from .. import choices
from ..body import DYNAMIC_PARAMETER_NAMES, Body
from ..dynamics import knee_lock_map, stance_hips
from ..dynamics.evaluate import evaluate
from ..errors import ConvergenceError
from ..solvers import SubphaseProblem, SubphaseSolution, time_grid
from ..solvers.problem import mapped
from .gains import ControlGains
from .stance_law import PA_KNOTS, STANCE_CONTEXT, STANCE_PARAMETERS
from .stance_spec import (NO_LOCK_EVENTS, lock_context, lock_mode, stance_fixed,
                          stance_path_bounds, stance_spec, stance_unknowns)
from .swing_clearance import clearance_retraction
from .step_stages import (CLOSING_RETRY_CURVE_P_TRAVEL, MIN_CURVE_P_TRAVEL, CurveP, DoubleSupport, closing_hip_settle,
                          completed_hind_leg, double_support, landing_stance_foot, node_at, plan_curve_p, step_pelvis,
                          swing_context, thigh_peak, with_curve_p)
from .swing_law import SWING_CONTEXT
from .swing_spec import swing_specs
# (StepInput, StepResult and the stance notes are read from here too: what a step takes and gives)
from .step_result import StanceStage, StepInput, StepResult, lock_rule_notes, solved_without_events  # noqa: F401

#: The solvers' unknowns are scaled to order one by these magnitudes (finite differences, trust regions
#: and tolerances then act alike on each). F_theta1: 5 % of the body's weight times l1; the stance's pa
#: knots and offset 2 cm; swing1's F_theta3 fall and mean 20 % of the leg's weight times l1; swing2's knee
#: fall and mean 10 % of the shank's weight times l4, its recovery actuator 0.05 rad; swing3's moment 5 %.
F_THETA1_SCALE_REL = 0.05
STANCE_OTHER_SCALE = 0.02
SWING1_SCALE_REL = 0.2
SWING2_KNEE_SCALE_REL = 0.1
SWING2_RECOVERY_SCALE = 0.05
SWING3_SCALE_REL = 0.05
#: Swing2's recovery (§4.3): where the toe would touch the ground, the thigh's holding target is
#: moved by steps of this much (rad; negative: the thigh further forward, the hip torque larger).
SWING2_RECOVERY_STEP = -0.005
_HOLD_OFFSET = SWING_CONTEXT.index["hold_offset"]
#: swing1's continuation (:meth:`StepController.solve_swing1`): the shares of curve P's end slope,
#: and its name among a solve's fallbacks (summary.json, docs/solvers.md)
SWING1_CONTINUATION = (0.0, 0.5, 1.0)
CURVE_P_CONTINUATION = "curve-p-continuation"
#: the closing stance solved again from no push torque (:meth:`StepController.solve_stance`)
CLOSING_RESTART = "closing-restart"
#: a closing step's swing1 on a longer curve P (:meth:`StepController._closing_swings`)
CLOSING_LONGER_CURVE_P = "closing-longer-curve-p"
#: Slow steps' stances start on a graded grid (issue #36). Right after heel strike the leg spring
#: takes the impact and the state changes fastest, for as long whatever the step's duration; where
#: the uniform stance interval t_step / n is longer than GRADED_STANCE_ABOVE (s; at the default 20
#: intervals, below 2 km/h only: 88 ms at 0.5 km/h), RK4's error on the first interval was 5.5e-3
#: and the solved torques missed eq. 3 in the continuous model by 5.3e-4. The graded grid puts its
#: first nodes where STANCE_IMPACT_NODES puts them in the stance at that threshold (fractions of
#: n * GRADED_STANCE_ABOVE, 1 s: 30 to 200 ms after heel strike), which brings the miss to 3.1e-6;
#: the other intervals share the rest, none before the F_theta1 switch and on average none after
#: it longer than GRADED_STANCE_STRETCH uniform ones (a grid of too few intervals for that stays
#: uniform). Faster steps keep the uniform grid, bit for bit.
GRADED_STANCE_ABOVE = 0.05
STANCE_IMPACT_NODES = (0.03, 0.06, 0.10, 0.15, 0.20)
GRADED_STANCE_STRETCH = 4 / 3


def prepare_kernels(solver, lock_rule: str = choices.DEFAULT_LOCK_RULE) -> None:
    """Load, or compile, the kernels a walk with this solver and lock rule solves, at once on every core
    (a machine's first walk); a closing step's swing2 (most walks never stop) when a walk first stops."""
    solver.prepare([stance_spec(lock_rule, False), *(s for s in swing_specs(lock_rule).values() if not s.subphase)])


def stance_grid(t_step: float, n: int, breakpoints) -> np.ndarray:
    """The stance's n + 1 nodes over (0, t_step), every breakpoint on a node: uniform between the
    breakpoints or, for a slow step, dense after heel strike (:data:`GRADED_STANCE_ABOVE`)."""
    uniform = t_step / n
    plain = time_grid(0.0, t_step, n, breakpoints)
    if uniform <= GRADED_STANCE_ABOVE:
        return plain
    # the impact nodes, then even intervals up to the first breakpoint (the F_theta1 switch, 0.4
    # t_step by default), where the leg still rebounds from the impact and may lock: none longer
    # than GRADED_STANCE_STRETCH uniform ones (a longer one hid a dip of w past l1 from plain
    # shooting's events); then the plain grid of what is left, on average no coarser than that
    inside = sorted(b for b in breakpoints if 1e-9 < b < t_step - 1e-9)
    if not inside:                 # (a stance always has toe-off inside it)
        return plain
    switch, later = inside[0], inside[1:]
    impact = [t for t in (f * n * GRADED_STANCE_ABOVE for f in STANCE_IMPACT_NODES) if t < switch - 1e-9]
    rebound = math.ceil((switch - impact[-1]) / (GRADED_STANCE_STRETCH * uniform) - 1e-9) if impact else 0
    rest = n - len(impact) - rebound                # the intervals after the switch
    if not impact or rest < len(later) + 1 or (t_step - switch) / rest > GRADED_STANCE_STRETCH * uniform:
        return plain
    head = time_grid(0.0, switch, len(impact) + rebound, lead=[t / switch for t in impact])
    return np.concatenate([head, time_grid(switch, t_step, rest, later)[1:]])


def body_context(body: Body) -> dict:
    """The body's entries of every subphase context (:data:`klaw_ocp.body.DYNAMIC_PARAMETER_NAMES`)."""
    return dict(zip(DYNAMIC_PARAMETER_NAMES, body.dynamic_parameters()))


class StepController:
    """Builds and solves the subphase problems of successive steps with one solver."""

    def __init__(self, body: Body, attrs, gains: ControlGains, solver, lock_rule: str = choices.DEFAULT_LOCK_RULE,
                 stance_formulation: str = choices.DEFAULT_STANCE):
        self.body, self.attrs, self.gains, self.solver = body, attrs, gains, solver
        self.lock_rule = lock_rule
        #: "monitored" (the paper's square stance) or "tracking" (pa free over the grid, IPOPT)
        self.tracking = stance_formulation == choices.TRACKING
        self.n = solver.intervals
        self.swing_specs = swing_specs(lock_rule)
        prepare_kernels(solver, lock_rule)
        self.guesses: dict = {}
        #: the last solution of each subphase that multiple shooting's IPOPT found (a repair, an
        #: optimisation), with its multipliers
        self.ipopt_solutions: dict = {}
        #: the thigh retraction the last step needed (deg), the next step's first try
        self.retraction_hint: float | None = None
        torque = F_THETA1_SCALE_REL * (body.mass * body.g) * body.l1
        stance_scale = {"F_theta1_magnitude": torque, "F_theta1_brake": torque}
        self.stance_scale = {n: stance_scale.get(n, STANCE_OTHER_SCALE) for n in STANCE_PARAMETERS.names}
        hip, knee = SWING1_SCALE_REL * body.m1 * body.g * body.l1, SWING2_KNEE_SCALE_REL * body.m4 * body.g * body.l4
        self.scales = {"swing1": np.array([hip, hip]),          # F_theta3's fall and mean
                       "swing2": np.array([knee, SWING2_RECOVERY_SCALE, knee]),
                       "swing2_closing": np.array([knee, hip, knee, hip]),
                       "swing3": np.array([SWING3_SCALE_REL * body.m1 * body.g * body.l1])}

    # -- contexts ------------------------------------------------------------------------------
    def stance_context(self, plan, inp: StepInput) -> dict:
        b, g, t = self.body, self.gains, plan.timings
        ctx = body_context(b)
        ctx.update(k_w=g.k_w, v_w=g.v_w, k_t=g.k_t, d_t=g.d_t, theta2_ref=g.theta2_ref, k_y=g.k_y, c_y=g.c_y,
                   t_off=t.t_theta1_off, t_step=t.t_step, y_start=inp.y_start,
                   y_end=plan.constraints.hip_y - b.l9, excursion=inp.excursion,
                   hip_rise=self.attrs.hip_rise_fraction, hip_fall=self.attrs.hip_fall_fraction,
                   hip_fall_power=self.attrs.hip_fall_power, locked=0.0, hip_settle=closing_hip_settle(plan),
                   theta1_target=plan.constraints.theta1, w_target=plan.constraints.w)
        return ctx

    def _solve(self, step: int, problem: SubphaseProblem, remember: bool = True) -> SubphaseSolution:
        """Solve; raise ConvergenceError on failure; keep the parameters and, for a solution IPOPT
        found (its multipliers with it: a repair, an optimised problem), the whole solution, from
        which the next step's IPOPT starts when it solves the same problem (and the tracking
        stance from its node states whatever the problem)."""
        problem.previous_solution = self.ipopt_solutions.get(problem.spec.name)
        solution = self.solver.solve(problem)
        if not solution.success:
            raise ConvergenceError(step, problem.spec.solution_name, solution.residual, solution.message,
                                   iterations=solution.iterations, path_min=solution.path_min, nlp=solution.nlp,
                                   finite=bool(np.all(np.isfinite(solution.states))),
                                   max_iterations=getattr(self.solver, "max_iterations", None))
        if remember:
            self.guesses[problem.spec.name] = np.array([solution.parameters[k] for k in problem.spec.unknown_names])
            if solution.ipopt is not None:
                self.ipopt_solutions[problem.spec.name] = solution
            else:                  # a step that needed no IPOPT: the next one's is not like it
                self.ipopt_solutions.pop(problem.spec.name, None)
        return solution

    def _guess(self, name: str, nu: int) -> np.ndarray:
        return self.guesses.get(name, np.zeros(nu)).copy()

    def solve_stance(self, plan, inp: StepInput, index: int, at_rest: bool = False) -> SubphaseSolution:
        """The stance of a step; ``at_rest``: the closing stance that ends with theta1d = 0."""
        t = plan.timings
        grid = stance_grid(t.t_step, self.n, self._breakpoints(plan))
        ctx = STANCE_CONTEXT.pack(self.stance_context(plan, inp))
        names = stance_unknowns(at_rest)
        spec = stance_spec(self.lock_rule, at_rest)
        previous = dict(zip(stance_unknowns(), self._guess("stance", len(stance_unknowns()))))
        if "stance" not in self.guesses:
            previous["F_theta1_magnitude"] = self._balancing_torque(inp.x0)
        if not self.tracking:   # the paper's formulation: pa is the monitoring law plus the offset alone
            previous.update({k: 0.0 for k in PA_KNOTS})
        guess = np.array([previous.get(k, 0.0) for k in names])
        scale = np.array([self.stance_scale[k] for k in names])
        problem = SubphaseProblem(spec, inp.x0, grid, ctx, guess, scale, fixed=stance_fixed(at_rest),
                                  path_lower=stance_path_bounds(self.tracking, at_rest), optimize=self.tracking,
                                  state_guess=self._tracking_states(at_rest))
        # the closing stance has one more unknown: it must not seed the next walk's stances
        if not at_rest:
            return self._solve(index, problem)
        try:
            return self._solve(index, problem, remember=False)
        except ConvergenceError:
            magnitude = names.index("F_theta1_magnitude")
            if guess[magnitude] == 0.0:
                raise
        # A stop right after slowing down at the per-step limit to the slowest walk (3-9 -> 0.5
        # km/h, then stop at once): from the walking stance's push (-9 N m) plain shooting's
        # searches do not reach the stop's (+2.8 N m; multiple shooting's Newton does). A stop's
        # torques are small, so the closing stance starts again from none (docs/envelope.md).
        solution = self._solve(index, replace(problem, guess=np.where(np.arange(len(names)) == magnitude, 0.0, guess)),
                               remember=False)
        solution.fallbacks.insert(0, CLOSING_RESTART)
        return solution

    def _tracking_states(self, at_rest: bool) -> np.ndarray | None:
        """The node states the tracking stance starts from: the previous tracking stance's (IPOPT
        optimises it every step); none for the paper's square stance or the closing one."""
        previous = self.ipopt_solutions.get("stance")
        return previous.states if self.tracking and not at_rest and previous is not None else None

    def _balancing_torque(self, x0: np.ndarray) -> float:
        """A cold start's F_theta1: the torque that holds the stance leg against gravity at heel
        strike (A.1: b2 = F_theta1 + (m1 r1 + m2 w) g sin theta1). With zero torque instead, a slow
        walk's body falls backwards from its heel-strike posture and the first stance starts from a
        trajectory whose telescope ends metres long."""
        b = self.body
        return float(-(b.m1 * b.r1 + b.m2 * x0[0]) * b.g * math.sin(x0[1]))

    @staticmethod
    def _breakpoints(plan) -> list:
        t = plan.timings
        return [t.t_theta1_off, t.t_ds, t.t_ds + t.t_swing1_end, t.t_ds + t.t_swing2_end]

    # -- the whole step ------------------------------------------------------------------------
    def solve_step(self, plan, inp: StepInput, index: int, at_rest: bool = False) -> StepResult:
        """One step in its stages: the stance half (:meth:`solve_stance_stage`), then the swings
        (:meth:`solve_swing_stage`)."""
        return self.solve_swing_stage(self.solve_stance_stage(plan, inp, index, at_rest))

    def solve_stance_stage(self, plan, inp: StepInput, index: int, at_rest: bool = False) -> StanceStage:
        """The step's first stages, what the body of the step before reads: the stance (solved),
        the stance leg's heel-strike foot, the pelvis (its other hip, from which the hind leg and
        the swing hang), the hind leg's rules completed to toe-off."""
        b, a = self.body, plan.attributes       # (a schedule's per step)
        stance = self.solve_stance(plan, inp, index, at_rest)
        stance_ctx = self.stance_context(plan, inp)
        origin = np.array([inp.origin_x, b.l9])
        hips, hip_vels = stance_hips(b, stance.states, origin)   # world hip at every stance node
        landing = landing_stance_foot(b, a, plan, stance.states[0], hips[0], inp.origin_x, inp.stance_standing,
                                      inp.next_t_ds)
        pelvis = step_pelvis(b, a, plan, inp.stance_standing, inp.pelvis_rotation)
        other_hips, other_vels = pelvis.swing_side_hips(stance.t, hips, hip_vels)
        hind = completed_hind_leg(a, plan, stance, other_hips, inp.hind_foot)
        return StanceStage(index, plan, inp, at_rest, stance, stance_ctx, hips, hip_vels, other_hips, other_vels,
                           landing, pelvis, hind)

    def solve_swing_stage(self, stage: StanceStage) -> StepResult:
        """The step's other stages from its stance half: the stance leg's heel-off, the hind leg
        over the double support to toe-off, curve P and the swing foot, the swing context, the
        three swings (solved), the heel's clearance before it strikes."""
        b, plan, inp, index, stance, stance_ctx = self.body, stage.plan, stage.inp, stage.index, stage.stance, \
            stage.stance_ctx
        t, a, pelvis, other_hips, other_vels = plan.timings, plan.attributes, stage.pelvis, stage.other_hips, \
            stage.other_vels
        stance_foot = stage.landing_foot.find_heel_off(stance.t, stage.stance_hips)
        ds = double_support(plan, stance, other_hips, other_vels, stage.hind_foot)
        origin = np.array([inp.origin_x, b.l9])
        node_t1, node_to = node_at(stance.t, t.t_ds + t.t_swing1_end), node_at(stance.t, t.t_ds)
        events = None if stage.at_rest or solved_without_events(stance) else stance.events

        def swings_with(retraction_deg: float, least_travel: float = MIN_CURVE_P_TRAVEL):
            # curve P, the swing foot and the swing context are planned about the thigh's peak
            a_r = a if retraction_deg == a.terminal_swing_retraction else \
                a.with_overrides({"terminal_swing_retraction": retraction_deg})
            curve = plan_curve_p(b, a_r, plan, ds, other_hips[node_t1], other_vels[node_t1], least_travel)
            c = swing_context(b, a_r, self.gains, plan, stance_ctx, stance.parameters, origin, curve, pelvis)
            return self.solve_swings(plan, index, stance.states[node_to], ds, c, events, stance.t[node_to], curve), pelvis, curve, c
        # the swing leg high enough for a foot: the thigh's peak ahead of its landing angle where the ankle would
        # pass lower than l9 (control/swing_clearance.py); a closing step's thigh comes in from behind (thigh_peak)
        (swings, _, curve, c), retraction = (
            (self._closing_swings(swings_with, a.terminal_swing_retraction),
             math.degrees(plan.constraints.theta3 - thigh_peak(a, plan.constraints)))
            if stage.at_rest else clearance_retraction(b, swings_with, inp.origin_x, a.terminal_swing_retraction, self.retraction_hint))
        self.retraction_hint = None if inp.stance_standing else retraction     # (a first step's is its own)
        return StepResult(index=index, origin_x=inp.origin_x, hind_ankle_x=inp.hind_ankle_x,
                          t_start=plan.t_start, subphases=[stance, *swings],
                          double_support=ds.as_dict(), curve_p=curve.as_dict(),
                          final_stance_state=stance.final_state,
                          heel_clearance_min=self.heel_clearance_min(swings[-1], c),
                          plan=plan, notes=lock_rule_notes(stance, b.l1),
                          hip_reference={"y_start": inp.y_start, "y_end": stance_ctx["y_end"], "excursion": inp.excursion,
                                         **{k: stance_ctx[f"hip_{k}"] for k in ("rise", "fall", "settle")},
                                         "power": stance_ctx["hip_fall_power"]},
                          hind_foot=ds.hind_foot, hind_samples=ds.samples, stance_foot=stance_foot,
                          stance_hips=stage.stance_hips, swing_foot=curve.swing_foot, pelvis=pelvis,
                          thigh_retraction_deg=retraction)

    @staticmethod
    def _closing_swings(swings_with, retraction_deg: float):
        """A closing step's swings; where swing1 does not converge on its curve P, again on a curve
        spanning more of the ankle's travel (CLOSING_RETRY_CURVE_P_TRAVEL), noted among swing1's
        fallbacks."""
        try:
            return swings_with(retraction_deg)
        except ConvergenceError as err:
            if err.subphase != "swing1":
                raise
        swings, *rest = swings_with(retraction_deg, CLOSING_RETRY_CURVE_P_TRAVEL)
        swings[0].fallbacks.insert(0, CLOSING_LONGER_CURVE_P)
        return (swings, *rest)

    def solve_swings(self, plan, index: int, x_to: np.ndarray, ds: DoubleSupport, c: np.ndarray,
                     stance_events, t_toe_off: float, curve: CurveP) -> list[SubphaseSolution]:
        """Swing1 from the toe-off posture, swing2 from swing1's end (the knee's rate from swing1's
        kinematic constraint), swing3 from the knee locked at t2 (eq. 5). ``stance_events``: the
        stance's lock events, None in the closing step (whose stance has none)."""
        t = plan.timings
        t1, t2 = t.t_ds + t.t_swing1_end, t.t_ds + t.t_swing2_end
        specs, a = self.swing_specs, plan.attributes
        # The swing re-simulates the stance (swing_law.py), so with plain shooting's lock events it
        # must start in the stance's lock state at toe-off: locked after an early 'leg_too_long'
        # not yet undone by 'leg_vertical'; in the closing step, whose stance has no lock events,
        # with the swing specs' events disarmed. Each later subphase starts in the mode the one
        # before ended in. Multiple shooting has no events: its modes are unlocked and unused.
        mode1 = NO_LOCK_EVENTS if stance_events is None else lock_mode(stance_events, t_toe_off)
        c1 = lock_context(c, mode1)
        s1 = self.solve_swing1(index, SubphaseProblem(
            specs["swing1"], np.concatenate([x_to, [ds.theta3_toe_off, ds.theta4_toe_off, ds.theta3d_toe_off]]),
            time_grid(t.t_ds, t1, self.n, [t.t_theta1_off]), c1, self._guess("swing1", 2), self.scales["swing1"],
            mode=mode1), curve)
        x_end1 = s1.final_state
        mode2 = lock_mode(s1.events, mode=mode1)
        c2 = lock_context(c, mode2)
        u1 = [s1.parameters[k] for k in specs["swing1"].unknown_names]
        th4d = float(evaluate(specs["swing1"].rhs, x_end1, t1, u1, c2)[0][7])
        grid2, x02 = time_grid(t1, t2, self.n, [t.t_theta1_off]), np.concatenate([x_end1, [th4d]])
        if plan.constraints.closing:   # no recovery: the foot comes down in place (swing_spec.py, swing2_closing)
            s2 = self._solve(index, SubphaseProblem(specs["swing2_closing"], x02, grid2, c2, self._guess(
                "swing2_closing", 4), self.scales["swing2_closing"], mode=mode2))
        else:
            guess2 = self._guess("swing2", 3)
            guess2[1] = 0.0
            s2 = self._solve(index, SubphaseProblem(
                specs["swing2"], x02, grid2, c2, guess2, self.scales["swing2"], fixed=(False, True, False), mode=mode2,
                path_lower=np.array([a.toe_clearance, -np.inf]), recovery_step=np.array([0.0, SWING2_RECOVERY_STEP, 0.0])))
        x_end2 = s2.final_state
        knee = knee_lock_map(self.body, x_end2[6:10], np.zeros(2), self.lock_rule)   # the knee locks at t2
        mode3 = lock_mode(s2.events, mode=mode2)
        c3 = lock_context(c, mode3)        # with swing2's recovery shift, fading on in swing3
        c3[_HOLD_OFFSET] = s2.parameters.get("hip_actuator", 0.0)
        s3 = self._solve(index, SubphaseProblem(
            specs["swing3"], np.concatenate([x_end2[:6], [x_end2[6], knee[2]]]),
            time_grid(t2, t.t_step, self.n, [t.t_theta1_off]), c3, self._guess("swing3", 1),
            self.scales["swing3"], mode=mode3))
        return [s1, s2, s3]

    def solve_swing1(self, index: int, problem: SubphaseProblem, curve: CurveP) -> SubphaseSolution:
        """Swing1 on curve P; where that fails from the guess (a first step, a change of speed), by
        continuation from the paper's curve with y'(D) = 0, whose knee arrives at t1 at rest: its
        solution starts the curve half-way to the solved one's slope, that one the curve itself;
        where that fails too, or the curve is flat-ended already, with the solver's scan of the
        unknowns (``scan``, multiple shooting)."""
        scans = getattr(self.solver, "scans", False)
        try:
            return self._solve(index, problem)
        except ConvergenceError:
            if curve.end_slope == 0.0 and not scans:
                raise
        if curve.end_slope != 0.0:
            try:
                return self._continued_swing1(index, problem, curve)
            except ConvergenceError:
                if not scans:
                    raise
        # the last resort: the solver's scan of the unknowns about the guess (a first step's swing1
        # at 1.2-1.4 x the natural step and 3-6 km/h, whose all-zero guess stalls everything else)
        return self._solve(index, replace(problem, scan=True))

    def _continued_swing1(self, index: int, problem: SubphaseProblem, curve: CurveP) -> SubphaseSolution:
        solution = None
        for share in SWING1_CONTINUATION:
            stage = replace(problem, context=with_curve_p(problem.context, curve.with_end_slope(share)))
            if solution is not None:
                stage = replace(stage, guess=np.array([solution.parameters[k] for k in problem.spec.unknown_names]),
                                state_guess=solution.states)
            solution = self._solve(index, stage, remember=share == 1.0)
        solution.fallbacks.insert(0, CURVE_P_CONTINUATION)
        return solution

    def heel_clearance_min(self, swing3: SubphaseSolution, c: np.ndarray) -> float:
        """The heel's lowest height over swing3 before it strikes (all nodes in one call)."""
        heel = evaluate(mapped(self.swing_specs["swing3"].path, len(swing3.t) - 1), swing3.states[:-1], swing3.t[:-1],
                        swing3.parameters["F_theta3_moment"], c)[0]
        return float(heel.min()) if heel.size else 0.0
