"""The supported envelope (gait/envelope.py, docs/envelope.md): refused before any solving."""
import re

import numpy as np
import pytest

from klaw_ocp.cli import main
from klaw_ocp.config import ExperimentConfig
from klaw_ocp.errors import GaitLimitError
from klaw_ocp.gait.envelope import SUPPORTED_HEIGHT_M, SUPPORTED_MASS_KG


def _config(body=None, **walk):
    return {"name": "e", "body": body or {"height": 1.8, "mass": 80}, "walk": {"steps": 4, **walk}}


def _accepted(body=None, **walk):
    """The config, its body model and its plan: what an accepted config hands to the walk."""
    config = ExperimentConfig.from_mapping(_config(body, **walk))
    return config, config.body_model(), config.plan()


def _parameters(plans):
    """(speed km/h, step length m, step frequency steps/min) of every planned step."""
    return [(p.parameters.speed_kmh, p.parameters.step_length_m, p.parameters.step_frequency_spm) for p in plans]


def _cadence(speed_kmh, step_length_m):
    """Eq. 1: sf = v / sl, in steps/min (v in m/min)."""
    return speed_kmh * 1000 / 60 / step_length_m


def _natural(height_m, speed_kmh):
    """Eq. 1's natural step length sl = sqrt(0.004 H v), v in m/min."""
    return (0.004 * height_m * speed_kmh * 1000 / 60) ** 0.5


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
    """Accepted as given: the body is the edge itself (not clamped inwards), and every step of
    the walk is planned at the asked-for speed with eq. 1's natural step of that body."""
    assert (body["height"], body["mass"]) in {(SUPPORTED_HEIGHT_M[0], SUPPORTED_MASS_KG[0]),
                                              (SUPPORTED_HEIGHT_M[1], SUPPORTED_MASS_KG[1])}
    config, model, plans = _accepted(body, speed=5.0)
    assert (config.body.height, config.body.mass) == (body["height"], body["mass"])
    assert (model.height, model.mass) == (body["height"], body["mass"])
    assert [p.index for p in plans] == [0, 1, 2, 3]
    natural = _natural(body["height"], 5.0)
    for speed, length, cadence in _parameters(plans):
        assert speed == pytest.approx(5.0, rel=1e-12)
        assert length == pytest.approx(natural, rel=1e-9)
        assert cadence == pytest.approx(_cadence(5.0, natural), rel=1e-9)


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
    """2 -> 7 km/h over 5 steps is 1 km/h per step, exactly the per-step limit: all six steps are
    planned, the schedule's speeds at its steps and a linear ramp between them, each step's
    length moving from the natural step at 2 km/h to the natural step at 7 km/h."""
    config, model, plans = _accepted(speed=None, steps=6, schedule=[{"step": 0, "speed": 2.0},
                                                                    {"step": 5, "speed": 7.0}])
    assert (model.height, model.mass) == (1.8, 80)
    assert [p.index for p in plans] == list(range(6))
    speeds, lengths, cadences = (list(c) for c in zip(*_parameters(plans)))
    assert speeds == pytest.approx([2.0, 3.0, 4.0, 5.0, 6.0, 7.0], rel=1e-12)
    assert lengths[0] == pytest.approx(_natural(1.8, 2.0), rel=1e-9)
    assert lengths[-1] == pytest.approx(_natural(1.8, 7.0), rel=1e-9)
    steps = np.diff(lengths)
    assert np.all(steps > 0) and steps == pytest.approx(np.full(5, steps.mean()), rel=1e-9)
    assert steps.max() <= config.attributes_model().max_step_length_change_rel * model.l1
    assert cadences == pytest.approx([_cadence(v, sl) for v, sl in zip(speeds, lengths)], rel=1e-9)


@pytest.fixture
def solver_calls(monkeypatch):
    """Every entry point into solving (building a solver, preparing or compiling its kernels,
    the step controller, any subphase solve) records its name and raises: the list stays empty
    only if nothing of the solving machinery was touched."""
    import klaw_ocp.solvers as solvers
    import klaw_ocp.step_loop as step_loop
    import klaw_ocp.walk as walk
    from klaw_ocp.control.step import StepController
    from klaw_ocp.solvers.multiple_shooting import MultipleShootingSolver
    from klaw_ocp.solvers.plain_shooting import PlainShootingSolver

    calls = []

    def spy(name):
        def called(*args, **kwargs):
            calls.append(name)
            raise AssertionError(f"{name} was called before the config was refused")
        return called

    for owner, attr in [(walk, "make_solver"), (solvers, "make_solver"), (step_loop, "periodic_start"),
                        (StepController, "__init__"), (StepController, "solve_step"),
                        (StepController, "solve_stance"), (MultipleShootingSolver, "solve"),
                        (MultipleShootingSolver, "prepare"), (PlainShootingSolver, "solve"),
                        (PlainShootingSolver, "prepare")]:
        monkeypatch.setattr(owner, attr, spy(f"{getattr(owner, '__name__', owner)}.{attr}"))
    return calls


def test_cli_refuses_before_solving(tmp_path, capsys, solver_calls):
    cfg = tmp_path / "tall.yaml"
    cfg.write_text("name: tall\nbody: {height: 2.3, mass: 80}\nwalk: {speed: 5, steps: 2}\n")
    assert main(["run", str(cfg), "--out", str(tmp_path / "out"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "body.height: got 2.3 m, allowed 1.4 to 2.1 m" in err
    assert solver_calls == []
    assert not (tmp_path / "out").exists()


def test_the_solver_spies_do_see_a_run(tmp_path, capsys, solver_calls):
    """The spies above are on the path a run really takes: an accepted config reaches them."""
    cfg = tmp_path / "ok.yaml"
    cfg.write_text("name: ok\nbody: {height: 1.8, mass: 80}\nwalk: {speed: 5, steps: 2}\n")
    with pytest.raises(AssertionError, match="before the config was refused"):
        main(["run", str(cfg), "--out", str(tmp_path / "out"), "--quiet", "--no-plots"])
    assert solver_calls and "make_solver" in solver_calls[0]


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
    """Inside means planned as asked: all four steps at the given speed and step length, at the
    cadence eq. 1 gives them (166.67 steps/min for fig. 10's 0.5 m at 5 km/h)."""
    _, model, plans = _accepted(**walk)
    assert (model.height, model.mass) == (1.8, 80)
    assert [p.index for p in plans] == [0, 1, 2, 3]
    cadence = _cadence(walk["speed"], walk["step_length"])
    assert cadence == pytest.approx({0.5: 166.67, 1.05: 79.37, 0.8: 62.5}[walk["step_length"]], abs=5e-3)
    assert np.array(_parameters(plans)) == pytest.approx(np.tile([walk["speed"], walk["step_length"], cadence], (4, 1)),
                                                         rel=1e-9)


def test_cadences_above_the_supported_ceiling_are_refused():
    start = "walk.step[0].step_frequency: got 175 steps/min, allowed at most 170 steps/min"
    with pytest.raises(GaitLimitError, match="^" + re.escape(start)):
        ExperimentConfig.from_mapping(_config(step_length=0.6, step_frequency=175))


def test_a_start_from_rest_ramps_into_the_steps_asked_for():
    plans = ExperimentConfig.from_mapping(_config(speed=8.5, step_length=1.1, steps=6, start_from_rest=True)).plan()
    speeds = [p.parameters.speed_kmh for p in plans]
    assert speeds == pytest.approx([5.0, 6.0, 7.0, 8.0, 8.5, 8.5])
    assert plans[-1].parameters.step_length_m == pytest.approx(1.1)
