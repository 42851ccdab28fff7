"""Issue #4 acceptance on full walks: the paper's walks at full length and the whole range of
speeds and body heights, in both modes (tests/test_walk.py has the same mechanisms on short walks)."""
from pathlib import Path

import numpy as np
import pytest

from klaw_ocp.results import walk_table
from klaw_ocp.walk import simulate_walk

ROOT = Path(__file__).resolve().parents[1]
METHODS = ["multiple-shooting", "plain-shooting"]


def walk_of(method, height=1.8, steps=4, attributes=None, **walk):
    return simulate_walk({"name": "a", "body": {"height": height, "mass": 80}, "walk": {"steps": steps, **walk},
                          "attributes": attributes or {}}, method=method)


def max_residual(walk):
    return max(s.residual for step in walk.steps for s in step.subphases)


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("speed", [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0])
def test_speed_range(method, speed):
    walk = walk_of(method, speed=speed)
    assert walk.status == "ok" and max_residual(walk) <= 1e-6


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("height", [1.5, 2.0])
def test_body_heights(method, height):
    walk = walk_of(method, height=height, speed=5.0)
    assert walk.status == "ok" and max_residual(walk) <= 1e-6


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("step_length", [0.50, 1.05])
def test_fig10_short_and_long_steps(method, step_length):
    walk = walk_of(method, speed=5.0, step_length=step_length, steps=6)
    assert walk.status == "ok" and max_residual(walk) <= 1e-6


@pytest.mark.parametrize("config", ["start_stop_2kmh.yaml", "start_stop_5kmh.yaml", "accelerate.yaml"])
@pytest.mark.parametrize("method", METHODS)
def test_fig8_and_schedules(method, config):
    walk = simulate_walk(ROOT / "configs" / config, method=method)
    assert walk.status == "ok" and max_residual(walk) <= 1e-6


def test_twelve_second_natural_walk_in_both_modes():
    walks = [simulate_walk(ROOT / "configs" / "natural_walk.yaml", method=m) for m in METHODS]
    tables = [walk_table(w) for w in walks]
    for walk, table in zip(walks, tables):
        assert walk.status == "ok" and max_residual(walk) <= 1e-6
        assert walk.duration >= 12.0
        speed = 3.6 * (table["hip_x"][-1] - table["hip_x"][0]) / (table["t"][-1] - table["t"][0])
        assert speed == pytest.approx(5.0, rel=0.05)
        assert 0.01 < np.ptp(table["hip_y"]) < 0.08
    assert np.max(np.abs(tables[0]["hip_y"] - tables[1]["hip_y"])) < 0.01


def hip_floor_breach(walk):
    """Deepest dip of the hip below the lower heel-strike height of its step (0 when none)."""
    worst = 0.0
    for step in walk.steps:
        x = step.subphase("stance").states
        y = x[:, 0] * np.cos(x[:, 1])
        worst = max(worst, min(y[0], y[-1]) - y.min())
    return worst


def test_twelve_second_walk_with_the_tracking_stance():
    monitored = simulate_walk(ROOT / "configs" / "natural_walk.yaml")
    walk = simulate_walk({**_natural_walk_mapping(), "solver": {"stance": "tracking"}})
    table = walk_table(walk)
    assert walk.status == "ok" and max_residual(walk) <= 1e-6 and walk.duration >= 12.0
    speed = 3.6 * (table["hip_x"][-1] - table["hip_x"][0]) / (table["t"][-1] - table["t"][0])
    assert speed == pytest.approx(5.0, rel=0.05)
    assert hip_floor_breach(walk) < 1e-8 < 1e-3 < hip_floor_breach(monitored)
    assert np.max(np.abs(table["hip_y"] - walk_table(monitored)["hip_y"])) < 0.01


@pytest.mark.parametrize("method", METHODS)
def test_lock_rule_holds_on_a_walk_that_triggers_it(method):
    """A 3 %-of-l1 hip bump at 2 km/h asks for a leg longer than l1 before it is vertical."""
    walk = walk_of(method, speed=2.0, steps=3, attributes={"min_hip_excursion_rel": 0.03})
    assert walk.status == "ok" and max_residual(walk) <= 1e-6
    l1 = walk.spec.body.l1
    for step in walk.steps:
        stance = step.subphase("stance")
        w, theta1 = stance.states[:, 0], stance.states[:, 1]
        rule = (np.cumsum(w <= l1) > 0) & (theta1 < 0)
        assert np.all(w[rule] <= l1 + 1e-7)
        assert step.notes and ("lock events" in step.notes[0] or "held by the path constraint" in step.notes[0])


def _natural_walk_mapping():
    import yaml
    with open(ROOT / "configs" / "natural_walk.yaml") as f:
        return yaml.safe_load(f)
