"""Multiple shooting's IPOPT repair starts from the step before's repair (docs/solvers.md).

A walk's steps repeat, so a stance whose lock rule needed a repair in one step needs nearly the
same repair in the next: starting IPOPT there, with its multipliers and active nodes, reaches the
same solution in a few iterations instead of a cold repair's 25. Checked against the cold repair
(the same walk with the warm start taken away), and the fall back to it when a warm start fails.
"""
import numpy as np
import pytest

from klaw_ocp import simulate_walk
from klaw_ocp.config import ExperimentConfig
from klaw_ocp.solvers.multiple_shooting import MultipleShootingSolver
from klaw_ocp.walk import walk_spec


def _walk():
    """1 km/h from a periodic start: the lock rule fires in every stance."""
    config = ExperimentConfig.from_mapping({"name": "w", "body": {"height": 1.8, "mass": 80.0},
                                            "walk": {"speed": 1.0, "steps": 3}})
    return simulate_walk(walk_spec(config, "multiple-shooting"))


def _stances(walk):
    return [step.subphase("stance") for step in walk.steps]


def _states(walk):
    return np.concatenate([s.states.ravel() for step in walk.steps for s in step.subphases])


@pytest.fixture(scope="module")
def warm_and_cold():
    warm = _walk()
    patch = pytest.MonkeyPatch()
    patch.setattr(MultipleShootingSolver, "_repair_start", lambda self, pb: None)
    try:
        cold = _walk()
    finally:
        patch.undo()
    return warm, cold


def test_every_stance_is_repaired_in_both(warm_and_cold):
    for walk in warm_and_cold:
        assert walk.status == "ok"
        assert all(s.fallbacks == ["ipopt-repair"] and s.multipliers is not None for s in _stances(walk))


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
    assert all(s.fallbacks == ["ipopt-repair", "cold-repair"] for s in _stances(walk))
    # each step then solves what the cold walk solved, from the same square solution
    assert np.max(np.abs(_states(walk) - _states(cold))) <= 1e-12
