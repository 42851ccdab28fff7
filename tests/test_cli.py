"""`klaw-ocp plan`: output, JSON shape, and one-line errors with exit code 2 (API and subprocess)."""
import json
import os
import shlex
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

import pytest
import yaml

from klaw_ocp.cli import SUBCOMMANDS, build_parser, main

ROOT = Path(__file__).resolve().parents[1]
NATURAL = str(ROOT / "configs" / "natural_walk.yaml")
STEP_KEYS = {"speed_kmh", "step_length_m", "step_frequency_spm", "t_cycle_s", "t_step_s", "t_ds_s",
             "t_stance_s", "t_swing_s", "w_m", "theta1_rad", "theta3_rad", "hip_y_m",
             "t_swing1_end_s", "t_swing2_end_s"}


def run_main(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_plan_speed_json(capsys):
    code, out, err = run_main(capsys, "plan", "--speed", "5", "--json")
    assert code == 0 and err == ""
    data = json.loads(out)
    assert set(data) >= {"body", "attributes", "steps"}
    assert data["body"]["height"] == 1.8 and data["body"]["mass"] == 80
    assert data["attributes"]["sf_max"] == 182
    (step,) = data["steps"]
    assert STEP_KEYS <= set(step)
    assert step["step_length_m"] == pytest.approx(0.7746, abs=1e-4)
    assert step["step_frequency_spm"] == pytest.approx(107.58, abs=5e-3)
    assert step["w_m"] == pytest.approx(0.922, abs=1e-3)
    assert step["hip_lead_m"] == pytest.approx(0.045 * step["step_length_m"])
    assert step["t_stance_s"] == pytest.approx(step["t_step_s"] + step["t_ds_s"])


@pytest.mark.parametrize("argv, sf", [
    (["--speed", "5", "--step-length", "0.5"], 166.67),
    (["--speed", "5", "--step-length", "1.05"], 79.37),
    (["--step-length", "0.7", "--step-frequency", "100", "--height", "1.6", "--mass", "60"], 100.0),
])
def test_plan_combinations(capsys, argv, sf):
    code, out, _ = run_main(capsys, "plan", *argv, "--json")
    assert code == 0
    assert json.loads(out)["steps"][0]["step_frequency_spm"] == pytest.approx(sf, abs=5e-3)


def test_plan_human_output_lists_parameters_timings_constraints(capsys):
    code, out, _ = run_main(capsys, "plan", "--speed", "5")
    assert code == 0
    for text in ("Locomotion parameters (eq. 1)", "107.58", "State-phase timings (eq. 2)",
                 "t_ds", "Step constraints at heel strike (eq. 3)", "0.9218", "0.4680", "-0.3740",
                 "landing hip ahead by", "0.0126", "hip ahead of mid-step", "0.0349"):
        assert text in out


def test_plan_config_every_step(capsys):
    code, out, _ = run_main(capsys, "plan", NATURAL, "--json")
    assert code == 0
    data = json.loads(out)
    assert data["name"] == "natural_walk" and len(data["steps"]) == 22
    assert [s["index"] for s in data["steps"]] == list(range(22))
    code, out, _ = run_main(capsys, "plan", NATURAL)
    assert code == 0 and "Walk 'natural_walk': 22 steps" in out
    assert len([l for l in out.splitlines() if l.strip().split(" ")[0].isdigit()]) == 22


BAD_ARGS = [
    (["plan", "--speed", "-1"], "walk.speed: got -1.0"),
    (["plan", "--speed", "nan"], "walk.speed: got nan"),
    (["plan", "--speed", "inf"], "walk.speed: got inf"),
    (["plan", "--speed", "0"], "walk.speed: got 0.0"),
    (["plan", "--step-frequency", "190"], "walk.step_frequency: got 190 steps/min, allowed 30 to 182"),
    (["plan", "--speed", "20"], "walk.speed: got 20 km/h, allowed 0.5 to 9"),
    (["plan", "--speed", "5", "--height", "0"], "body.height: got 0.0"),
    (["plan", "--speed", "5", "--mass", "-80"], "body.mass: got -80.0"),
    (["plan", "--speed", "5", "--step-length", "0.8", "--step-frequency", "120"], "walk: got speed 5 km/h"),
    (["plan"], "plan: got no locomotion parameter"),
    (["plan", NATURAL, "--speed", "3"], "plan: got CONFIG together with --speed"),
    (["plan", "does_not_exist.yaml"], "config: got 'does_not_exist.yaml'"),
]


@pytest.mark.parametrize("argv, start", BAD_ARGS, ids=[" ".join(a[1:])[-40:] for a, _ in BAD_ARGS])
def test_bad_input_via_main(capsys, argv, start):
    code, out, err = run_main(capsys, *argv)
    assert code == 2 and out == ""
    lines = err.splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith(f"klaw-ocp: error: {start}"), lines[0]
    assert "Traceback" not in err


def test_bad_config_values_via_main(capsys, tmp_path):
    f = tmp_path / "bad.yaml"
    f.write_text("name: bad\nbody: {height: 1.8, mass: 80}\nwalk: {speed: 5, steps: 2}\n"
                 "colour: red\n", encoding="utf-8")
    code, _, err = run_main(capsys, "plan", str(f))
    assert code == 2
    assert err.splitlines() == ["klaw-ocp: error: colour: got an unknown key (value 'red'), allowed only "
                                "the keys name, body, walk, attributes, solver, output"]


def test_argparse_errors_exit_2(capsys):
    """argparse's errors are one line too, naming the flag and what it allows; no usage banner."""
    code, _, err = run_main(capsys, "plan", "--speed", "abc")
    assert code == 2 and err == "klaw-ocp: error: --speed: got 'abc', allowed a number (walking speed v, km/h)\n"
    code, _, err = run_main(capsys)
    assert code == 2 and "a COMMAND is required" in err and len(err.splitlines()) == 1
    code, _, err = run_main(capsys, "run", "x.yaml", "--method", "newton")
    assert err == "klaw-ocp: error: --method: got 'newton', allowed one of multiple-shooting, plain-shooting\n"
    code, _, err = run_main(capsys, "frobnicate")
    assert code == 2 and err.startswith("klaw-ocp: error: COMMAND: got 'frobnicate', allowed one of plan, validate, run")
    code, _, err = run_main(capsys, "plan", "--height", "0")    # the height, not the missing speed
    assert code == 2 and err.startswith("klaw-ocp: error: body.height: got 0.0")


#: Every subcommand the CLI documents (cli.py's docstring, README): none may go missing.
COMMANDS = {"plan", "validate", "run", "plot", "compare", "sweep", "reproduce", "serve"}


def test_subcommands_are_a_registry(capsys):
    assert set(SUBCOMMANDS) == COMMANDS
    code, out, _ = run_main(capsys, "--help")
    assert code == 0
    for name, command in SUBCOMMANDS.items():
        assert callable(command.handler) and callable(command.configure)
        assert isinstance(command.help, str) and len(command.help.split()) >= 4, name
        assert name in out and command.help.split()[0] in out, name     # listed in `klaw-ocp --help`


@pytest.mark.parametrize("name", sorted(COMMANDS))
def test_every_subcommand_has_help_and_a_valid_example(capsys, name):
    """`klaw-ocp NAME --help` describes it and ends with at least one example that parses."""
    code, out, err = run_main(capsys, name, "--help")
    assert code == 0 and err == ""
    usage, _, rest = out.partition("\n\n")
    assert usage.startswith(f"usage: klaw-ocp {name}")
    description = rest.partition("\n\n")[0]
    assert not description.startswith(("options:", "positional arguments:")), f"{name}: no description"
    assert len(description.split()) >= 10, description
    _, sep, examples = rest.rpartition("\nexample")
    assert sep, f"no example in `klaw-ocp {name} --help`"
    lines = [line.strip() for line in examples.partition(":")[2].splitlines() if line.strip()]
    assert lines and all(line.startswith(f"klaw-ocp {name}") for line in lines), examples
    for line in lines:
        args = build_parser().parse_args(shlex.split(line)[1:])  # argparse exits on a bad example
        assert args.command == name and args.handler is SUBCOMMANDS[name].handler


def _cli(*argv, cwd, module="klaw_ocp.cli", timeout=60):
    env = {**os.environ, "PYTHONWARNINGS": "ignore"}
    return subprocess.run([sys.executable, "-m", module, *argv], capture_output=True,
                          text=True, cwd=cwd, env=env, timeout=timeout)


@pytest.mark.parametrize("argv, start", [
    (["plan", "--speed", "-1"], "klaw-ocp: error: walk.speed: got -1.0"),
    (["plan", "--speed", "nan", "--json"], "klaw-ocp: error: walk.speed: got nan"),
    (["plan", "--step-frequency", "190"], "klaw-ocp: error: walk.step_frequency: got 190"),
    (["plan", "--speed", "5", "--height", "0"], "klaw-ocp: error: body.height: got 0.0"),
])
def test_bad_input_via_subprocess(argv, start, tmp_path):
    r = _cli(*argv, cwd=tmp_path)
    assert r.returncode == 2 and r.stdout == ""
    assert r.stderr.splitlines() == [r.stderr.strip()] and r.stderr.startswith(start), r.stderr
    assert "Traceback" not in r.stderr


def test_plan_via_subprocess(tmp_path):
    """From a working directory that has no configs/ of its own: the path given is the one read."""
    assert not (tmp_path / "configs").exists()
    r = _cli("plan", str(ROOT / "configs" / "short_steps.yaml"), "--json", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    steps = json.loads(r.stdout)["steps"]
    assert len(steps) == 34 and steps[0]["step_frequency_spm"] == pytest.approx(166.67, abs=5e-3)


def _assert_plan_json(r):
    assert r.returncode == 0 and r.stderr == "", r.stderr
    data = json.loads(r.stdout)
    assert data["body"]["height"] == 1.8 and data["body"]["mass"] == 80
    (step,) = data["steps"]
    assert STEP_KEYS <= set(step)
    assert step["speed_kmh"] == pytest.approx(5.0) and step["step_frequency_spm"] == pytest.approx(107.58, abs=5e-3)


def test_python_dash_m_klaw_ocp(tmp_path):
    """`python -m klaw_ocp` (the package's __main__) is the klaw-ocp command, exit codes included."""
    _assert_plan_json(_cli("plan", "--speed", "5", "--json", cwd=tmp_path, module="klaw_ocp"))
    r = _cli("plan", "--speed", "-1", cwd=tmp_path, module="klaw_ocp")
    assert r.returncode == 2 and r.stderr.startswith("klaw-ocp: error: walk.speed: got -1.0"), r.stderr


def _console_script():
    # the script installed beside this interpreter first, then whatever PATH finds
    scripts = [sysconfig.get_path("scripts"), str(Path(sys.executable).parent)]
    return shutil.which("klaw-ocp", path=os.pathsep.join(scripts + [os.environ.get("PATH", "")]))


def test_the_installed_console_script(tmp_path):
    script = _console_script()
    if script is None:
        pytest.skip("the klaw-ocp console script is not installed")
    env = {**os.environ, "PYTHONWARNINGS": "ignore"}
    r = subprocess.run([script, "plan", "--speed", "5", "--json"], capture_output=True, text=True,
                       cwd=tmp_path, env=env, timeout=60)
    _assert_plan_json(r)
    r = subprocess.run([script], capture_output=True, text=True, cwd=tmp_path, env=env, timeout=60)
    assert r.returncode == 2 and "a COMMAND is required" in r.stderr


def test_run_writes_to_results_name_in_the_working_directory(tmp_path):
    """`klaw-ocp run CONFIG` without --out (and no output.dir): results/<name>/ under the working
    directory, wherever the config file is."""
    work, elsewhere = tmp_path / "work", tmp_path / "configs"
    work.mkdir(), elsewhere.mkdir()
    config = elsewhere / "two_steps.yaml"
    config.write_text(yaml.safe_dump({"name": "two_steps", "body": {"height": 1.8, "mass": 80},
                                      "walk": {"speed": 5.0, "steps": 2}}), encoding="utf-8")
    r = _cli("run", str(config), "--no-plots", "--quiet", cwd=work, module="klaw_ocp", timeout=300)
    assert r.returncode == 0, r.stderr
    out = work / "results" / "two_steps"
    assert sorted(p.name for p in out.iterdir()) == [".klaw-ocp", "angles.csv", "config.resolved.yaml", "dynamics.csv",
                                                   "events.csv", "summary.json", "walk.bvh", "walk.mot"]
    assert sorted(p.name for p in work.iterdir()) == ["results"]        # nothing else in the cwd
    assert sorted(p.name for p in elsewhere.iterdir()) == ["two_steps.yaml"]   # nor beside the config
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    assert summary["name"] == "two_steps" and summary["status"] == "ok" and summary["steps_completed"] == 2
    assert r.stdout.strip().endswith(f"wrote {Path('results') / 'two_steps'}/")
