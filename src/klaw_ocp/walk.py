"""The middle level: a state machine that runs step after step (sections 2.2, 2.4, 3, 5).

For each step (principle 1: high level before the step, low level during it):

1. stance of the leading leg, simulated for t_step (not t_stance: "the continuing stance phase of
   the hind leg is completed kinematically");
2. double support of the hind leg, kinematic, until toe-off at t_ds;
3. swing1 / swing2 / swing3 of the hind leg on the hip motion of this stance (assumption 4);
4. heel strike: the swing leg becomes the stance leg, and the heel-strike map gives the next
   stance's initial state (:func:`klaw_ocp.dynamics.heel_strike_map`).

First step: a walk that starts "walking" begins on the periodic orbit of its first step: the
initial hip speed is found (secant method) so that the hip leaves the step as fast as it entered
it, and from there the whole stance state (theta2, the hip's velocity, the trunk's rate) is
iterated through the step and its heel-strike map until it repeats
(:func:`klaw_ocp.control.periodic_start.periodic_start`). A walk that starts from rest
(``start_from_rest``) begins standing on both feet side by side, at rest; its first stance starts
at theta1 = 0 and the hind foot swings from beside the stance foot. See docs/walk.md for the last
step and for what changes from step to step.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field, replace

import numpy as np

from . import choices
from .body import Body
from .config import DEFAULT_FPS
from .console import CasadiMessages, DeferredInterrupt
from .control.gains import control_gains
from .control.step import StepController, StepResult
from .errors import ConvergenceError, Interrupted
from .kinematics.virtual_leg import StanceFoot, VirtualLegFrames
from .solvers import make_solver
from .kernels import compile_seconds
from .solvers.thread_safety import solving
from .step_loop import StepLoop
from .stop_signals import stopped_words


@dataclass
class WalkSpec:
    """Everything the walk needs, independent of any file format."""
    name: str
    body: Body
    attributes: object
    plans: list
    method: str = choices.DEFAULT_METHOD
    intervals: int = choices.DEFAULT_INTERVALS
    tolerance: float = choices.DEFAULT_TOLERANCE
    max_iterations: int = choices.DEFAULT_MAX_ITERATIONS
    nlp: str = choices.DEFAULT_NLP
    start_from_rest: bool = False
    end_at_rest: bool = False
    lock_rule: str = choices.DEFAULT_LOCK_RULE
    stance: str = choices.DEFAULT_STANCE
    #: frames per second of the body's files (output.fps): the walk carries it to every writer
    fps: float = DEFAULT_FPS


@dataclass
class Walk:
    """A simulated walk: the solved steps in order, and how the run ended (``status``: "ok",
    "failed" or "interrupted")."""
    spec: WalkSpec
    steps: list[StepResult] = field(default_factory=list)
    status: str = "ok"
    message: str = ""
    #: the walk's own wall time: compiling the solver kernels (``compile_s``) is left out, as the
    #: time in ``on_step`` is, so that ``duration / wall_s`` is the walk's real-time factor
    wall_s: float = 0.0
    #: seconds spent compiling the solver kernels during the walk: the first walk on a machine
    #: (or after an upgrade) compiles them once (kernels.py); 0.0 when they were cached
    compile_s: float = 0.0
    initial_state: np.ndarray | None = None
    #: why a failed walk stopped (:meth:`klaw_ocp.errors.ConvergenceError.as_dict`), else None
    failure: dict | None = None
    #: CasADi's warnings during the walk, each once, without their date (klaw_ocp.console)
    solver_messages: list = field(default_factory=list)

    @property
    def duration(self) -> float:
        return sum(s.plan.timings.t_step for s in self.steps)

    def stance_foot(self, k: int) -> StanceFoot:
        """The virtual leg of step ``k``'s stance leg (§4.2) as far as the walk fixed it: the rules
        its own stance fixed (``steps[k].stance_foot``), completed through their double support to
        toe-off by the next step (its ``hind_foot``) where the walk has one."""
        return self.steps[k + 1].hind_foot if k + 1 < len(self.steps) else self.steps[k].stance_foot

    def stance_leg_frames(self, k: int) -> VirtualLegFrames | None:
        """Step ``k``'s stance leg as a human leg from its heel strike to its toe-off, at the
        stance's nodes and the next step's double support's; None for the walk's last step, whose
        stance leg no double support completed."""
        if k + 1 >= len(self.steps):
            return None
        step, following = self.steps[k], self.steps[k + 1]
        t_after, hips_after = following.hind_samples
        t = np.concatenate([step.subphase("stance").t, t_after[1:]])
        return following.hind_foot.frames(t, np.vstack([step.stance_hips, hips_after[1:]]))


def simulate_walk(spec, method: str | None = None, progress: bool = False, raise_on_failure: bool = True,
                  on_step=None) -> Walk:
    """Run the walk step by step. ``spec`` is a :class:`WalkSpec`, an experiment configuration,
    a mapping in the configuration's shape, or the path of a YAML configuration file; ``method``
    overrides the configured solver. On a subphase that does not converge, raise
    :class:`ConvergenceError` (naming step, subphase, residual) whose ``partial`` is the
    :class:`Walk` of the steps completed before it (its ``failure`` the error's
    :meth:`~klaw_ocp.errors.ConvergenceError.as_dict`); with ``raise_on_failure=False`` return
    that walk with ``status == "failed"`` instead. Ctrl-C raises
    :class:`~klaw_ocp.errors.Interrupted` (a KeyboardInterrupt) whose ``partial`` is the walk
    of the completed steps, ``status == "interrupted"``.

    Ctrl-C waits for the end of the step being solved, and CasADi's warnings go to
    ``walk.solver_messages`` rather than to the terminal (:mod:`klaw_ocp.console`).

    ``on_step(walk)``, if given, is called after each step is complete (``walk.steps[-1]`` the
    step just solved, ``walk.wall_s`` the simulation time so far): ``klaw-ocp run`` writes the
    step's rows there. The time spent in it is not counted in ``wall_s``, nor is the time spent
    compiling the solver kernels, which is ``walk.compile_s``
    (:func:`klaw_ocp.kernels.compile_notices` tells when compiling starts).

    With ``progress``, a tqdm bar on stderr advances as each step completes.

    Every argument is checked before anything is built or solved: a bad one raises
    :class:`~klaw_ocp.errors.ConfigError` (one line naming it and what is allowed;
    :class:`~klaw_ocp.errors.GaitLimitError`, a kind of ConfigError, for a walk outside the
    supported envelope).

    Threads: it may be called from several threads at once, and each walk is the walk it would
    be alone, to the last bit (docs/limits.md, "Threads"). Walks in several threads run at the
    same time (the compiled kernels' C code in parallel, the Python in turns under the GIL;
    CasADi's expressions are built and IPOPT solves one at a time for the process); each keeps
    the CasADi warnings of its own thread; ``compile_s`` counts any compiling the walk waited
    for, another thread's included. Ctrl-C is deferred to the end of the step only in the main
    thread."""
    spec = _checked_spec(spec, method, progress, raise_on_failure, on_step)
    with solving():     # one walk at a time only with a CasADi that is not thread-safe
        return _simulate(spec, progress, raise_on_failure, on_step)


def _simulate(spec: WalkSpec, progress: bool, raise_on_failure: bool, on_step) -> Walk:
    """:func:`simulate_walk` of a checked spec (its clock starts here: a turn waited for is not
    the walk's time)."""
    wall0, compile0 = time.perf_counter(), compile_seconds()
    walk = Walk(spec)
    outside = 0.0       # seconds spent in on_step, kept out of wall_s

    def timed() -> None:
        walk.compile_s = compile_seconds() - compile0
        walk.wall_s = time.perf_counter() - wall0 - outside - walk.compile_s

    bar = None
    interrupts, messages = DeferredInterrupt(), CasadiMessages()
    try:
        with interrupts, messages:
            # built under the deferred Ctrl-C: CasADi's wrappers drop a KeyboardInterrupt raised
            # while its expressions are built (the interrupt was lost, the walk went on)
            solver = make_solver(spec.method, intervals=spec.intervals, tolerance=spec.tolerance,
                                 max_iterations=spec.max_iterations, nlp=spec.nlp)
            gains = control_gains(spec.body, spec.attributes)
            controller = StepController(spec.body, spec.attributes, gains, solver, spec.lock_rule, spec.stance)
            interrupts.check()
            plans = list(spec.plans) + ([closing_plan(spec)] if spec.end_at_rest else [])
            if progress:
                # a bar advanced by hand as steps complete (iterating a list of the steps would
                # fill it before the first solve); made inside ``messages`` so that a line written
                # with tqdm.write (the compile notice) clears and redraws it
                from tqdm import tqdm
                bar = tqdm(total=len(plans), desc=f"{spec.name} ({spec.method})", unit="step")
            plan_of = lambda k: (plans[k], k == len(spec.plans)) if k < len(plans) else None  # noqa: E731
            loop = StepLoop(spec, controller, plan_of)
            walk.initial_state = loop.initial_state.copy()
            while True:
                interrupts.check()          # Ctrl-C stops the walk between steps (klaw_ocp.console)
                result = loop.solve_next()
                if result is None:
                    break
                # the step is complete: only now does the walk hold it (an interrupt inside the
                # solve leaves the walk as it was after the previous step)
                walk.steps.append(result)
                if bar is not None:
                    bar.update(1)
                if on_step is not None:
                    t0 = time.perf_counter()
                    timed()
                    on_step(walk)
                    outside += time.perf_counter() - t0
            interrupts.check()
    except ConvergenceError as err:
        if interrupts.pressed:      # a second Ctrl-C inside IPOPT fails the solve: it is an interrupt
            walk.status, walk.message = "interrupted", stopped_words()
            raise Interrupted(walk) from None
        walk.status, walk.message, walk.failure = "failed", str(err), err.as_dict()
        err.partial = walk
        if raise_on_failure:
            raise
        return walk
    except KeyboardInterrupt as err:
        walk.status, walk.message = "interrupted", stopped_words()
        raise Interrupted(walk) from err
    finally:
        # however the walk ends (complete, failed, interrupted): before the caller sees it
        timed()
        walk.solver_messages = list(messages.messages)
        if bar is not None:
            bar.close()      # the bar's line ends before any message that follows
    return walk


_SPEC_ALLOWED = ("a WalkSpec, an ExperimentConfig, a mapping in the config's shape (name, body, walk, ...) "
                 "or the path of a YAML config file (a str or os.PathLike)")


def _checked_spec(spec, method, progress, raise_on_failure, on_step=None) -> WalkSpec:
    """:func:`simulate_walk`'s arguments checked before anything is built or solved: the walk as
    a :class:`WalkSpec` within the config's bounds, or one ConfigError line naming the argument."""
    import os

    from .config import (INTERVALS_RANGE, ITERATIONS_RANGE, LOCK_RULES, MAX_FPS, NLP_CHOICES, SOLVER_METHODS,
                         STANCES, TOLERANCE_RANGE, ExperimentConfig, check_stance_method,
                         check_walk_size, load_config)
    from .errors import ConfigError, out_of_range
    from .gait import LocomotionAttributes, StepPlan
    from .gait.plan import MAX_STEPS

    if method is not None and (not isinstance(method, str) or method not in SOLVER_METHODS):
        raise ConfigError(out_of_range("method", method, f"None or one of {', '.join(SOLVER_METHODS)}"))
    for name, value in (("progress", progress), ("raise_on_failure", raise_on_failure)):
        if not isinstance(value, (bool, np.bool_)):
            raise ConfigError(out_of_range(name, value, "True or False"))
    if on_step is not None and not callable(on_step):   # else a TypeError after the first step
        raise ConfigError(out_of_range("on_step", on_step, "None or a callable taking the walk"))
    if isinstance(spec, WalkSpec):
        spec = spec if method is None else replace(spec, method=method)
    elif isinstance(spec, ExperimentConfig):
        spec = walk_spec(spec, method)
    elif isinstance(spec, dict):
        spec = walk_spec(ExperimentConfig.from_mapping(spec), method)
    elif isinstance(spec, (str, os.PathLike)):
        spec = walk_spec(load_config(spec), method)
    else:
        raise ConfigError(out_of_range("spec", spec, _SPEC_ALLOWED))

    def need(field: str, ok: bool, value, allowed: str) -> None:
        if not ok:
            raise ConfigError(out_of_range(f"spec.{field}", value, allowed))

    def integer(value) -> bool:
        return isinstance(value, (int, np.integer)) and not isinstance(value, (bool, np.bool_))

    def number(value) -> bool:
        return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, (bool, np.bool_))

    need("name", isinstance(spec.name, str), spec.name, "a str")
    need("body", isinstance(spec.body, Body), spec.body, "a klaw_ocp.Body")
    need("attributes", isinstance(spec.attributes, LocomotionAttributes), spec.attributes,
         "a klaw_ocp.gait.LocomotionAttributes")
    need("plans", isinstance(spec.plans, (list, tuple)) and 1 <= len(spec.plans) <= MAX_STEPS
         and all(isinstance(p, StepPlan) for p in spec.plans), spec.plans,
         f"a list of 1 to {MAX_STEPS} klaw_ocp.gait.StepPlan (klaw_ocp.gait.plan_steps)")
    def choice(field: str, choices: tuple) -> None:
        value = getattr(spec, field)
        need(field, isinstance(value, str) and value in choices, value, f"one of {', '.join(choices)}")

    choice("method", SOLVER_METHODS)
    lo, hi = INTERVALS_RANGE
    need("intervals", integer(spec.intervals) and lo <= spec.intervals <= hi, spec.intervals,
         f"an integer from {lo} to {hi}")
    lo, hi = TOLERANCE_RANGE
    need("tolerance", number(spec.tolerance) and lo <= spec.tolerance <= hi, spec.tolerance,
         f"a number from {lo:g} to {hi:g}")
    lo, hi = ITERATIONS_RANGE
    need("max_iterations", integer(spec.max_iterations) and lo <= spec.max_iterations <= hi,
         spec.max_iterations, f"an integer from {lo} to {hi}")
    choice("nlp", NLP_CHOICES)
    choice("stance", STANCES)
    choice("lock_rule", LOCK_RULES)
    need("fps", number(spec.fps) and 0 < spec.fps <= MAX_FPS, spec.fps, f"a number > 0 and <= {MAX_FPS:g}")
    for flag in ("start_from_rest", "end_at_rest"):
        need(flag, isinstance(getattr(spec, flag), (bool, np.bool_)), getattr(spec, flag), "True or False")
    check_walk_size(len(spec.plans), int(spec.intervals))
    check_stance_method(spec.stance, spec.method)
    return spec


def closing_plan(spec: WalkSpec):
    """The step that ends a walk at rest (:func:`klaw_ocp.gait.closing_step`); its stance ends
    with theta1d = 0 (a braking level of F_theta1 after 0.4 t_step)."""
    from .gait import closing_step
    return closing_step(spec.body, spec.attributes, spec.plans[-1])


def walk_spec(config, method: str | None = None) -> WalkSpec:
    """A :class:`WalkSpec` from a validated experiment configuration (``klaw_ocp.config``)."""
    solver = config.solver
    return WalkSpec(name=config.name, body=config.body_model(), attributes=config.attributes_model(),
                    plans=config.plan(), method=method or solver.method, intervals=solver.intervals,
                    tolerance=solver.tolerance, max_iterations=solver.max_iterations, nlp=solver.nlp,
                    start_from_rest=config.walk.start_from_rest, end_at_rest=config.walk.end_at_rest,
                    stance=solver.stance, lock_rule=solver.lock_rule, fps=config.output.fps)
