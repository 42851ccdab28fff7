"""One locomotion step at the low level: stance, hind-leg double support, swing1-3 (section 4).

:class:`StepController` turns a step's constraints (eq. 2, eq. 3) into the four subphase problems,
solves them with whichever solver it was given, and carries each subphase's torque parameters
over to initialise the next step ("the F profiles from one step are carried over to initialize
the next", §4.1). Frames: world x forward, y up, ground y = 0; the stance state is relative to the
stance ankle at ``(origin_x, l9)``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..body import Body
from ..dynamics import knee_lock_map, stance_hips
from ..dynamics.evaluate import evaluate
from ..errors import ConvergenceError
from ..solvers import SubphaseProblem, SubphaseSolution, time_grid
from ..solvers.problem import mapped
#: Curve P spans at least this fraction of the ankle's travel from toe-off to its landing point
#: (steady steps: about 0.43 from the toe-under-knee rule). See docs/solvers.md, "The first step".
MIN_CURVE_P_TRAVEL = 0.4
#: The thigh rate that starts swing1 is the hind leg's mean rate over this fraction of t_ds before toe-off.
TOE_OFF_RATE_WINDOW = 0.1

from ..kinematics.swing_foot import SCHEDULE_FIELDS, SwingFoot
from ..kinematics.virtual_leg import toe_off_pitch
from .curve_p import curve_p_coefficients, swing1_end_posture
from .gains import ControlGains
from .stance_law import PA_KNOTS, STANCE_CONTEXT, STANCE_PARAMETERS
from .stance_spec import (NO_LOCK_EVENTS, lock_context, lock_mode, lock_rule_nodes, stance_fixed,
                          stance_path_bounds, stance_spec, stance_unknowns)
from .swing_law import FOOT_CONTEXT, SWING_CONTEXT
from .swing_spec import swing_specs


@dataclass
class StepInput:
    """What a step needs besides its plan: where it starts and how the body arrives there."""
    x0: np.ndarray                 # stance state at heel strike, relative to the stance ankle
    origin_x: float                # stance ankle x (flat-foot ankle, eq. 3's ankle1)
    hind_ankle_x: float            # flat-foot ankle x of the hind (soon swinging) leg
    y_start: float                 # hip height above the stance ankle at heel strike
    excursion: float               # height of the hip's mid-step bump (0 for start/stop steps)
    #: the hind leg's virtual leg (kinematics.virtual_leg.StanceFoot): its stance so far
    hind_foot: object = None


@dataclass
class StepResult:
    """A solved step: its subphase solutions plus the kinematic double support of the hind leg."""
    index: int
    origin_x: float
    hind_ankle_x: float
    t_start: float
    subphases: list
    double_support: dict
    curve_p: dict
    final_stance_state: np.ndarray
    heel_clearance_min: float
    plan: object = None
    notes: list = field(default_factory=list)
    #: the hip-height sinusoid the stance is guided towards (§4.2), in the stance ankle's frame:
    #: ``y_start``/``y_end`` (the two heel-strike heights) and ``excursion`` (the mid-step bump), m
    hip_reference: dict = field(default_factory=dict)
    #: the hind leg's virtual leg, completed by this step's double support, and its samples there
    #: (leg stance time, world hips)
    hind_foot: object = None
    hind_samples: tuple = ()
    #: this step's stance leg (kinematics.virtual_leg.StanceFoot): the rules its own stance fixed
    #: (heel strike, foot flat, heel-off), then completed by the next step's double support
    #: (:meth:`complete_stance_leg`, whose samples go to ``stance_samples``)
    stance_foot: object = None
    stance_samples: tuple = ()
    #: the world hip at every stance node (m)
    stance_hips: np.ndarray = None
    #: the swing foot's angle schedule (kinematics.swing_foot.SwingFoot), step-local times
    swing_foot: object = None

    def complete_stance_leg(self, following: "StepResult") -> None:
        """The next step's double support finished this stance leg: keep its rules and samples."""
        self.stance_foot = following.hind_foot
        self.stance_samples = following.hind_samples

    def stance_leg_frames(self):
        """This step's stance leg as a human leg (kinematics.virtual_leg.VirtualLegFrames) from its
        heel strike to its toe-off, at the stance's nodes and the next double support's; None until
        the next step has completed it."""
        if self.stance_foot is None or not self.stance_foot.complete:
            return None
        t_after, hips_after = self.stance_samples
        t = np.concatenate([self.subphase("stance").t, t_after[1:]])
        return self.stance_foot.frames(t, np.vstack([self.stance_hips, hips_after[1:]]))

    def subphase(self, name: str) -> SubphaseSolution:
        return next(s for s in self.subphases if s.name == name)


def lock_rule_notes(stance: SubphaseSolution, l1: float, tol: float = 1e-7) -> list:
    """How the stance met the lock rule (w <= l1 while theta1 < 0, once the leg has come down to l1).

    Plain shooting locks the leg (events); multiple shooting holds the rule as a path constraint,
    re-solving with IPOPT when the square solution breaks it. A breach left in a solution (the
    closing stance, or ``nlp: rootfinder``) is reported, not hidden.
    """
    if stance.events:
        return [f"stance lock events: {', '.join(f'{n} at t={t:.3f} s' for n, t in stance.events)}"]
    w = stance.states[:, 0]
    on_limit = lock_rule_nodes(stance.states, l1) & (w > l1 - tol)
    breach = np.flatnonzero(on_limit & (w > l1 + tol))
    if breach.size:
        return [f"lock rule not enforced: w exceeds l1 by {w[breach].max() - l1:.3g} m at "
                f"t={stance.t[breach[0]]:.3f} s while theta1 < 0"]
    if on_limit[1:].any() and stance.nlp == "ipopt":
        return [f"lock rule held by the path constraint w <= l1 (IPOPT), first at t={stance.t[np.argmax(on_limit)]:.3f} s"]
    return []


class StepController:
    """Builds and solves the subphase problems of successive steps with one solver."""

    def __init__(self, body: Body, attrs, gains: ControlGains, solver, lock_rule: str = "momentum",
                 stance_formulation: str = "monitored"):
        self.body, self.attrs, self.gains, self.solver = body, attrs, gains, solver
        self.lock_rule = lock_rule
        #: "monitored" (the paper's square stance) or "tracking" (pa free over the grid, IPOPT)
        self.tracking = stance_formulation == "tracking"
        self.n = solver.intervals
        self.swing_specs = swing_specs(lock_rule)
        # the first walk on a machine compiles these kernels: all at once, on every core
        solver.prepare([stance_spec(lock_rule, False), *self.swing_specs.values()])
        self.guesses: dict = {}
        self.previous_states: dict = {}
        weight = body.mass * body.g
        stance_scale = {"F_theta1_magnitude": 0.05 * weight * body.l1, "F_theta1_brake": 0.05 * weight * body.l1}
        self.stance_scale = {n: stance_scale.get(n, 0.02) for n in STANCE_PARAMETERS.names}
        self.scales = {"swing1": np.array([0.2 * body.m1 * body.g * body.l1]),
                       "swing2": np.array([0.1 * body.m4 * body.g * body.l4, 0.05]),
                       "swing3": np.array([0.05 * body.m1 * body.g * body.l1])}

    # -- contexts ------------------------------------------------------------------------------
    def stance_context(self, plan, inp: StepInput) -> dict:
        b, g, t = self.body, self.gains, plan.timings
        ctx = dict(zip(STANCE_CONTEXT.names[:16], b.dynamic_parameters()))
        ctx.update(k_w=g.k_w, v_w=g.v_w, k_t=g.k_t, d_t=g.d_t, theta2_ref=g.theta2_ref, k_y=g.k_y, c_y=g.c_y,
                   t_off=t.t_theta1_off, t_step=t.t_step, y_start=inp.y_start,
                   y_end=plan.constraints.hip_y - b.l9, excursion=inp.excursion, locked=0.0,
                   theta1_target=plan.constraints.theta1, w_target=plan.constraints.w)
        return ctx

    def _solve(self, step: int, problem: SubphaseProblem, remember: bool = True) -> SubphaseSolution:
        """Solve; raise ConvergenceError on failure; keep the parameters and, for an optimised
        problem, the node states to start the next step from."""
        solution = self.solver.solve(problem)
        if not solution.success:
            raise ConvergenceError(step, problem.spec.name, solution.residual, solution.message,
                                   iterations=solution.iterations, path_min=solution.path_min, nlp=solution.nlp,
                                   finite=bool(np.all(np.isfinite(solution.states))),
                                   max_iterations=getattr(self.solver, "max_iterations", None))
        if remember:
            self.guesses[problem.spec.name] = np.array([solution.parameters[k] for k in problem.spec.unknown_names])
            if problem.optimize:
                self.previous_states[problem.spec.name] = solution.states
        return solution

    def _guess(self, name: str, nu: int) -> np.ndarray:
        return self.guesses.get(name, np.zeros(nu)).copy()

    def solve_stance(self, plan, inp: StepInput, index: int, at_rest: bool = False) -> SubphaseSolution:
        """The stance of a step; ``at_rest``: the closing stance that ends with theta1d = 0."""
        t = plan.timings
        grid = time_grid(0.0, t.t_step, self.n, self._breakpoints(plan))
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
                                  state_guess=None if at_rest else self.previous_states.get("stance"))
        # the closing stance has one more unknown: it must not seed the next walk's stances
        return self._solve(index, problem, remember=not at_rest)

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
        b, a, t, con = self.body, self.attrs, plan.timings, plan.constraints
        stance = self.solve_stance(plan, inp, index, at_rest)
        sctx = self.stance_context(plan, inp)
        origin = np.array([inp.origin_x, b.l9])

        hips, hip_vels = stance_hips(b, stance.states, origin)   # world hip at every stance node

        def node(time):
            return int(np.argmin(np.abs(stance.t - time)))

        # hind leg: the previous stance's virtual leg (kinematics.virtual_leg) goes on through the
        # double support in the same foot periods, to toe-off, where swing1 starts from it
        t_to, t1, t2 = t.t_ds, t.t_ds + t.t_swing1_end, t.t_ds + t.t_swing2_end
        k_to = node(t_to)
        x_to, hip_to, hip_vel_to = stance.states[k_to], hips[k_to], hip_vels[k_to]
        hind = inp.hind_foot
        t0 = hind.t_step                      # this step's heel strike in the hind leg's stance time
        pitch_ds = hind.pitch_at_other_heel_strike(hips[0])
        pitch_to = toe_off_pitch(hind, hip_to, pitch_ds, math.radians(a.toe_off_foot_pitch), con.theta3)
        hind = hind.with_double_support(hips[0], t_to, pitch_to, start=pitch_ds)
        ds_nodes = np.flatnonzero(stance.t <= t_to + 1e-12)
        # swing1 starts with the thigh's mean rate over the last tenth of the double support: the
        # kinematic leg has a kink at toe-off (the heel rise stops; the leg may just have reached
        # full stretch, where its inverse kinematics is singular), and an infinitesimal difference
        # there handed swing1 thigh rates of up to 19 rad/s at 7 km/h
        window = TOE_OFF_RATE_WINDOW * t_to
        # the double support's nodes, then toe-off and the window's start, in one pass
        m = len(ds_nodes)
        legs = hind.frames(np.r_[t0 + stance.t[ds_nodes], t0 + t_to, t0 + (t_to - window)],
                           np.vstack([hips[ds_nodes], hip_to, hip_to - window * hip_vel_to]))
        ds = {"t": stance.t[ds_nodes], "theta3": legs.theta3[:m], "theta4": legs.theta4[:m], "pitch": legs.pitch[:m]}
        th3_to, th4_to, ankle_to = float(legs.theta3[m]), float(legs.theta4[m]), legs.ankle[m]
        th3d_to = float(legs.theta3[m] - legs.theta3[m + 1]) / window

        # curve P: from the toe-off ankle to the ankle with the toe under the knee at t1
        theta5_to, theta6_to = float(legs.theta5[m]), float(legs.theta6[m])
        theta5_hs, theta6_hs = math.radians(a.theta5_impact), math.radians(a.theta6_impact)
        hip_t1 = hips[node(t1)]
        knee_t1 = hip_t1 - b.l3 * np.array([math.sin(con.theta3), math.cos(con.theta3)])
        # the foot reaches its heel-strike angles by t1, dorsiflexing further if the toe needs it
        ankle_t1, _, theta5_t1 = swing1_end_posture(b, knee_t1, theta5_hs, theta6_hs, a.toe_clearance + 0.01 * b.l1)
        a0, x0 = ankle_to[1], ankle_to[0]
        a_min = ankle_t1[1]
        d_travel = max(ankle_t1[0] - x0, MIN_CURVE_P_TRAVEL * (con.next_ankle_x - x0))
        a_max = max(b.l1 * (a.ankle_peak_height_rel - a.ankle_peak_height_speed_slope * plan.parameters.speed_kmh),
                    max(a0, a_min) + 0.01 * b.l1)
        coeffs = curve_p_coefficients(a0, a_max, a_min, a.swing_peak_position * d_travel, d_travel)
        swing_foot = SwingFoot(t_to, t1, t2, t.t_step, theta5_to, theta6_to, theta5_t1, theta5_hs, theta6_hs)

        ctx = dict(sctx)
        ctx.update({f"stance_{k}": stance.parameters.get(k, 0.0) for k in STANCE_PARAMETERS.names})
        ctx.update(origin_x=origin[0], origin_y=origin[1],
                   l8=b.l8, l9=b.l9, l12=b.l12, l13=b.l13, toe_off_time=t_to, swing_end_time=t.t_step,
                   **{key: getattr(swing_foot, name) for key, name in zip(FOOT_CONTEXT, SCHEDULE_FIELDS)}, k_h=self.gains.k_h, d_h=self.gains.d_h, theta3_target=con.theta3,
                   tau3=a.swing1_torque_time_constant * (t1 - t_to), curve_x0=x0, baumgarte=50.0,
                   swing2_start=t1, tau4=a.swing2_knee_time_constant * (t2 - t1),
                   **{f"P{i}": coeffs[i] for i in range(5)})
        c = SWING_CONTEXT.pack(ctx)
        specs = self.swing_specs
        # The swing re-simulates the stance (swing_law.py), so with plain shooting's lock events it
        # must start in the stance's lock state at toe-off: locked after an early 'leg_too_long'
        # not yet undone by 'leg_vertical'; in the closing step, whose stance has no lock events,
        # with the swing specs' events disarmed. Each later subphase starts in the mode the one
        # before ended in. Multiple shooting has no events: its modes are unlocked and unused.
        mode1 = NO_LOCK_EVENTS if at_rest else lock_mode(stance.events, stance.t[k_to])
        c1 = lock_context(c, mode1)
        s1 = self._solve(index, SubphaseProblem(
            specs["swing1"], np.concatenate([x_to, [th3_to, th4_to, th3d_to]]),
            time_grid(t_to, t1, self.n, [t.t_theta1_off]), c1, self._guess("swing1", 1), self.scales["swing1"],
            mode=mode1))
        x_end1 = s1.final_state
        mode2 = lock_mode(s1.events, mode=mode1)
        c2 = lock_context(c, mode2)
        th4d = float(evaluate(specs["swing1"].rhs, x_end1, t1, s1.parameters["F_theta3_magnitude"], c2)[0][7])
        guess2 = self._guess("swing2", 2)
        guess2[1] = 0.0
        s2 = self._solve(index, SubphaseProblem(
            specs["swing2"], np.concatenate([x_end1, [th4d]]), time_grid(t1, t2, self.n, [t.t_theta1_off]), c2,
            guess2, self.scales["swing2"], fixed=(False, True), path_lower=np.array([a.toe_clearance, -np.inf]),
            recovery_step=np.array([0.0, -0.005]), mode=mode2))
        x_end2 = s2.final_state
        knee = knee_lock_map(b, x_end2[6:10], np.zeros(2), self.lock_rule)   # the knee locks at t2
        th3d_locked = knee[2]
        mode3 = lock_mode(s2.events, mode=mode2)
        s3 = self._solve(index, SubphaseProblem(
            specs["swing3"], np.concatenate([x_end2[:6], [x_end2[6], th3d_locked]]),
            time_grid(t2, t.t_step, self.n, [t.t_theta1_off]), lock_context(c, mode3), self._guess("swing3", 1),
            self.scales["swing3"], mode=mode3))
        nodes = len(s3.t) - 1   # the heel's clearance before it strikes, all nodes in one call
        path = specs["swing3"].path
        heel = evaluate(mapped(path, nodes), s3.states[:-1], s3.t[:-1], s3.parameters["F_theta3_moment"], c)[0]
        notes = lock_rule_notes(stance, b.l1)
        return StepResult(index=index, origin_x=inp.origin_x, hind_ankle_x=inp.hind_ankle_x,
                          t_start=plan.t_start, subphases=[stance, s1, s2, s3],
                          double_support={k: np.array(v) for k, v in ds.items()},
                          curve_p={"a0": a0, "a_max": a_max, "a_min": a_min, "C": a.swing_peak_position * d_travel,
                                   "D": d_travel, "x0": x0, "coefficients": coeffs.tolist(),
                                   "theta5_toe_off": theta5_to, "theta6_toe_off": theta6_to, "theta5_t1": theta5_t1},
                          final_stance_state=stance.final_state, heel_clearance_min=float(heel.min()) if heel.size else 0.0,
                          plan=plan, notes=notes,
                          hip_reference={"y_start": inp.y_start, "y_end": sctx["y_end"], "excursion": inp.excursion},
                          hind_foot=hind, hind_samples=(t0 + stance.t[ds_nodes], hips[ds_nodes]), stance_hips=hips,
                          swing_foot=swing_foot)
