"""Multiple shooting's IPOPT (a repair, the tracking stance's optimisation) starts from the step
before's IPOPT solution of the same problem (docs/solvers.md).

A periodic walk's steps repeat, so a stance whose lock rule needed a repair in one step needs the
same repair in the next: starting IPOPT there, with its multipliers and active nodes, reaches the
same solution in a few iterations instead of a cold repair's 25. Checked against the cold repair
(the same walk with the warm start taken away); a problem that is not the step before's starts
cold (a start from another problem's repair can reach another local optimum of the stance's fit);
a failed warm start falls back to the cold repair. The tracking stance of a periodic walk,
optimised every step, starts from the step before's optimum: one iteration instead of 13.
"""
import numpy as np
import pytest

from klaw_ocp import simulate_walk
from klaw_ocp.config import ExperimentConfig
from klaw_ocp.solvers.multiple_shooting import REPEAT_TOLERANCE, MultipleShootingSolver
from klaw_ocp.solvers.problem import IpoptPoint
from klaw_ocp.walk import walk_spec


def _walk(speed=1.0, height=1.8, steps=3):
    """By default 1 km/h from a periodic start: the lock rule fires in every stance."""
    config = ExperimentConfig.from_mapping({"name": "w", "body": {"height": height, "mass": 80.0},
                                            "walk": {"speed": speed, "steps": steps}})
    return simulate_walk(walk_spec(config, "multiple-shooting"))


def _cold(*args):
    """The walk with every repair started from its square solution."""
    patch = pytest.MonkeyPatch()
    patch.setattr(MultipleShootingSolver, "_same_problem_start", lambda self, pb: None)
    try:
        return _walk(*args)
    finally:
        patch.undo()


def _stances(walk):
    return [step.subphase("stance") for step in walk.steps]


def _states(walk):
    return np.concatenate([s.states.ravel() for step in walk.steps for s in step.subphases])


@pytest.fixture(scope="module")
def warm_and_cold():
    return _walk(), _cold()


def test_every_stance_is_repaired_in_both(warm_and_cold):
    for walk in warm_and_cold:
        assert walk.status == "ok"
        assert all(s.fallbacks == ["ipopt-repair"] and s.ipopt is not None for s in _stances(walk))


def test_a_repair_from_the_step_before_takes_a_fraction_of_the_iterations(warm_and_cold):
    warm, cold = warm_and_cold
    for w, c in zip(_stances(warm), _stances(cold)):
        assert c.iterations >= 15
        assert w.iterations <= c.iterations / 3


def test_it_reaches_the_cold_repairs_solution(warm_and_cold):
    """The same optimum, to the solver tolerance (1e-9) carried through three steps."""
    warm, cold = warm_and_cold
    assert _states(warm).shape == _states(cold).shape
    assert np.max(np.abs(_states(warm) - _states(cold))) <= 1e-7
    for w, c in zip(_stances(warm), _stances(cold)):
        assert w.path_min >= -1e-7 and c.path_min >= -1e-7
        assert w.parameters.keys() == c.parameters.keys()
        assert max(abs(w.parameters[k] - c.parameters[k]) for k in w.parameters) <= 1e-6


def test_a_failed_warm_start_falls_back_to_the_cold_repair(warm_and_cold, monkeypatch):
    _, cold = warm_and_cold
    original = MultipleShootingSolver._solve_ipopt

    def warm_fails(self, pb, call, start, previous=None):
        result = original(self, pb, call, start, previous)
        if previous is not None:
            result.success = False
        return result
    monkeypatch.setattr(MultipleShootingSolver, "_solve_ipopt", warm_fails)
    walk = _walk()
    assert walk.status == "ok"
    assert all(s.fallbacks == ["ipopt-repair", "ipopt-restart"] for s in _stances(walk))
    # each step then solves what the cold walk solved, from the same square solution
    assert np.max(np.abs(_states(walk) - _states(cold))) <= 1e-12


def test_only_the_same_problem_starts_from_the_step_befores():
    """0.5 km/h, 1.5 m: the periodic start's search solves the first stance from starts 1e-2
    apart; from those repairs the walk's stances reached another local optimum of the hip's fit
    (a cost 8 % higher, peak F_w 617 against 781 N). Started only from the same problem's, the
    walk is the cold one's."""
    warm, cold = _walk(0.5, 1.5, 2), _cold(0.5, 1.5, 2)
    assert np.max(np.abs(_states(warm) - _states(cold))) <= 1e-7
    assert any(s.iterations < 6 for s in _stances(warm))    # and its repeated steps start warm


def test_the_same_problem_has_the_same_path_bounds():
    """A toe clearance changed on the playground changes swing2's bound, not its NLP parameters."""
    from types import SimpleNamespace

    def problem(lower):
        return SimpleNamespace(spec=SimpleNamespace(residuals=None), fixed=(False, True), x0=np.ones(2),
                               grid=np.linspace(0, 1, 3), context=np.zeros(2), guess=np.zeros(2),
                               scale=np.ones(2), path_lower=lower)
    key = MultipleShootingSolver._problem_key
    point = IpoptPoint(np.zeros(1), np.zeros(1), key(problem(np.full((3, 2), [0.015, -np.inf]))))
    assert point.repeated_by(key(problem(np.full((3, 2), [0.015, -np.inf]))), REPEAT_TOLERANCE)
    assert not point.repeated_by(key(problem(np.full((3, 2), [0.02, -np.inf]))), REPEAT_TOLERANCE)
    assert not point.repeated_by(key(problem(None)), REPEAT_TOLERANCE)


def test_a_problem_repeats_to_the_tolerance():
    params = np.array([0.7, -0.14, 0.0, 120.0])
    point = IpoptPoint(np.zeros(3), np.zeros(4), params)
    assert point.repeated_by(params + 0.1 * REPEAT_TOLERANCE, REPEAT_TOLERANCE)
    assert point.repeated_by(params * (1 + 0.5 * REPEAT_TOLERANCE), REPEAT_TOLERANCE)
    assert not point.repeated_by(params + np.array([0, 0, 3 * REPEAT_TOLERANCE, 0]), REPEAT_TOLERANCE)
    assert not point.repeated_by(params[:3], REPEAT_TOLERANCE)


def _tracking_walk():
    config = ExperimentConfig.from_mapping({"name": "t", "body": {"height": 1.8, "mass": 80.0},
                                            "walk": {"speed": 5.0, "steps": 3},
                                            "solver": {"stance": "tracking"}})
    return simulate_walk(walk_spec(config, "multiple-shooting"))


def test_a_tracking_stance_starts_from_the_step_befores_optimum():
    warm = _tracking_walk()
    patch = pytest.MonkeyPatch()
    patch.setattr(MultipleShootingSolver, "_same_problem_start", lambda self, pb: None)
    try:
        cold = _tracking_walk()
    finally:
        patch.undo()
    assert warm.status == cold.status == "ok"
    for w, c in zip(_stances(warm)[1:], _stances(cold)[1:]):
        assert c.iterations >= 8 and w.iterations <= c.iterations / 4, (w.iterations, c.iterations)
    assert np.max(np.abs(_states(warm) - _states(cold))) <= 1e-7
