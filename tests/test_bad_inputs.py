"""Issue #24, reliability: every bad input is refused cleanly before any solving.

A catalogue of bad inputs, each run through the command line (``python -m klaw_ocp`` in a fresh
working directory that holds only its input files). Every case must exit with code 2, print
exactly one line on stderr, ``klaw-ocp: error: <field or flag>: got <value>, allowed <...>``,
naming the field or flag at fault, with no traceback and no usage banner, and write nothing:
the working directory holds only the inputs afterwards. None of them gets as far as solving
(they are refused in the time it takes to start Python).

Below the catalogue: the Python API (:func:`klaw_ocp.simulate_walk` and the loaders) raises
klaw_ocp's own ConfigError for arguments of the wrong type, naming the argument.
"""
from __future__ import annotations

import os
import subprocess
import sys
from dataclasses import dataclass, field
from pathlib import Path

import pytest
import yaml

import klaw_ocp
from klaw_ocp.config import ExperimentConfig, load_config
from klaw_ocp.config_yaml import MAX_YAML_BYTES, MAX_YAML_DEPTH, parse_yaml
from klaw_ocp.errors import ConfigError, GaitLimitError, KlawError

SRC = Path(__file__).resolve().parents[1] / "src"
#: the tests' own checkout first, whatever is installed (the subprocess runs in a tmp folder)
ENV = {**os.environ, "PYTHONWARNINGS": "ignore",
       "PYTHONPATH": os.pathsep.join([str(SRC), *filter(None, [os.environ.get("PYTHONPATH")])])}

BASE = "name: t\nbody: {height: 1.8, mass: 80}\nwalk: {speed: 5.0, steps: 2}\n"


def config(**sections) -> str:
    """BASE with whole top-level sections replaced (a value of None drops the section) or added,
    each given as its YAML text."""
    lines = {"name": "t", "body": "{height: 1.8, mass: 80}", "walk": "{speed: 5.0, steps: 2}"}
    lines.update(sections)
    return "".join(f"{k}: {v}\n" for k, v in lines.items() if v is not None)


@dataclass
class Case:
    id: str
    argv: list[str]
    field: str                      # what the message must start with, after "klaw-ocp: error: "
    files: dict = field(default_factory=dict)   # name -> str or bytes written before the run
    dirs: tuple = ()                # folders made before the run


def run_cfg(text, *extra, field, id, name="c.yaml") -> Case:
    """``klaw-ocp run c.yaml`` on a config of the given text."""
    return Case(id, ["run", name, "--quiet", *extra], field, {name: text})


def setting(*sets, field, id) -> Case:
    """``klaw-ocp run c.yaml --set ...`` on the valid BASE config."""
    return Case(id, ["run", "c.yaml", "--quiet", *[a for s in sets for a in ("--set", s)]], field,
                {"c.yaml": BASE})


NESTED = "walk: " + "[" * 5000 + "]" * 5000 + "\n"
LAUGHS = "".join([f"l{i}: &l{i} [" + ", ".join([f"*l{i - 1}"] * 9) + "]\n" if i else
                  'l0: &l0 ["lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol"]\n' for i in range(10)])

CASES = [
    # -- YAML syntax and structure ------------------------------------------------------------
    run_cfg("name: t\nbody: {height: 1.8, mass: 80\nwalk: {}\n", field="c.yaml: got invalid YAML at line", id="yaml-unclosed-brace"),
    run_cfg("name: t\nbody:\n\theight: 1.8\n", field="c.yaml: got invalid YAML", id="yaml-tab-indent"),
    run_cfg("name: t\n---\nname: u\n", field="c.yaml: got invalid YAML", id="yaml-two-documents"),
    run_cfg("name: !!python/object/apply:os.system ['echo hacked']\n", field="c.yaml: got invalid YAML", id="yaml-python-tag"),
    run_cfg("name: 2001-02-30\n", field="c.yaml: got invalid YAML", id="yaml-impossible-date"),
    run_cfg(config(walk="{speed: 5, steps: " + "9" * 5000 + "}"), field="c.yaml: got invalid YAML", id="yaml-5000-digit-int"),
    run_cfg("- 1\n- 2\n", field="config: got [1, 2]", id="yaml-list-document"),
    run_cfg("just words\n", field="config: got 'just words'", id="yaml-scalar-document"),
    run_cfg("", field="config: got", id="yaml-empty-file"),
    run_cfg("# only a comment\n", field="config: got", id="yaml-only-comment"),
    run_cfg(BASE.encode("utf-8") + b"\xff\xfe\n", field="config: got 'c.yaml'", id="yaml-not-utf8"),
    run_cfg(BASE + "note: \x00\n", field="c.yaml: got invalid YAML", id="yaml-nul-char"),
    run_cfg(NESTED, field="walk[0][0][0][0][0][0][0][0][0]: got mappings and lists nested 11 deep", id="yaml-5000-nested-brackets"),
    run_cfg(BASE + LAUGHS, field="l", id="yaml-billion-laughs"),
    run_cfg(BASE + "loop: &a [1, *a]\n", field="loop[1]: got the alias *a inside its own anchor", id="yaml-recursive-alias"),
    run_cfg(BASE + "deep: &d [[[[[[1]]]]]]\ndeeper: [[[[[*d]]]]]\n", field="deeper[0][0][0][0][0]: got mappings and lists nested 12 deep", id="yaml-alias-too-deep"),
    run_cfg(BASE + "# " + "x" * MAX_YAML_BYTES + "\n", field="config: got 'c.yaml', a file of more than", id="yaml-too-large"),
    run_cfg(BASE + "walk: {speed: 3.0, steps: 2}\n", field="walk: got the key a second time", id="duplicate-top-key"),
    run_cfg("name: t\nbody: {height: 1.8, mass: 80, mass: 70}\nwalk: {speed: 5.0, steps: 2}\n",
            field="body.mass: got the key a second time", id="duplicate-nested-key"),
    run_cfg(config(walk="{speed: 5.0, steps: 4, schedule: [{step: 1, speed: 4, 'speed': 3}]}"),
            field="walk.schedule[0].speed: got the key a second time", id="duplicate-key-in-schedule-entry"),
    # -- types --------------------------------------------------------------------------------
    run_cfg(config(name="5"), field="name: got 5", id="name-int"),
    run_cfg(config(name="Natural Walk"), field="name: got 'Natural Walk'", id="name-not-slug"),
    run_cfg(config(name="x" * 200), field="name: got 'xxx", id="name-too-long"),
    run_cfg(config(body="[1.8, 80]"), field="body: got [1.8, 80]", id="body-a-list"),
    run_cfg(config(body="{height: '1.8', mass: 80}"), field="body.height: got '1.8'", id="height-a-string"),
    run_cfg(config(body="null"), field="body: got None", id="body-null"),
    run_cfg(config(walk="{speed: 5.0, steps: 2.5}"), field="walk.steps: got 2.5", id="steps-a-float"),
    run_cfg(config(walk="{speed: 5.0, steps: 2, start_from_rest: 'yes'}"), field="walk.start_from_rest: got 'yes'", id="bool-a-string"),
    run_cfg(config(attributes="[1, 2]"), field="attributes: got [1, 2]", id="attributes-a-list"),
    run_cfg(config(solver="fast"), field="solver: got 'fast'", id="solver-a-string"),
    run_cfg(config(output="{plots: 1}"), field="output.plots: got 1", id="plots-an-int"),
    run_cfg(BASE + "1: 2\n", field="config: got the key 1 (int)", id="key-not-a-string"),
    run_cfg(config(walk="{speed: !!binary aGVsbG8=, steps: 2}"), field="walk.speed: got b'hello'", id="speed-bytes"),
    # -- ranges: NaN, infinity, negative, zero, huge ---------------------------------------------
    run_cfg(config(walk="{speed: .nan, steps: 2}"), field="walk.speed: got nan", id="speed-nan"),
    run_cfg(config(walk="{speed: .inf, steps: 2}"), field="walk.speed: got inf", id="speed-inf"),
    run_cfg(config(walk="{speed: -5, steps: 2}"), field="walk.speed: got -5", id="speed-negative"),
    run_cfg(config(walk="{speed: 0, steps: 2}"), field="walk.speed: got 0", id="speed-zero"),
    run_cfg(config(walk="{speed: 1.0e+308, steps: 2}"), field="walk.speed: got 1e+308", id="speed-huge"),
    run_cfg(config(body="{height: 0, mass: 80}"), field="body.height: got 0", id="height-zero"),
    run_cfg(config(body="{height: 1.8, mass: -80}"), field="body.mass: got -80", id="mass-negative"),
    run_cfg(config(body="{height: 3.0, mass: 80}"), field="body.height: got 3.0", id="height-too-tall"),
    run_cfg(config(body="{height: 1.8, mass: 1.0e+9}"), field="body.mass: got 1000000000.0", id="mass-huge"),
    run_cfg(config(body="{height: 1.0, mass: 80}"), field="body.height: got 1 m, allowed 1.4 to 2.1 m", id="height-outside-envelope"),
    # -- unknown keys -----------------------------------------------------------------------------
    run_cfg(BASE + "colour: red\n", field="colour: got an unknown key", id="unknown-top-key"),
    run_cfg(config(walk="{sped: 5.0, steps: 2}"), field="walk.sped: got an unknown key", id="unknown-walk-key"),
    run_cfg(config(attributes="{pelvic_lst: 3}"), field="attributes.pelvic_lst: got 'pelvic_lst'", id="unknown-attribute"),
    run_cfg(config(attributes="{pelvic_list: 30}"), field="attributes.pelvic_list: got 30.0", id="attribute-out-of-range"),
    # -- the walk's length and shape ------------------------------------------------------------
    run_cfg(config(walk="{speed: 5.0, duration: 40000}"), field="walk.duration: got 40000", id="duration-40000"),
    run_cfg(config(walk="{speed: 5.0, steps: 100000}"), field="walk.steps: got 100000", id="steps-100000"),
    run_cfg(config(walk="{speed: 1.0, steps: 1000}"), field="walk.steps: got 1000 steps, which last more than 600 s", id="steps-longer-than-600s"),
    run_cfg(config(walk="{speed: 9.0, duration: 600}"), field="walk.duration: got 600 s, which takes more than 1000 steps", id="duration-more-than-1000-steps"),
    run_cfg(config(walk="{speed: 5.0, steps: 2, duration: 3}"), field="walk: got duration 3 and steps 2", id="duration-and-steps"),
    run_cfg(config(walk="{speed: 5.0}"), field="walk: got neither duration nor steps", id="neither-duration-nor-steps"),
    run_cfg(config(walk="{speed: 5.0, steps: 0}"), field="walk.steps: got 0", id="steps-zero"),
    run_cfg(config(walk="{steps: 2}"), field="walk: got 'no speed, step_length or step_frequency'", id="no-locomotion-parameter"),
    # -- the schedule ---------------------------------------------------------------------------
    run_cfg(config(walk="{speed: 5.0, steps: 6, schedule: [{step: 4, speed: 4}, {step: 2, speed: 3}]}"),
            field="walk.schedule[1].step: got 2, allowed a step after 4", id="schedule-out-of-order"),
    run_cfg(config(walk="{speed: 5.0, steps: 6, schedule: [{step: 2, speed: 4}, {step: 2, speed: 3}]}"),
            field="walk.schedule[1].step: got 2, allowed a step not already", id="schedule-step-twice"),
    run_cfg(config(walk="{speed: 5.0, steps: 4, schedule: [{step: 9, speed: 4}]}"),
            field="walk.schedule[0].step: got 9, allowed 0 to 3", id="schedule-beyond-the-walk"),
    run_cfg(config(walk="{speed: 5.0, steps: 4, schedule: [{step: 1}]}"),
            field="walk.schedule[0]: got {step: 1} with no parameter", id="schedule-entry-empty"),
    run_cfg(config(walk="{speed: 5.0, steps: 4, schedule: [{step: -1, speed: 3}]}"),
            field="walk.schedule[0].step: got -1", id="schedule-step-negative"),
    run_cfg(config(walk="{speed: 5.0, steps: 4, schedule: {step: 1, speed: 3}}"),
            field="walk.schedule: got {", id="schedule-not-a-list"),
    run_cfg(config(walk="{speed: 2.0, steps: 4, schedule: [{step: 1, speed: 8}]}"),
            field="walk.schedule: got a speed change of +6 km/h from step 0 to step 1", id="schedule-jump-too-large"),
    # -- speed, step length and step frequency limits -------------------------------------------
    run_cfg(config(walk="{speed: 12.0, steps: 2}"), field="walk.speed: got 12 km/h, allowed 0.5 to 9", id="speed-above-limit"),
    run_cfg(config(walk="{speed: 0.1, steps: 2}"), field="walk.speed: got 0.1 km/h", id="speed-below-limit"),
    run_cfg(config(walk="{step_frequency: 190, step_length: 0.5, steps: 2}"), field="walk.step_frequency: got 190", id="sf-above-limit"),
    run_cfg(config(walk="{step_length: 3.0, steps: 2}"), field="walk.step_length: got 3", id="sl-above-limit"),
    run_cfg(config(walk="{speed: 5.0, step_length: 0.8, step_frequency: 120, steps: 2}"), field="walk: got speed 5 km/h", id="v-sl-sf-disagree"),
    # -- solver settings ---------------------------------------------------------------------------
    run_cfg(config(solver="{intervals: 1}"), field="solver.intervals: got 1, allowed a number >= 5", id="intervals-1"),
    run_cfg(config(solver="{intervals: 501}"), field="solver.intervals: got 501", id="intervals-501"),
    run_cfg(config(walk="{speed: 5.0, steps: 500}", solver="{intervals: 100}"),
            field="solver.intervals: got 100 for a walk of 500 steps", id="intervals-times-steps"),
    run_cfg(config(solver="{tolerance: 0}"), field="solver.tolerance: got 0", id="tolerance-zero"),
    run_cfg(config(solver="{tolerance: 1.0e-20}"), field="solver.tolerance: got 1e-20", id="tolerance-tiny"),
    run_cfg(config(solver="{tolerance: 0.5}"), field="solver.tolerance: got 0.5", id="tolerance-loose"),
    run_cfg(config(solver="{max_iterations: 0}"), field="solver.max_iterations: got 0", id="iterations-zero"),
    run_cfg(config(solver="{max_iterations: 1000000}"), field="solver.max_iterations: got 1000000", id="iterations-huge"),
    run_cfg(config(solver="{nlp: snopt}"), field="solver.nlp: got 'snopt'", id="nlp-unknown"),
    run_cfg(config(solver="{method: euler}"), field="solver.method: got 'euler'", id="method-unknown"),
    run_cfg(config(solver="{method: plain-shooting, stance: tracking}"), field="solver.stance: got 'tracking'", id="tracking-with-plain-shooting"),
    run_cfg(config(solver="{lock_rule: elastic}"), field="solver.lock_rule: got 'elastic'", id="lock-rule-unknown"),
    # -- output settings -------------------------------------------------------------------------
    run_cfg(config(output="{fps: 0}"), field="output.fps: got 0", id="fps-zero"),
    run_cfg(config(output="{fps: -1}"), field="output.fps: got -1", id="fps-negative"),
    run_cfg(config(output="{fps: abc}"), field="output.fps: got 'abc'", id="fps-text"),
    run_cfg(config(output="{fps: 1.0e+9}"), field="output.fps: got 1000000000.0", id="fps-1e9"),
    run_cfg(config(walk="{speed: 5.0, duration: 120}", output="{fps: 1000}"),
            field="output.fps: got 1000 frames/s for", id="fps-too-many-frames"),
    run_cfg(config(output="{dir: ''}"), field="output.dir: got ''", id="output-dir-empty"),
    Case("output-dir-a-file", ["run", "c.yaml", "--quiet"], "output.dir: got 'taken', an existing file",
         {"c.yaml": config(output="{dir: taken}"), "taken": "a file\n"}),
    Case("output-dir-under-a-file", ["run", "c.yaml", "--quiet"], "output.dir: got 'taken/sub/dir', which lies under the file 'taken'",
         {"c.yaml": config(output="{dir: taken/sub/dir}"), "taken": "a file\n"}),
    # -- --set paths and values --------------------------------------------------------------------
    setting("walk.speed=abc", field="walk.speed: got 'abc'", id="set-speed-text"),
    setting("walk.speed=.nan", field="walk.speed: got nan", id="set-speed-nan"),
    setting("walk.speed=-1", field="walk.speed: got -1", id="set-speed-negative"),
    setting("nonsense", field="--set: got 'nonsense'", id="set-no-equals"),
    setting("walk.speed=", field="--set: got 'walk.speed='", id="set-empty-value"),
    setting("walk.speed=[1, 2]", field="--set walk.speed: got '[1, 2]'", id="set-a-list"),
    setting("walk.speed=" + "[" * 5000, field="--set walk.speed: got '[[[", id="set-5000-brackets"),
    setting("name.first=x", field="--set name.first: got name = 't' in the config", id="set-path-through-a-scalar"),
    setting("colour=red", field="colour: got an unknown key", id="set-unknown-key"),
    setting("solver.intervals=1", field="solver.intervals: got 1", id="set-intervals-1"),
    setting("walk.steps=100000", field="walk.steps: got 100000", id="set-steps-huge"),
    setting("a" + ".b" * 30 + "=1", field="--set: got 'a.b.b", id="set-path-too-deep"),
    # -- command-line flags and choices ------------------------------------------------------------
    Case("flag-unknown", ["run", "c.yaml", "--turbo"], "--turbo: got an unknown option", {"c.yaml": BASE}),
    Case("flag-method-choice", ["run", "c.yaml", "--method", "newton"], "--method: got 'newton', allowed one of multiple-shooting, plain-shooting", {"c.yaml": BASE}),
    Case("flag-stance-choice", ["run", "c.yaml", "--stance", "sideways"], "--stance: got 'sideways', allowed one of monitored, tracking", {"c.yaml": BASE}),
    Case("flag-tracking-with-plain-shooting", ["run", "c.yaml", "--method", "plain-shooting", "--stance", "tracking"], "solver.stance: got 'tracking'", {"c.yaml": BASE}),
    Case("flag-fps-text", ["run", "c.yaml", "--fps", "abc"], "output.fps: got 'abc'", {"c.yaml": BASE}),
    Case("flag-fps-empty", ["run", "c.yaml", "--fps", ""], "--fps: got ''", {"c.yaml": BASE}),
    Case("flag-fps-1e9", ["run", "c.yaml", "--fps", "1e9"], "output.fps: got 1000000000.0", {"c.yaml": BASE}),
    Case("flag-fps-zero", ["run", "c.yaml", "--fps", "0"], "output.fps: got 0", {"c.yaml": BASE}),
    Case("flag-fps-negative", ["run", "c.yaml", "--fps=-1"], "output.fps: got -1", {"c.yaml": BASE}),
    Case("flag-flag-with-a-value", ["run", "c.yaml", "--quiet=3"], "--quiet: got the value '3'", {"c.yaml": BASE}),
    Case("flag-option-without-value", ["run", "c.yaml", "--out"], "--out: got nothing", {"c.yaml": BASE}),
    Case("flag-extra-argument", ["run", "c.yaml", "d.yaml"], "klaw-ocp run: got the extra argument 'd.yaml'", {"c.yaml": BASE}),
    Case("plan-speed-text", ["plan", "--speed", "abc"], "--speed: got 'abc', allowed a number"),
    Case("plan-height-zero-alone", ["plan", "--height", "0"], "body.height: got 0.0"),
    Case("plan-ambiguous-abbreviation", ["plan", "--s", "5"], "--s: got an ambiguous abbreviation"),
    Case("plan-config-and-flags", ["plan", "c.yaml", "--speed", "3"], "plan: got CONFIG together with --speed", {"c.yaml": BASE}),
    Case("missing-config-argument", ["run"], "CONFIG: got nothing"),
    Case("unknown-command", ["frobnicate"], "COMMAND: got 'frobnicate', allowed one of plan, validate, run"),
    Case("no-command", [], "COMMAND: got nothing"),
    Case("sweep-without-vary", ["sweep", "c.yaml"], "--vary: got nothing", {"c.yaml": BASE}),
    Case("sweep-workers-zero", ["sweep", "c.yaml", "--vary", "walk.speed=3,4", "--workers", "0"], "--workers: got 0", {"c.yaml": BASE}),
    Case("sweep-vary-zero-step", ["sweep", "c.yaml", "--vary", "walk.speed=1:2:0"], "--vary walk.speed: got range '1:2:0'", {"c.yaml": BASE}),
    Case("compare-method-choice", ["compare", "c.yaml", "--method", "newton"], "--method: got 'newton'", {"c.yaml": BASE}),
    # -- files and folders ---------------------------------------------------------------------
    Case("config-missing", ["run", "nope.yaml"], "config: got 'nope.yaml', allowed an existing YAML file"),
    Case("config-a-directory", ["run", "folder"], "config: got 'folder', allowed a readable", dirs=("folder",)),
    Case("validate-config-missing", ["validate", "nope.yaml"], "config: got 'nope.yaml'"),
    Case("out-a-file", ["run", "c.yaml", "--out", "taken"], "--out: got 'taken', an existing file", {"c.yaml": BASE, "taken": "x\n"}),
    Case("out-under-a-file", ["run", "c.yaml", "--out", "taken/sub"], "--out: got 'taken/sub', which lies under the file 'taken'",
         {"c.yaml": BASE, "taken": "x\n"}),
    Case("out-empty", ["run", "c.yaml", "--out", ""], "--out: got ''", {"c.yaml": BASE}),
    Case("out-name-too-long", ["run", "c.yaml", "--out", "x" * 300 + "/y"], "--out: got 'xxx", {"c.yaml": BASE}),
    Case("compare-out-a-file", ["compare", "c.yaml", "--out", "taken"], "--out: got 'taken', an existing file", {"c.yaml": BASE, "taken": "x\n"}),
    Case("sweep-out-under-a-file", ["sweep", "c.yaml", "--vary", "walk.speed=3,4", "--out", "taken/s"],
         "--out: got 'taken/s', which lies under the file", {"c.yaml": BASE, "taken": "x\n"}),
    Case("reproduce-out-a-file", ["reproduce", "--out", "taken"], "--out: got 'taken', an existing file", {"taken": "x\n"}),
]


def _tree(root: Path) -> list[tuple[str, int]]:
    return sorted((str(p.relative_to(root)), p.stat().st_size if p.is_file() else -1) for p in root.rglob("*"))


def _klaw(argv, cwd):
    return subprocess.run([sys.executable, "-m", "klaw_ocp", *argv], capture_output=True, text=True,
                          cwd=cwd, env=ENV, timeout=120)


def test_the_catalogue_is_large_and_its_ids_unique():
    assert len(CASES) >= 60
    assert len({c.id for c in CASES}) == len(CASES)


def _prepare(case: Case, folder: Path):
    for name, content in case.files.items():
        (folder / name).write_bytes(content if isinstance(content, bytes) else content.encode("utf-8"))
    for name in case.dirs:
        (folder / name).mkdir()
    return _tree(folder)


@pytest.fixture(scope="module")
def outcomes(request, tmp_path_factory):
    """Every selected case run once, on every core at a time (each in a working directory of its
    own): case id -> (folder, its listing before, the finished process)."""
    from concurrent.futures import ThreadPoolExecutor
    # this module's selected cases only (other modules have parameters named "case" too)
    wanted = {item.callspec.params["case"].id for item in request.session.items
              if getattr(item, "callspec", None) and isinstance(item.callspec.params.get("case"), Case)}
    cases = [c for c in CASES if c.id in wanted]
    folders = {c.id: tmp_path_factory.mktemp("bad") for c in cases}
    before = {c.id: _prepare(c, folders[c.id]) for c in cases}
    with ThreadPoolExecutor(max_workers=max(2, os.cpu_count() or 2)) as pool:
        done = dict(zip([c.id for c in cases], pool.map(lambda c: _klaw(c.argv, folders[c.id]), cases)))
    return {i: (folders[i], before[i], done[i]) for i in done}


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_bad_input_is_refused_in_one_line_before_any_solving(case, outcomes):
    tmp_path, before, r = outcomes[case.id]
    assert r.returncode == 2, (r.returncode, r.stderr[-2000:])
    assert r.stdout == ""
    assert "Traceback" not in r.stderr and "usage:" not in r.stderr
    lines = r.stderr.splitlines()
    assert len(lines) == 1, r.stderr[-3000:]
    line = lines[0]
    assert line.startswith("klaw-ocp: error: " + case.field), line
    assert ": got " in line and ", allowed " in line, line
    assert len(line) < 400, line                  # long values are cut with "…"
    assert _tree(tmp_path) == before               # nothing written, nothing created


@pytest.mark.skipif(hasattr(os, "geteuid") and os.geteuid() == 0,
                    reason="root may write anywhere: os.access ignores permissions (see out-under-a-file)")
def test_an_unwritable_output_folder_is_refused(tmp_path):
    (tmp_path / "c.yaml").write_text(BASE, encoding="utf-8")
    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(0o555)
    try:
        for out in ("locked", "locked/new"):
            r = _klaw(["run", "c.yaml", "--quiet", "--out", out], tmp_path)
            assert r.returncode == 2 and len(r.stderr.splitlines()) == 1, r.stderr
            assert r.stderr.startswith(f"klaw-ocp: error: --out: got '{out}'"), r.stderr
        assert list(locked.iterdir()) == []
    finally:
        locked.chmod(0o755)


# ------------------------------------------------------------------------------- the Python API

@pytest.mark.parametrize("spec, allowed", [
    ([1, 2], "spec: got [1, 2], allowed a WalkSpec"),
    (None, "spec: got None, allowed a WalkSpec"),
    (5, "spec: got 5, allowed a WalkSpec"),
    (b"configs/natural_walk.yaml", "spec: got b'configs/natural_walk.yaml', allowed a WalkSpec"),
    (3.5, "spec: got 3.5"),
    ({"name": "t"}, "body: got nothing"),
    ("does/not/exist.yaml", "config: got 'does/not/exist.yaml', allowed an existing YAML file"),
])
def test_simulate_walk_refuses_a_bad_spec_with_a_config_error(spec, allowed):
    with pytest.raises(ConfigError) as err:
        klaw_ocp.simulate_walk(spec)
    assert str(err.value).startswith(allowed), str(err.value)
    assert "\n" not in str(err.value)


GOOD = {"name": "t", "body": {"height": 1.8, "mass": 80}, "walk": {"speed": 5.0, "steps": 2}}


@pytest.mark.parametrize("kwargs, start", [
    ({"method": "newton"}, "method: got 'newton', allowed None or one of multiple-shooting, plain-shooting"),
    ({"method": 3}, "method: got 3"),
    ({"progress": "yes"}, "progress: got 'yes', allowed True or False"),
    ({"raise_on_failure": None}, "raise_on_failure: got None"),
    ({"on_step": 5}, "on_step: got 5, allowed None or a callable taking the walk"),
    ({"on_step": "print"}, "on_step: got 'print', allowed None or a callable"),
])
def test_simulate_walk_refuses_bad_keyword_arguments(kwargs, start, monkeypatch):
    """Before anything is built or solved (an on_step that is no callable used to fail with a
    TypeError after step 0): no step controller is made."""
    import klaw_ocp.walk as walk_module

    def no_controller(*args, **kw):
        raise AssertionError("a step controller was built before the arguments were checked")
    monkeypatch.setattr(walk_module, "StepController", no_controller)
    with pytest.raises(ConfigError, match="^" + start.replace("(", r"\(").replace(")", r"\)")):
        klaw_ocp.simulate_walk(GOOD, **kwargs)


def test_simulate_walk_calls_a_callable_on_step_after_each_step():
    seen = []
    walk = klaw_ocp.simulate_walk(GOOD, on_step=lambda w: seen.append(len(w.steps)))
    assert seen == list(range(1, len(walk.steps) + 1))


def test_simulate_walk_checks_a_hand_made_walk_spec():
    from dataclasses import replace

    from klaw_ocp.walk import walk_spec
    spec = walk_spec(ExperimentConfig.from_mapping(GOOD))
    for change, start in [({"intervals": 1}, "spec.intervals: got 1"), ({"tolerance": 0.0}, "spec.tolerance: got 0.0"),
                          ({"max_iterations": 10**9}, "spec.max_iterations"), ({"nlp": "snopt"}, "spec.nlp"),
                          ({"plans": []}, "spec.plans: got []"), ({"body": "tall"}, "spec.body"),
                          ({"method": "euler"}, "spec.method"), ({"stance": "tracking", "method": "plain-shooting"}, "solver.stance")]:
        with pytest.raises(ConfigError) as err:
            klaw_ocp.simulate_walk(replace(spec, **change))
        assert str(err.value).startswith(start), str(err.value)


@pytest.mark.parametrize("path", [None, 5, [1], b"c.yaml", True])
def test_load_config_refuses_a_path_of_the_wrong_type(path):
    with pytest.raises(ConfigError, match=r"^config: got .*, allowed the path of a YAML file"):
        load_config(path)


def test_gait_limit_errors_are_config_errors():
    """Everything refused before solving is a ConfigError (a walk outside the envelope too)."""
    assert issubclass(GaitLimitError, ConfigError) and issubclass(ConfigError, KlawError)
    with pytest.raises(ConfigError):
        ExperimentConfig.from_mapping({**GOOD, "walk": {"speed": 20.0, "steps": 2}})


def test_anchors_and_aliases_within_the_bounds_still_load():
    data = parse_yaml("base: &b {height: 1.8, mass: 80}\nbody: *b\nother: {<<: *b, mass: 70}\n")
    assert data["body"] == {"height": 1.8, "mass": 80} and data["other"] == {"height": 1.8, "mass": 70}


def test_the_shipped_configs_are_far_inside_the_yaml_bounds():
    for path in sorted((SRC.parent / "configs").glob("*.yaml")):
        assert path.stat().st_size < MAX_YAML_BYTES / 10
        load_config(path)


class _EarlyNestingParser(yaml.SafeLoader):
    """A parser with a nesting limit of its own, below ours, met before any event is yielded (as
    libyaml's scanner meets its 1000 levels on a deep flow collection): whatever such a parser
    says, the refusal is ours."""

    def check_event(self, *choices):
        if self.flow_level == 0 and not getattr(self, "_scanned", False):
            self._scanned = True
            depth = level = 0
            for ch in self.buffer:
                level += (ch in "[{") - (ch in "]}")
                depth = max(depth, level)
            if depth > 5:
                raise yaml.scanner.ScannerError("while increasing flow level", None,
                                                "some wording of this library's own", self.get_mark())
        return super().check_event(*choices)


@pytest.mark.parametrize("loader", ["libyaml-or-pure", "pure-python", "early-nesting-limit"])
@pytest.mark.parametrize("text, path", [
    ("walk: " + "[" * 5000 + "]" * 5000 + "\n", "walk[0][0][0][0][0][0][0][0][0]"),
    ("walk: " + "{a: " * 12 + "1" + "}" * 12 + "\n", "walk.a.a.a.a.a.a.a.a.a"),
    ("a:\n" + "".join("  " * i + "- \n" for i in range(1, 30)), "a[0][0][0][0][0][0][0][0][0]"),
])
def test_the_nesting_limit_is_ours_whichever_parser_notices_first(monkeypatch, loader, text, path):
    import klaw_ocp.config_yaml as cy
    if loader == "pure-python":
        monkeypatch.setattr(cy, "_Loader", yaml.SafeLoader)
    elif loader == "early-nesting-limit":
        monkeypatch.setattr(cy, "_Loader", _EarlyNestingParser)
    with pytest.raises(ConfigError) as err:
        parse_yaml(text, "c.yaml")
    line = str(err.value)
    assert "\n" not in line
    assert line.startswith(f"{path}: got mappings and lists nested 11 deep"), line
    assert line.endswith(f"allowed at most {MAX_YAML_DEPTH} (docs/limits.md)"), line


@pytest.mark.parametrize("text, value", [
    ("1e-9", 1e-9), ("5e3", 5000.0), ("-2E-4", -2e-4), ("+1e2", 100.0), (".5e3", 500.0),
    ("1.0e5", 1e5), ("1.5e-3", 1.5e-3), ("2.e1", 20.0), ("0.5", 0.5), ("5", 5), ("-3", -3),
    ("1e", "1e"), ("e5", "e5"), ("1.2.3e4", "1.2.3e4"), ("'1e-9'", "1e-9"), (".inf", float("inf")),
])
def test_a_number_with_an_exponent_is_a_float_everywhere(tmp_path, text, value):
    """YAML 1.2 reads ``1e-9`` as a number; PyYAML (YAML 1.1) as text: one resolver in the loader
    reads it as a number in config files and in ``--set`` and ``--vary`` values alike."""
    from klaw_ocp.config_paths import parse_set, parse_vary
    for got in (parse_yaml(f"x: {text}\n")["x"], parse_yaml(f"x: [{text}]\n")["x"][0],
                parse_set(f"solver.tolerance={text}")[1], parse_vary(f"walk.speed={text},1")[1][0]):
        assert type(got) is type(value) and (got == value or got != got), (text, got)


def test_a_tolerance_written_1e_9_is_accepted_from_a_file(tmp_path):
    (tmp_path / "c.yaml").write_text(BASE + "solver: {tolerance: 1e-9}\n", encoding="utf-8")
    config = load_config(tmp_path / "c.yaml")
    assert config.solver.tolerance == 1e-9
    assert load_config(tmp_path / "c.yaml", sets=["solver.tolerance=1E-8"]).solver.tolerance == 1e-8
