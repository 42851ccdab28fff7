"""The experiment schema: YAML loading, strict validation and one-line errors."""
from pathlib import Path

import pytest

from klaw_ocp.body import Body
from klaw_ocp.config import ExperimentConfig, load_config
from klaw_ocp.errors import ConfigError, GaitLimitError
from klaw_ocp.gait import LocomotionAttributes

ROOT = Path(__file__).resolve().parents[1]
CONFIGS = sorted((ROOT / "configs").glob("*.yaml"))

ISSUE_EXAMPLE = """
name: natural_walk            # a plain slug, also the default output folder name
body: {height: 1.8, mass: 80} # m, kg
walk:
  speed: 5.0
  step_length: null
  step_frequency: null
  duration: 12
  schedule:
    - {step: 0, speed: 2.0}
    - {step: 4, speed: 5.0}
attributes: {pelvic_list: 5.0}
solver: {method: multiple-shooting}
output: {animation: true}
"""


def _base(**changes):
    data = {"name": "t", "body": {"height": 1.8, "mass": 80}, "walk": {"speed": 5.0, "steps": 4}}
    data.update(changes)
    return data


def test_the_issue_example_loads(tmp_path):
    f = tmp_path / "x.yaml"
    f.write_text(ISSUE_EXAMPLE, encoding="utf-8")
    c = load_config(f)
    assert c.output.animation is True and c.solver.method == "multiple-shooting"
    plans = c.plan()
    assert [p.parameters.speed_kmh for p in plans[:5]] == pytest.approx([2.0, 2.75, 3.5, 4.25, 5.0])
    assert c.attributes_model().pelvic_list == 5.0


def test_natural_walk_is_fig10_top():
    c = load_config(ROOT / "configs" / "natural_walk.yaml")
    assert (c.name, c.body.height, c.body.mass, c.walk.speed, c.walk.duration) == (
        "natural_walk", 1.8, 80, 5.0, 12)
    assert c.body_model() == Body(1.8, 80)
    assert c.attributes_model() == LocomotionAttributes.defaults()
    plans = c.plan()
    assert len(plans) == 22
    assert plans[0].parameters.step_frequency_spm == pytest.approx(107.58, abs=5e-3)
    assert c.output_dir() == Path("results") / "natural_walk"


@pytest.mark.parametrize("path", CONFIGS, ids=[p.stem for p in CONFIGS])
def test_every_shipped_config_loads_and_is_named_after_its_file(path):
    c = load_config(path)
    assert c.name == path.stem
    assert len(c.plan()) >= 1


@pytest.mark.parametrize("path", CONFIGS, ids=[p.stem for p in CONFIGS])
def test_every_shipped_config_draws_walk_gif(path):
    """Issue #23: output.animation is on in the shipped configs (off by default, for other files)."""
    assert load_config(path).output.animation is True
    assert ExperimentConfig.from_mapping(_base()).output.animation is False


@pytest.mark.parametrize("name, steps, first_sf", [
    ("short_steps", 34, 166.67), ("long_steps", 16, 79.37), ("start_stop_2kmh", 8, 68.04),
    ("start_stop_5kmh", 6, 107.58),
])
def test_shipped_config_numbers(name, steps, first_sf):
    c = load_config(ROOT / "configs" / f"{name}.yaml")
    plans = c.plan()
    assert len(plans) == steps
    assert plans[0].parameters.step_frequency_spm == pytest.approx(first_sf, abs=5e-3)
    if name.startswith("start_stop"):
        assert c.walk.start_from_rest and c.walk.end_at_rest


def test_accelerate_goes_2_5_2():
    speeds = [p.parameters.speed_kmh for p in load_config(ROOT / "configs" / "accelerate.yaml").plan()]
    assert speeds[0] == 2.0 and max(speeds) == pytest.approx(5.0) and speeds[-1] == pytest.approx(2.0)
    assert speeds.index(max(speeds)) == 4


def test_defaults_and_output_dir():
    c = ExperimentConfig.from_mapping(_base(output={"dir": "/tmp/elsewhere"}))
    assert c.solver.model_dump() == {"method": "multiple-shooting", "intervals": 20, "tolerance": 1e-9,
                                     "max_iterations": 50, "nlp": "auto", "stance": "monitored",
                                     "lock_rule": "momentum"}
    assert c.output_dir() == Path("/tmp/elsewhere")
    assert c.output.fps == 30.0 and c.output.plots is True
    assert c.walk.start_from_rest is False and c.walk.end_at_rest is False


BAD = [
    (_base(extra=1), "extra: got an unknown key (value 1), allowed only the keys name, body, walk"),
    (_base(body={"height": 0, "mass": 80}), "body.height: got 0.0, allowed 0.8 to 2.5 m"),
    (_base(body={"height": "1.8", "mass": 80}), "body.height: got '1.8', allowed a number"),
    (_base(body={"height": 1.8, "mass": 80, "age": 30}), "body.age: got an unknown key (value 30), allowed only the keys height, mass"),
    (_base(walk={"speed": 5.0, "steps": 4, "duration": 2}), "walk: got duration 2 and steps 4, allowed exactly one of duration (s) or steps"),
    (_base(walk={"speed": 5.0}), "walk: got neither duration nor steps, allowed exactly one"),
    (_base(walk={"speed": -1.0, "steps": 4}), "walk.speed: got -1.0, allowed a number > 0"),
    (_base(walk={"speed": 0, "steps": 4}), "walk.speed: got 0, allowed a number > 0"),
    (_base(walk={"speed": float("nan"), "steps": 4}), "walk.speed: got nan, allowed a finite number"),
    (_base(walk={"speed": float("inf"), "steps": 4}), "walk.speed: got inf, allowed a finite number"),
    (_base(walk={"speed": 12.0, "steps": 4}), "walk.speed: got 12 km/h, allowed 0.5 to 9 km/h"),
    (_base(walk={"step_frequency": 190.0, "step_length": 0.5, "steps": 4}), "walk.step_frequency: got 190 steps/min, allowed 30 to 182"),
    (_base(walk={"steps": 4}), "walk: got 'no speed, step_length or step_frequency'"),
    (_base(walk={"speed": 5.0, "steps": 0}), "walk.steps: got 0, allowed a number >= 1"),
    (_base(walk={"speed": 5.0, "steps": 2.0}), "walk.steps: got 2.0, allowed an integer"),
    (_base(walk={"speed": 5.0, "steps": 4, "schedule": [{"step": 1}]}), "walk.schedule[0]: got {step: 1} with no parameter"),
    (_base(walk={"speed": 5.0, "steps": 4, "schedule": [{"step": 1, "sped": 3}]}), "walk.schedule[0].sped: got an unknown key"),
    (_base(walk={"speed": 5.0, "steps": 4, "schedule": [{"step": 9, "speed": 3}]}), "walk.schedule[0].step: got 9, allowed 0 to 3"),
    (_base(walk={"speed": 5.0, "steps": 4, "schedule": [{"step": 1, "speed": 30}]}), "walk.schedule[0].speed: got 30 km/h"),
    (_base(walk={"speed": 5.0, "steps": 4, "start_from_rest": "yes"}), "walk.start_from_rest: got 'yes', allowed true or false"),
    (_base(attributes={"pelvic_lst": 3}), "attributes.pelvic_lst: got 'pelvic_lst', allowed a registered attribute name, close matches: pelvic_list"),
    (_base(attributes={"pelvic_list": 30}), "attributes.pelvic_list: got 30.0, allowed 0 to 20 deg"),
    (_base(attributes={"pelvic_list": "x"}), "attributes.pelvic_list: got 'x', allowed a number"),
    (_base(solver={"method": "euler"}), "solver.method: got 'euler', allowed one of 'multiple-shooting' or 'plain-shooting'"),
    (_base(solver={"intervals": 501}), "solver.intervals: got 501, allowed a number <= 500"),
    (_base(solver={"nlp": "snopt"}), "solver.nlp: got 'snopt', allowed one of 'auto', 'rootfinder' or 'ipopt'"),
    (_base(solver={"lock_rule": "elastic"}), "solver.lock_rule: got 'elastic', allowed one of 'momentum' or 'zero'"),
    (_base(name="Natural Walk"), "name: got 'Natural Walk', allowed a slug of lowercase letters, digits, '_' and '-'"),
    (_base(output={"animation": 1}), "output.animation: got 1, allowed true or false"),
    (_base(output={"fps": 0}), "output.fps: got 0, allowed a number > 0"),
    (_base(output={"fps": -1}), "output.fps: got -1, allowed a number > 0"),
    (_base(output={"fps": "abc"}), "output.fps: got 'abc', allowed a number"),
    (_base(output={"fps": 1001}), "output.fps: got 1001, allowed a number <= 1000"),
    ({"name": "t", "walk": {"speed": 5.0, "steps": 4}}, "body: got nothing, allowed a required value"),
    ([1, 2], "config: got [1, 2], allowed a mapping with name, body, walk"),
]


#: the cases of BAD that are locomotion limits (section 3), not malformed input
GAIT_LIMITS = {"walk.speed: got 12 km/h, allowed 0.5 to 9 km/h",
               "walk.step_frequency: got 190 steps/min, allowed 30 to 182",
               "walk.schedule[0].speed: got 30 km/h"}
assert GAIT_LIMITS <= {start for _, start in BAD}


@pytest.mark.parametrize("data, start", BAD, ids=[b[1].split(":")[0] + f"-{i}" for i, b in enumerate(BAD)])
def test_bad_configs_give_one_line_naming_the_field(data, start):
    # limits of the supported envelope (a locomotion parameter outside its limit attribute, the
    # message in that parameter's unit) stay GaitLimitError; everything else is a ConfigError
    expected = GaitLimitError if start in GAIT_LIMITS else ConfigError
    with pytest.raises((ConfigError, GaitLimitError)) as err:
        ExperimentConfig.from_mapping(data)
    assert type(err.value) is expected, (type(err.value).__name__, start)
    msg = str(err.value)
    assert msg.startswith(start), msg
    assert "\n" not in msg and ": got " in msg and "allowed" in msg


def test_missing_file():
    with pytest.raises(ConfigError, match=r"^config: got '.*nope.yaml', allowed an existing YAML file"):
        load_config("nope.yaml")


def test_yaml_syntax_error_names_the_file_and_line(tmp_path):
    f = tmp_path / "broken.yaml"
    f.write_text("name: x\nbody: {height: 1.8, mass: 80\nwalk: {}\n", encoding="utf-8")
    with pytest.raises(ConfigError) as err:
        load_config(f)
    assert str(err.value).startswith(f"{f}: got invalid YAML at line ")
    assert "\n" not in str(err.value)


@pytest.mark.parametrize("text, start", [("", "config: got '"), ("- 1\n- 2\n", "config: got [1, 2]")])
def test_empty_or_non_mapping_file(tmp_path, text, start):
    f = tmp_path / "x.yaml"
    f.write_text(text, encoding="utf-8")
    with pytest.raises(ConfigError, match="^" + start.replace("[", r"\[").replace("]", r"\]")):
        load_config(f)


def test_directory_is_not_a_config(tmp_path):
    with pytest.raises(ConfigError, match=r"^config: got .*allowed a readable"):
        load_config(tmp_path)


@pytest.mark.parametrize("sets, steps, duration", [
    (["walk.steps=300"], 300, None),
    (["walk.steps=300", "walk.duration=20"], None, 20),
    (["walk.duration=20", "walk.steps=7"], 7, None),
    (["walk.speed=4"], None, 12),
])
def test_a_set_of_one_alternative_replaces_the_other(sets, steps, duration):
    """natural_walk.yaml gives a duration: ``--set walk.steps=300`` walks 300 steps (the last
    alternative set wins), where it used to be refused as "both steps and duration"."""
    config = load_config(ROOT / "configs" / "natural_walk.yaml", sets)
    assert (config.walk.steps, config.walk.duration) == (steps, duration)


def test_a_file_giving_both_alternatives_is_still_refused(tmp_path):
    path = tmp_path / "c.yaml"
    path.write_text("name: t\nbody: {height: 1.8, mass: 80}\nwalk: {speed: 5, steps: 4, duration: 3}\n")
    with pytest.raises(ConfigError, match=r"^walk: got duration 3 and steps 4, allowed exactly one of"):
        load_config(path)
    assert load_config(path, ["walk.duration=null"]).walk.steps == 4


def test_a_vary_of_one_alternative_replaces_the_other():
    from klaw_ocp.sweep import expand
    _, tasks = expand(ROOT / "configs" / "natural_walk.yaml", {"walk.steps": [3, 5]})
    assert [t["mapping"]["walk"].get("duration") for t in tasks] == [None, None]
    assert [t["mapping"]["walk"]["steps"] for t in tasks] == [3, 5]
