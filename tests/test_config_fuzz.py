"""Issue #24, reliability: fuzzing the config loader and the high-level functions (hypothesis).

- Any document, of any shape and any values (nested mappings and lists, scalars, None, bytes,
  huge integers, NaN, infinities, strings, random keys among the valid ones), given to
  :meth:`ExperimentConfig.from_mapping` or as YAML text to the loader, gives a valid config or
  one :class:`ConfigError` line, never another exception.
- Near-valid configs (a valid one with random fields changed) reach the paper's own checks
  (eq. 1-3, the envelope, the walk's bounds): still a valid config or a ConfigError.
- The high level (section 3) on random valid input gives finite results with v = sl·sf (sf in
  steps/min, v in m/min) and t_stance = t_step + t_ds.

Example counts are modest: the whole file runs in well under 20 s.
"""
from __future__ import annotations

import math
import string

import pytest
import yaml
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from klaw_ocp.body import Body
from klaw_ocp.config import ExperimentConfig, load_config
from klaw_ocp.config_yaml import parse_yaml
from klaw_ocp.config_paths import apply_sets
from klaw_ocp.errors import ConfigError
from klaw_ocp.gait import ATTRIBUTES, LocomotionAttributes, complete_parameters, state_phase_timings
from klaw_ocp.gait.envelope import SUPPORTED_HEIGHT_M, SUPPORTED_MASS_KG
from klaw_ocp.gait.parameters import KMH_TO_M_PER_MIN
from klaw_ocp.gait.timings import SF_DS_ZERO

FUZZ = settings(max_examples=100, deadline=None, database=None, suppress_health_check=[HealthCheck.too_slow])
FEW = settings(max_examples=40, deadline=None, database=None,
               suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])

#: every key the schema knows, so that random documents often get past the first unknown key
KEYS = ["name", "body", "walk", "attributes", "solver", "output", "height", "mass", "speed",
        "step_length", "step_frequency", "duration", "steps", "schedule", "step", "start_from_rest",
        "end_at_rest", "method", "intervals", "tolerance", "max_iterations", "nlp", "stance",
        "lock_rule", "dir", "plots", "fps", "animation", *list(ATTRIBUTES)[:8]]

scalars = st.one_of(
    st.none(), st.booleans(),
    st.integers(min_value=-10**6, max_value=10**6), st.integers(min_value=-10**400, max_value=10**400),
    st.floats(allow_nan=True, allow_infinity=True), st.sampled_from([0, -1, 1e308, -1e308, 5e-324, 1e-300]),
    st.text(max_size=30), st.binary(max_size=20),
    st.sampled_from(["multiple-shooting", "plain-shooting", "tracking", "monitored", "auto", "ipopt",
                     "nan", "inf", "", "5", "t", "natural_walk"]),
)
keys = st.one_of(st.sampled_from(KEYS), st.text(max_size=12), st.integers(-3, 3), st.none(), st.booleans(),
                 st.floats(allow_nan=False))
documents = st.recursive(scalars, lambda inner: st.one_of(
    st.lists(inner, max_size=5), st.dictionaries(keys, inner, max_size=6)), max_leaves=30)


def _refused_or_valid(fn, *args):
    """fn(*args) returns a config or raises ConfigError (one line); anything else fails the test."""
    try:
        result = fn(*args)
    except ConfigError as exc:
        message = str(exc)
        assert "\n" not in message and message.strip(), repr(message)
        assert len(message) < 700, message
        return None
    return result


@FUZZ
@given(documents)
def test_any_document_is_a_config_or_a_config_error(data):
    config = _refused_or_valid(ExperimentConfig.from_mapping, data)
    if config is not None:
        assert isinstance(config, ExperimentConfig) and config.plan()


@FUZZ
@given(st.dictionaries(st.sampled_from(["name", "body", "walk", "attributes", "solver", "output"]),
                       documents, max_size=6))
def test_any_mapping_of_the_top_level_keys_is_a_config_or_a_config_error(data):
    _refused_or_valid(ExperimentConfig.from_mapping, data)


VALID = {"name": "t", "body": {"height": 1.8, "mass": 80.0}, "walk": {"speed": 5.0, "steps": 4},
         "attributes": {}, "solver": {}, "output": {}}
#: where a changed value goes: (section, key); None as key replaces the whole section
PLACES = [(s, k) for s, ks in {
    "body": ["height", "mass"],
    "walk": ["speed", "step_length", "step_frequency", "duration", "steps", "start_from_rest", "end_at_rest", "schedule"],
    "solver": ["method", "intervals", "tolerance", "max_iterations", "nlp", "stance", "lock_rule"],
    "output": ["dir", "plots", "fps", "animation"],
    "attributes": list(ATTRIBUTES),
}.items() for k in ks] + [("name", None), ("body", None), ("walk", None), ("solver", None)]

numbers = st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.integers(-10**30, 10**30),
                    st.floats(min_value=-5, max_value=300), st.integers(-5, 1200))
schedules = st.lists(st.fixed_dictionaries({"step": st.integers(-2, 30)}, optional={
    "speed": numbers, "step_length": numbers, "step_frequency": numbers}), max_size=5)
values = st.one_of(numbers, scalars, schedules, documents)


@FUZZ
@given(st.lists(st.tuples(st.sampled_from(PLACES), values), min_size=1, max_size=4))
def test_a_valid_config_with_random_changes_is_a_config_or_a_config_error(changes):
    data = {k: (dict(v) if isinstance(v, dict) else v) for k, v in VALID.items()}
    for (section, key), value in changes:
        if key is None:
            data[section] = value
        elif isinstance(data.get(section), dict):
            data[section][key] = value
    _refused_or_valid(ExperimentConfig.from_mapping, data)


@FUZZ
@given(documents)
def test_any_document_as_yaml_text_is_a_config_or_a_config_error(data):
    try:
        text = yaml.safe_dump(data, allow_unicode=True)
    except (yaml.YAMLError, TypeError, ValueError, RecursionError):   # keys PyYAML cannot write
        assume(False)
    parsed = _refused_or_valid(parse_yaml, text, "fuzz.yaml")
    if parsed is not None:
        _refused_or_valid(ExperimentConfig.from_mapping, parsed)


YAML_BITS = ["name: t\n", "body: {height: 1.8, mass: 80}\n", "walk: {speed: 5.0, steps: 3}\n", "walk:\n",
             "  speed: 5\n", "  steps: 2\n", "  schedule:\n", "    - {step: 1, speed: 4}\n", "- ", "[", "]",
             "{", "}", "&a ", "*a", "*b", "&b [*a, *a, *a]\n", "<<: *a\n", "!!binary aGk=", "!!python/name:os.system",
             "!!float", "? ", ": ", ".nan", "-.inf", "1e400", "0x1F", "2001-02-30", "~", "'", '"', "\t", "\x00",
             "#", "---\n", "...\n", "\n", "  ", ",", "|\n", ">-\n", "%YAML 1.1\n", "!!set {a, b}\n", "!!omap [a: 1]\n"]


@FUZZ
@given(st.one_of(st.text(max_size=200), st.lists(st.sampled_from(YAML_BITS), max_size=25).map("".join)))
def test_any_yaml_text_is_parsed_or_refused_in_one_line(text):
    parsed = _refused_or_valid(parse_yaml, text, "fuzz.yaml")
    if isinstance(parsed, dict):
        _refused_or_valid(ExperimentConfig.from_mapping, parsed)


@FEW
@given(st.lists(st.sampled_from(YAML_BITS), max_size=25).map("".join))
def test_a_yaml_file_loads_or_is_refused_in_one_line(tmp_path_factory, text):
    path = tmp_path_factory.mktemp("fuzz") / "c.yaml"
    path.write_text(text, encoding="utf-8", errors="surrogatepass")
    _refused_or_valid(load_config, path)


set_paths = st.one_of(st.sampled_from([f"{s}.{k}" if k else s for s, k in PLACES]),
                      st.text(alphabet=string.ascii_letters + "._-", min_size=1, max_size=20))
set_values = st.one_of(st.sampled_from(["4", "0.03", "true", "null", ".nan", "-1", "1e9", "[1, 2]", "{a: 1}",
                                        "&a 1", "*a", "!!python/name:os.system", "plain-shooting", "'x'"]),
                       st.text(max_size=20))


@FUZZ
@given(st.lists(st.tuples(set_paths, set_values).map("=".join), min_size=1, max_size=3))
def test_any_set_override_is_applied_or_refused_in_one_line(sets):
    def apply(sets):
        return ExperimentConfig.from_mapping(apply_sets({k: (dict(v) if isinstance(v, dict) else v)
                                                         for k, v in VALID.items()}, sets))
    _refused_or_valid(apply, sets)


# ---------------------------------------------------------------------------- the high level

heights = st.floats(*SUPPORTED_HEIGHT_M)
masses = st.floats(*SUPPORTED_MASS_KG)
ATTRS = LocomotionAttributes.defaults()


@FUZZ
@given(heights, masses, st.floats(ATTRS.speed_min, ATTRS.speed_max), st.floats(0.1, 1.5),
       st.floats(ATTRS.sf_min, ATTRS.sf_max), st.sets(st.sampled_from(["v", "sl", "sf"]), min_size=1, max_size=2))
def test_eq1_completion_gives_finite_parameters_with_v_equal_sl_sf(height, mass, v, sl, sf, subset):
    """Eq. 1 from any one or two of (v, sl, sf): the completed set is finite and v = sl·sf."""
    body = Body(height, mass)
    kwargs = {"speed_kmh": v if "v" in subset else None, "step_length": sl if "sl" in subset else None,
              "step_frequency": sf if "sf" in subset else None}
    p = _refused_or_valid(lambda: complete_parameters(body, **kwargs))
    if p is None:
        return     # outside the limits: refused (a GaitLimitError, a kind of ConfigError)
    assert all(math.isfinite(x) and x > 0 for x in (p.speed_kmh, p.step_length_m, p.step_frequency_spm))
    assert p.speed_kmh * KMH_TO_M_PER_MIN == pytest.approx(p.step_length_m * p.step_frequency_spm, rel=1e-12)
    for name, typed, got in (("v", v, p.speed_kmh), ("sl", sl, p.step_length_m), ("sf", sf, p.step_frequency_spm)):
        if name in subset:
            assert got == pytest.approx(typed, rel=1e-12)
    assert ATTRS.speed_min <= p.speed_kmh <= ATTRS.speed_max
    assert ATTRS.sf_min <= p.step_frequency_spm <= ATTRS.sf_max


@FUZZ
@given(heights, masses, st.floats(ATTRS.speed_min, ATTRS.speed_max))
def test_eq1_from_the_speed_alone_is_the_normalizing_formula(height, mass, v):
    p = _refused_or_valid(lambda: complete_parameters(Body(height, mass), speed_kmh=v))
    if p is not None:
        assert p.step_length_m / (p.step_frequency_spm * height) == pytest.approx(0.004, rel=1e-12)


@FUZZ
@given(st.floats(min_value=1e-3, max_value=SF_DS_ZERO, exclude_max=True))
def test_eq2_timings_are_finite_and_add_up(sf):
    t = state_phase_timings(sf)
    values = [t.t_cycle, t.t_step, t.t_ds, t.t_stance, t.t_swing, t.t_swing1_end, t.t_swing2_end, t.t_theta1_off]
    assert all(math.isfinite(x) and x > 0 for x in values)
    assert t.t_stance == pytest.approx(t.t_step + t.t_ds, rel=1e-12)
    assert t.t_swing == pytest.approx(t.t_step - t.t_ds, rel=1e-12)
    assert t.t_cycle == pytest.approx(2 * t.t_step, rel=1e-12) and t.t_step == pytest.approx(60 / sf, rel=1e-12)
    assert 0 < t.t_swing1_end < t.t_swing2_end < t.t_swing


@FUZZ
@given(st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.integers(-10**400, 10**400), st.none(),
                 st.text(max_size=5), st.booleans(), st.binary(max_size=5)))
def test_eq2_refuses_any_other_step_frequency_with_a_config_error(sf):
    assume(not (isinstance(sf, (int, float)) and not isinstance(sf, bool) and abs(sf) < 1e300
                and math.isfinite(sf) and 0 < sf < SF_DS_ZERO))
    with pytest.raises(ConfigError):
        state_phase_timings(sf)


@FEW
@given(heights, masses, st.floats(ATTRS.speed_min, ATTRS.speed_max), st.integers(1, 40), st.booleans())
def test_a_planned_walk_chains_its_steps(height, mass, v, steps, from_rest):
    """Every step of a valid walk: finite, v = sl·sf, t_stance = t_step + t_ds, steps back to back."""
    data = {"name": "f", "body": {"height": height, "mass": mass},
            "walk": {"speed": v, "steps": steps, "start_from_rest": from_rest}}
    config = _refused_or_valid(ExperimentConfig.from_mapping, data)
    if config is None:
        return
    plans = config.plan()
    assert len(plans) == steps
    for a, b in zip(plans, plans[1:]):
        assert b.t_start == pytest.approx(a.t_start + a.timings.t_step)
        assert b.constraints.ankle_x == pytest.approx(a.constraints.next_ankle_x)
    for p in plans:
        q, t = p.parameters, p.timings
        assert q.speed_kmh * KMH_TO_M_PER_MIN == pytest.approx(q.step_length_m * q.step_frequency_spm, rel=1e-9)
        assert t.t_stance == pytest.approx(t.t_step + t.t_ds, rel=1e-12)
        assert all(math.isfinite(x) for x in p.as_dict().values())
