"""Convergence everywhere (issue: a solver core that converges on every machine).

- A converged walk does not depend on round-off: a 10x tighter tolerance, or initial guesses
  perturbed by 5 %, change no state of the walk by more than 1e-6.
- A coarse grid over the supported envelope (docs/envelope.md), starts from rest and stops at rest
  included, converges in both modes; so does a dense grid (60 walks per mode, about 20 s).
- Fallbacks are reported where they are needed, per subphase.
"""
import math
import time

import numpy as np
import pytest

from _walk_checks import COARSE
from klaw_ocp import simulate_walk
from klaw_ocp.config import ExperimentConfig
from klaw_ocp.control.step import StepController
from klaw_ocp.results import walk_summary, walk_table
from klaw_ocp.walk import walk_spec

METHODS = ("multiple-shooting", "plain-shooting")
STATE_COLUMNS = ("w", "theta1", "theta2", "theta3", "theta4", "wd", "theta1d", "theta2d", "theta3d", "hip_x", "hip_y")


def _spec(method, tolerance=1e-10, height=1.8, mass=80.0, steps=2, **walk):
    config = ExperimentConfig.from_mapping({"name": "r", "body": {"height": height, "mass": mass},
                                            "walk": {"steps": steps, **walk}})
    spec = walk_spec(config, method)
    spec.tolerance = tolerance
    return spec


def _states(walk):
    table = walk_table(walk)
    return np.column_stack([table[c] for c in STATE_COLUMNS])


@pytest.mark.parametrize("method", METHODS)
def test_a_converged_walk_does_not_depend_on_roundoff(method, monkeypatch):
    """The first swing from rest used to land on a round-off-dependent root (docs/solvers.md)."""
    walk = dict(speed=3.0, start_from_rest=True, end_at_rest=True)
    reference = simulate_walk(_spec(method, **walk))
    tighter = simulate_walk(_spec(method, tolerance=1e-11, **walk))

    original = StepController._guess

    def perturbed(self, name, nu):   # every subphase starts 5 % (and 1e-3 absolute) off
        return original(self, name, nu) * 1.05 + 1e-3
    monkeypatch.setattr(StepController, "_guess", perturbed)
    shaken = simulate_walk(_spec(method, **walk))

    base = _states(reference)
    for other in (tighter, shaken):
        assert len(other.steps) == len(reference.steps) == 3
        assert np.max(np.abs(_states(other) - base)) <= 1e-6


# speed (km/h), height (m), mass (kg), start from rest, end at rest: tests/_walk_checks.py


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("speed, height, mass, rest, stop", COARSE)
def test_the_coarse_envelope_grid_converges(method, speed, height, mass, rest, stop):
    walk = simulate_walk(_spec(method, height=height, mass=mass, speed=speed, start_from_rest=rest,
                               end_at_rest=stop), raise_on_failure=False)
    assert walk.status == "ok", walk.message
    assert len(walk.steps) == 2 + stop
    assert max(s.residual for step in walk.steps for s in step.subphases) <= 1e-6


#: How long the patched IPOPT build takes (s): a lower bound that time.sleep guarantees.
BUILD_DELAY_S = 0.05


@pytest.mark.parametrize("method, fallback", [("multiple-shooting", "ipopt-repair"),
                                              ("plain-shooting", "recovery-loop")])
def test_the_summary_says_which_subphase_needed_which_fallback(method, fallback, monkeypatch):
    """The first swing2 from rest at 8 km/h of a 1.5 m body needs the toe-clearance repair (§4.3's
    recovery loop; the 1.8 m body's no longer does, with the hip ahead of mid-step at heel strike).

    ``build_s`` (docs/solvers.md) is the one-off build time spent in a subphase's solve call and
    kept out of its ``wall_s``: multiple shooting's IPOPT repair builds (or fetches) its NLP there,
    here made to take at least BUILD_DELAY_S. Build and solve times are disjoint parts of the
    walk's wall and compile times, so neither is negative and their sum over the subphases fits
    in them."""
    if method == "multiple-shooting":
        import klaw_ocp.solvers.multiple_shooting as ms
        original = ms.ipopt_solver

        def slow_build(*args):
            time.sleep(BUILD_DELAY_S)
            return original(*args)
        monkeypatch.setattr(ms, "ipopt_solver", slow_build)
    walk = simulate_walk(_spec(method, height=1.5, speed=8.0, start_from_rest=True))
    summary = walk_summary(walk)
    swing2 = summary["steps"][0]["subphases"][2]
    assert swing2["name"] == "swing2" and fallback in swing2["fallbacks"]
    assert swing2["path_min"] >= -1e-7
    entries = [s for step in summary["steps"] for s in step["subphases"]]
    solutions = [s for step in walk.steps for s in step.subphases]
    assert len(entries) == len(solutions) >= 8 and all(isinstance(s["fallbacks"], list) for s in entries)
    for entry, solution in zip(entries, solutions):
        assert isinstance(entry["build_s"], float) and math.isfinite(entry["build_s"])
        assert entry["build_s"] == solution.build_s                 # the summary reports the solver's value
        assert entry["build_s"] >= 0 and entry["wall_s"] >= 0, entry["name"]
    # a library compiled on its first use (IPOPT's, in a fresh kernel cache) is in its
    # subphase's build_s and in the walk's compile_s, which the walk's wall_s leaves out
    assert sum(s["build_s"] + s["wall_s"] for s in entries) <= summary["wall_s"] + summary["compile_s"] + 1e-6
    if method == "multiple-shooting":
        ipopt = [s for s in entries if s["nlp"] == "ipopt"]
        assert ipopt and all(s["build_s"] >= BUILD_DELAY_S for s in ipopt)


# schedules at the per-step change limits (1 km/h, 0.15 l1 per step), both directions
SCHEDULES = [
    [{"step": 0, "speed": 2.0}, {"step": 3, "speed": 5.0}],
    [{"step": 0, "speed": 6.0, "step_length": 0.95}, {"step": 3, "speed": 6.0, "step_length": 0.6}],
]


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("schedule", SCHEDULES, ids=["accelerate", "shorten"])
def test_schedules_at_the_per_step_limits_converge(method, schedule):
    walk = simulate_walk(_spec(method, steps=4, schedule=schedule), raise_on_failure=False)
    assert walk.status == "ok", walk.message


@pytest.mark.parametrize("method", METHODS)
def test_slowing_at_the_per_step_limits_to_the_slowest_walk_and_stopping_at_once_converges(method):
    # 3 -> 0.5 km/h at the limits (0.83 km/h, 0.118 m a step), the closing step right after: plain
    # shooting's closing stance did not reach the stop from the walking stance's push (control/step.py)
    schedule = [{"step": 1, "speed": 3.0, "step_length": 0.6}, {"step": 4, "speed": 0.5, "step_length": 0.245}]
    walk = simulate_walk(_spec(method, steps=5, speed=3.0, step_length=0.6, schedule=schedule, end_at_rest=True),
                         raise_on_failure=False)
    assert walk.status == "ok", walk.message
    assert walk.steps[-1].plan.constraints.closing and walk.steps[-1].final_stance_state[4] == pytest.approx(0.0, abs=1e-6)


@pytest.mark.parametrize("method", METHODS)
def test_a_long_step_at_a_middle_cadence_converges_from_a_cold_start(method):
    # 5 km/h with 1.2 x eq. 1's natural step (0.93 m, 90 steps/min) on the periodic orbit: the first
    # swing1 from the all-zero guess stalled in multiple shooting (solvers/multiple_shooting_starts.py,
    # the scan); plain shooting's sweeps and continuation reach the same root
    walk = simulate_walk(_spec(method, steps=2, speed=5.0, step_length=1.2 * math.sqrt(0.004 * 1.8 * 5000 / 60)),
                         raise_on_failure=False)
    assert walk.status == "ok", walk.message
    swing1 = [s.subphase("swing1").parameters for s in walk.steps]
    assert swing1[1] == pytest.approx(swing1[0], rel=1e-6)        # the periodic orbit's, step after step


@pytest.mark.parametrize("method", METHODS)
def test_a_stop_after_steps_shorter_than_the_natural_one_converges(method):
    # 2.5 km/h with 0.8 x the natural step, then the closing step: its swing1's knee jumped between
    # postures on curve P over 0.4 of its short travel; planned again over 0.5 it converges
    walk = simulate_walk(_spec(method, steps=3, speed=2.5, step_length=0.8 * math.sqrt(0.004 * 1.8 * 2500 / 60),
                               end_at_rest=True), raise_on_failure=False)
    assert walk.status == "ok", walk.message
    closing = walk.steps[-1]
    assert closing.plan.constraints.closing and closing.subphase("swing1").fallbacks[0] == "closing-longer-curve-p"


DENSE = [(v, h, rest) for v in (0.5, 1.5, 2.5, 3.5, 4.5, 5.5, 6.5, 7.5, 8.5, 9.0)
         for h in (1.4, 1.75, 2.1) for rest in (False, True)]


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("speed, height, rest", DENSE)
def test_the_dense_envelope_grid_converges(method, speed, height, rest):
    walk = simulate_walk(_spec(method, height=height, steps=3, speed=speed, start_from_rest=rest,
                               end_at_rest=rest), raise_on_failure=False)
    assert walk.status == "ok", walk.message


@pytest.mark.parametrize("method", METHODS)
def test_a_schedule_across_the_whole_speed_range_converges(method):
    schedule = [{"step": 0, "speed": 1.0}, {"step": 8, "speed": 9.0}, {"step": 16, "speed": 1.0}]
    walk = simulate_walk(_spec(method, steps=17, schedule=schedule), raise_on_failure=False)
    assert walk.status == "ok", walk.message


def test_plain_shooting_takes_the_smooth_root_where_the_latch_leaves_none():
    """A 1.5 m, 60 kg body at 1.2 km/h: its telescope comes down to l1 and grows 72 µm past it
    between two nodes. The paper's latch then holds the leg at l1 until the vertical, the final
    conditions jump across the graze by 0.016 rad, and the evented problem has no root on either
    side. Plain shooting takes the smooth problem's root, which keeps the lock rule at every node,
    as multiple shooting does (solvers/plain_shooting.py, EVENT_FREE_ROOT): the two modes then
    agree to the solver tolerance, and the swings re-simulate that stance without events."""
    from klaw_ocp.control.stance_spec import lock_rule_nodes
    from klaw_ocp.solvers.plain_shooting import EVENT_FREE_ROOT
    walks = {m: simulate_walk(_spec(m, height=1.5, mass=60.0, speed=1.2, steps=3)) for m in METHODS}
    plain, multiple = walks["plain-shooting"], walks["multiple-shooting"]
    l1 = plain.spec.body.l1
    assert plain.status == "ok" and all(EVENT_FREE_ROOT in s.subphase("stance").fallbacks for s in plain.steps)
    for a, b in zip(plain.steps, multiple.steps):
        stance = a.subphase("stance")
        assert stance.events == [] and a.subphase("swing1").events == []
        assert np.all(stance.states[lock_rule_nodes(stance.states, l1), 0] <= l1 + 1e-7)
        for name in ("F_theta1_magnitude", "pa_offset"):
            assert stance.parameters[name] == pytest.approx(b.subphase("stance").parameters[name], rel=1e-6)
        # the swing re-simulates the stance it hangs from (assumption 4), here without events
        assert a.subphase("swing3").states[-1][:6] == pytest.approx(stance.states[-1], abs=4e-5)
