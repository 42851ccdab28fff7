"""The locomotion-attribute registry and its immutable, validated value set."""
import math
import pickle
import re
from pathlib import Path

import pytest

from klaw_ocp.errors import ConfigError
from klaw_ocp.gait import ATTRIBUTES, LocomotionAttributes

DOCS = Path(__file__).resolve().parents[1] / "docs" / "attributes.md"

EXPECTED_DEFAULTS = {
    "sf_max": 182, "sf_min": 30, "speed_min": 0.5, "speed_max": 9.0, "step_length_max_rel": 1.4,
    "step_length_min_rel": 0.2, "max_speed_change_per_step": 1.0, "start_speed_max": 5.0, "max_step_length_change_rel": 0.15,
    "parameter_consistency_tolerance": 0.01,
    "swing1_end_fraction": 0.5, "swing2_end_fraction": 0.85, "theta1_torque_off_fraction": 0.4,
    "theta5_impact": 90, "heel_strike_hip_lead": 0.045, "theta6_impact": 0, "foot_flat_fraction": 0.08, "heel_off_theta5": 105, "meta_off_theta6": 30,
    "terminal_stance_knee_flexion": 5, "knee_flexion_lead": 0.24, "toe_off_knee_flexion": 40, "toe_clearance": 0.015, "swing_peak_position": 0.3,
    "ankle_peak_height_rel": 0.20, "ankle_peak_height_speed_slope": 0.01,
    "swing1_torque_time_constant": 0.6, "swing2_knee_time_constant": 4.0, "knee_rate_at_t1": 0.95,
    "terminal_swing_retraction": 0, "hip_hold_frequency": 1.2, "hip_hold_damping_ratio": 1.0, "leg_frequency": 3.0,
    "leg_damping_ratio": 0.3, "trunk_frequency": 1.5, "trunk_damping_ratio": 0.8,
    "trunk_lean": 0, "hip_height_gain": 10.0, "hip_height_rate_gain": 0.05,
    "midstance_leg_shortening": 0.004, "hip_rise_fraction": 0.5, "hip_fall_fraction": 0.45, "hip_fall_power": 1.5,
    "min_hip_excursion_rel": 0.01, "pelvic_rotation": 4,
    "pelvic_list": 5, "pelvic_lateral_shift": 0.02, "foot_lateral_distance": 0.08,
    "arm_swing_amplitude": 15,
}


def test_registry_holds_the_specified_defaults():
    assert set(ATTRIBUTES) == set(EXPECTED_DEFAULTS)
    assert len(ATTRIBUTES) >= 20
    attrs = LocomotionAttributes.defaults()
    for name, default in EXPECTED_DEFAULTS.items():
        assert getattr(attrs, name) == pytest.approx(default), name


@pytest.mark.parametrize("name", list(ATTRIBUTES))
def test_every_spec_is_documented_and_its_default_sits_inside_the_range(name):
    spec = ATTRIBUTES[name]
    assert spec.name == name and spec.unit and spec.paper
    assert spec.low < spec.high
    assert spec.low <= spec.default <= spec.high
    # margin: the default is not pinned to an end of the range unless that end is a natural 0
    assert spec.default < spec.high
    assert spec.default > spec.low or spec.low == 0.0


def test_angles_are_degrees_and_rad_converts():
    attrs = LocomotionAttributes.defaults()
    assert ATTRIBUTES["theta5_impact"].unit == "deg"
    assert attrs.rad("theta5_impact") == pytest.approx(math.pi / 2)
    assert attrs.rad("pelvic_list") == pytest.approx(math.radians(5))
    with pytest.raises(ConfigError, match="toe_clearance"):
        attrs.rad("toe_clearance")


def test_overrides_return_a_new_object_and_keep_the_old():
    base = LocomotionAttributes.defaults()
    changed = base.with_overrides({"pelvic_list": 8, "toe_clearance": 0.02})
    assert changed.pelvic_list == 8.0 and changed.toe_clearance == 0.02
    assert base.pelvic_list == 5.0
    assert changed.overrides() == {"pelvic_list": 8.0, "toe_clearance": 0.02}
    assert changed.as_dict()["pelvic_list"] == 8.0 and len(changed.as_dict()) == len(ATTRIBUTES)
    assert base.with_overrides(None) is base
    assert changed != base and changed == base.with_overrides({"toe_clearance": 0.02, "pelvic_list": 8})
    assert pickle.loads(pickle.dumps(changed)) == changed


def test_values_are_immutable():
    attrs = LocomotionAttributes.defaults()
    with pytest.raises(AttributeError):
        attrs.pelvic_list = 3
    with pytest.raises(AttributeError):
        attrs.not_an_attribute


def test_unknown_name_lists_close_matches():
    with pytest.raises(ConfigError) as err:
        LocomotionAttributes.defaults().with_overrides({"toe_clearence": 0.02})
    assert str(err.value) == ("attributes.toe_clearence: got 'toe_clearence', allowed a registered "
                              "attribute name, close matches: toe_clearance")


def test_unknown_name_without_close_match_lists_every_name():
    with pytest.raises(ConfigError) as err:
        LocomotionAttributes.defaults().with_overrides({"zzz": 1})
    assert all(name in str(err.value) for name in ATTRIBUTES)


@pytest.mark.parametrize("name, value, allowed", [
    ("pelvic_list", 45, "0 to 20 deg"), ("toe_clearance", -0.01, "0 to 0.1 m"),
    ("sf_max", float("nan"), "60 to 240 steps/min"), ("leg_frequency", float("inf"), "0.1 to 20 Hz"),
    ("theta5_impact", "90", "a number in deg"), ("trunk_lean", True, "a number in deg"),
])
def test_out_of_range_names_field_value_and_range(name, value, allowed):
    with pytest.raises(ConfigError) as err:
        LocomotionAttributes.defaults().with_overrides({name: value})
    assert str(err.value).startswith(f"attributes.{name}: got ")
    assert str(err.value).endswith(f"allowed {allowed}")


def test_ordered_pairs_are_enforced():
    with pytest.raises(ConfigError, match=r"attributes.swing1_end_fraction: got 0.7, allowed less than"):
        LocomotionAttributes.defaults().with_overrides({"swing1_end_fraction": 0.7, "swing2_end_fraction": 0.6})


def test_docs_list_every_registered_attribute_with_its_default():
    text = DOCS.read_text(encoding="utf-8")
    rows = {m.group(1): m.group(2) for m in re.finditer(r"^\| `(\w+)` \| [^|]+ \| ([^|]+) \|", text, re.M)}
    assert set(rows) == set(ATTRIBUTES), "docs/attributes.md has drifted: regenerate it"
    for name, spec in ATTRIBUTES.items():
        assert float(rows[name]) == pytest.approx(spec.default), name


def test_docs_are_exactly_the_generated_table():
    from klaw_ocp.gait.attributes import markdown_table
    assert DOCS.read_text(encoding="utf-8") == markdown_table()


def test_not_used_yet_is_exactly_the_attributes_nothing_reads():
    """docs/attributes.md's "not used yet" must stay true both ways: a listed attribute appears
    nowhere in the package's code outside the registry, and every other one is read somewhere
    (as ``attrs.name``, ``get("name")`` or the like); so a walk changes with every unmarked one."""
    from klaw_ocp.gait.attributes import NOT_USED_YET
    src = Path(__file__).resolve().parents[1] / "src" / "klaw_ocp"
    code = "\n".join(p.read_text(encoding="utf-8") for p in src.rglob("*.py") if p.name != "attributes.py")
    # strings and comments only mention a name (examples, help texts): strip docstrings and comments
    code = re.sub(r'"""(.|\n)*?"""', "", code)
    code = re.sub(r"#.*", "", code)
    read = {name for name in ATTRIBUTES if re.search(rf"\b{name}\b", code)}
    assert NOT_USED_YET <= set(ATTRIBUTES)
    assert read & NOT_USED_YET == set(), "read by the code, so no longer 'not used yet'"
    assert set(ATTRIBUTES) - NOT_USED_YET - read == set(), "nothing reads these: mark them not used yet"
