"""The supported envelope (gait/envelope.py, docs/envelope.md): refused before any solving."""
import re

import pytest

from klaw_ocp.cli import main
from klaw_ocp.config import ExperimentConfig
from klaw_ocp.errors import GaitLimitError
from klaw_ocp.gait.envelope import SUPPORTED_HEIGHT_M, SUPPORTED_MASS_KG


def _config(body=None, **walk):
    return {"name": "e", "body": body or {"height": 1.8, "mass": 80}, "walk": {"steps": 4, **walk}}


@pytest.mark.parametrize("body, start", [
    ({"height": SUPPORTED_HEIGHT_M[0] - 0.01, "mass": 80}, "body.height: got 1.39 m, allowed 1.4 to 2.1 m"),
    ({"height": SUPPORTED_HEIGHT_M[1] + 0.01, "mass": 80}, "body.height: got 2.11 m, allowed 1.4 to 2.1 m"),
    ({"height": 1.8, "mass": SUPPORTED_MASS_KG[0] - 1}, "body.mass: got 39 kg, allowed 40 to 150 kg"),
    ({"height": 1.8, "mass": SUPPORTED_MASS_KG[1] + 1}, "body.mass: got 151 kg, allowed 40 to 150 kg"),
])
def test_bodies_outside_the_envelope_are_refused(body, start):
    with pytest.raises(GaitLimitError, match="^" + start.replace(".", r"\.")):
        ExperimentConfig.from_mapping(_config(body, speed=5.0))


@pytest.mark.parametrize("body", [{"height": 1.4, "mass": 40}, {"height": 2.1, "mass": 150}])
def test_the_envelope_edges_are_accepted(body):
    ExperimentConfig.from_mapping(_config(body, speed=5.0))


@pytest.mark.parametrize("schedule, start", [
    ([{"step": 0, "speed": 2.0}, {"step": 1, "speed": 7.0}],
     "walk.schedule: got a speed change of +5 km/h from step 0 to step 1"),
    ([{"step": 0, "speed": 5.0, "step_length": 0.5}, {"step": 1, "speed": 5.0, "step_length": 0.9}],
     "walk.schedule: got a step-length change of +0.4 m from step 0 to step 1"),
])
def test_schedule_jumps_beyond_the_per_step_limit_are_refused(schedule, start):
    with pytest.raises(GaitLimitError, match="^" + start.replace(".", r"\.").replace("+", r"\+")):
        ExperimentConfig.from_mapping(_config(speed=None, schedule=schedule))


def test_a_schedule_spread_over_steps_is_accepted():
    ExperimentConfig.from_mapping(_config(speed=None, steps=6, schedule=[{"step": 0, "speed": 2.0},
                                                                          {"step": 5, "speed": 7.0}]))


def test_cli_refuses_before_solving(tmp_path, capsys):
    cfg = tmp_path / "tall.yaml"
    cfg.write_text("name: tall\nbody: {height: 2.3, mass: 80}\nwalk: {speed: 5, steps: 2}\n")
    assert main(["run", str(cfg), "--out", str(tmp_path / "out"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "body.height: got 2.3 m, allowed 1.4 to 2.1 m" in err
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("walk, start", [
    ({"speed": 2.0, "step_length": 1.0}, "walk.step[0].step_length: got 1 m at 2 km/h and 33.33 steps/min, allowed at most 1.2 x"),
    ({"speed": 3.0, "step_length": 1.1}, "walk.step[0].step_length: got 1.1 m at 3 km/h and 45.45 steps/min, allowed at most 1.6 x"),
])
def test_steps_far_longer_than_natural_are_refused(walk, start):
    with pytest.raises(GaitLimitError, match="^" + re.escape(start)):
        ExperimentConfig.from_mapping(_config(**walk))


@pytest.mark.parametrize("walk", [{"speed": 5.0, "step_length": 1.05}, {"speed": 5.0, "step_length": 0.5},
                                  {"speed": 3.0, "step_length": 0.8}])
def test_the_papers_fig10_steps_are_inside(walk):
    ExperimentConfig.from_mapping(_config(**walk))


def test_cadences_above_the_supported_ceiling_are_refused():
    start = "walk.step[0].step_frequency: got 175 steps/min, allowed at most 170 steps/min"
    with pytest.raises(GaitLimitError, match="^" + re.escape(start)):
        ExperimentConfig.from_mapping(_config(step_length=0.6, step_frequency=175))


def test_a_start_from_rest_ramps_into_the_steps_asked_for():
    plans = ExperimentConfig.from_mapping(_config(speed=8.5, step_length=1.1, steps=6, start_from_rest=True)).plan()
    speeds = [p.parameters.speed_kmh for p in plans]
    assert speeds == pytest.approx([5.0, 6.0, 7.0, 8.0, 8.5, 8.5])
    assert plans[-1].parameters.step_length_m == pytest.approx(1.1)
