"""Safe results folders (issue #24, part 3): a run never mixes with an earlier one and never
destroys one by failing; a folder klaw-ocp did not write is refused without --force; the same
for compare, sweep and reproduce (klaw_ocp.result_files.results_folder)."""
import json
from pathlib import Path

import pytest

from klaw_ocp.cli import main
from klaw_ocp.errors import ConvergenceError
from klaw_ocp.result_files.results_folder import MARKER, inspect_folder, read_marker


def _snapshot(folder: Path) -> dict:
    """Every file under ``folder`` (relative path -> bytes)."""
    return {p.relative_to(folder).as_posix(): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def _beside(out: Path) -> list:
    """What klaw-ocp left beside ``out``: partial and old folders."""
    return sorted(p.name for p in out.parent.iterdir()
                  if p.name.startswith(f"{out.name}.") or p.name.startswith(f".{out.name}."))


#: the start of the line a run prints before it compiles the solver kernels
COMPILING = "klaw-ocp: compiling the solver kernels"


def _one_error_line(capsys) -> str:
    # the first walk of a test session compiles the solver kernels into the session's fresh
    # cache, and says so on a line of its own (tests/test_first_run.py)
    err = [line for line in capsys.readouterr().err.strip().splitlines() if not line.startswith(COMPILING)]
    assert len(err) == 1, err
    return err[0]


def _run(config, out, *extra):
    return main(["run", str(config), "--out", str(out), "--quiet", "--no-plots", "--no-animation", *extra])


# ---------------------------------------------------------------------------------------- run

def test_a_rerun_replaces_the_folder_whole(short_config, tmp_path, capsys):
    out = tmp_path / "o"
    assert main(["run", str(short_config), "--out", str(out), "--quiet", "--no-animation"]) == 0
    assert (out / "plots" / "hip_height.png").is_file()
    marker = read_marker(out)
    assert marker["command"] == "run" and "summary.json" in marker["files"] and "plots/legs.png" in marker["files"]
    (out / "walk.gif").write_bytes(b"GIF89a from an earlier run")      # a file of ours, not written again
    (out / ".summary.json.x1y2.tmp").write_bytes(b"{")                   # a leftover of an atomic write
    assert inspect_folder(out, "run")[0] == "ours"
    assert _run(short_config, out) == 0
    assert sorted(p.name for p in out.iterdir()) == [MARKER, "angles.csv", "config.resolved.yaml", "dynamics.csv",
                                                     "events.csv", "summary.json", "walk.bvh", "walk.mot"]
    assert read_marker(out)["files"] == sorted(p.name for p in out.iterdir() if p.name != MARKER)
    assert _beside(out) == []                      # no staging or old folder left beside it
    assert capsys.readouterr().out.strip().endswith(f"wrote {out}/")


def test_a_failed_rerun_keeps_the_earlier_folder_and_the_partial_beside_it(short_config, tmp_path, capsys,
                                                                           fail_at_step):
    out = tmp_path / "o"
    assert _run(short_config, out) == 0
    earlier = _snapshot(out)
    fail_at_step(1, "swing2", 0.031)
    assert _run(short_config, out) == 3
    line = _one_error_line(capsys)
    partials = _beside(out)
    assert len(partials) == 1 and partials[0].startswith("o.partial-")
    partial = out.parent / partials[0]
    assert f"kept in {partial}" in line and "step 1" in line and "untouched" in line
    assert _snapshot(out) == earlier                   # byte for byte
    summary = json.loads((partial / "summary.json").read_text())
    assert summary["status"] == "failed" and summary["steps_completed"] == 1
    assert read_marker(partial)["command"] == "run"
    # the partial run is a results folder like any other: a later run into it replaces it whole
    assert inspect_folder(partial, "run")[0] == "ours"


def test_an_interrupted_rerun_keeps_the_earlier_folder(short_config, tmp_path, capsys, monkeypatch):
    out = tmp_path / "o"
    assert _run(short_config, out) == 0
    earlier = _snapshot(out)
    from klaw_ocp.control.step import StepController
    original = StepController.solve_step

    def interrupted(self, plan, inp, k, at_rest=False):
        if k == 1:
            raise KeyboardInterrupt
        return original(self, plan, inp, k, at_rest)
    monkeypatch.setattr(StepController, "solve_step", interrupted)
    assert _run(short_config, out) == 130
    line = _one_error_line(capsys)
    assert line.startswith("klaw-ocp: interrupted") and "1 completed step(s) kept in" in line
    assert _snapshot(out) == earlier
    partial = out.parent / _beside(out)[0]
    summary = json.loads((partial / "summary.json").read_text())
    assert summary["status"] == "interrupted" and summary["steps_completed"] == 1


def test_a_failed_first_run_is_written_in_place(short_config, tmp_path, capsys, fail_at_step):
    out = tmp_path / "o"
    fail_at_step(1, "stance", 0.5)
    assert _run(short_config, out) == 3
    assert f"written to {out}" in _one_error_line(capsys)
    assert _beside(out) == [] and json.loads((out / "summary.json").read_text())["status"] == "failed"
    fail_at_step(5, "stance", 0.5)               # never reached: the rerun replaces the failed run
    assert _run(short_config, out) == 0
    assert json.loads((out / "summary.json").read_text())["status"] == "ok" and _beside(out) == []


def test_a_foreign_folder_is_refused_without_force(short_config, tmp_path, capsys, monkeypatch):
    out = tmp_path / "mine"
    out.mkdir()
    (out / "notes.txt").write_text("my notes")
    with monkeypatch.context() as m:
        import klaw_ocp.walk
        m.setattr(klaw_ocp.walk, "simulate_walk", lambda *a, **k: pytest.fail("solved a walk"))
        assert _run(short_config, out) == 2
    line = _one_error_line(capsys)
    assert line.startswith("klaw-ocp: error: --out") and "notes.txt" in line and "--force" in line
    assert sorted(p.name for p in out.iterdir()) == ["notes.txt"] and _beside(out) == []
    # --force: written into it, its own file kept, and it stays foreign (the next run needs --force again)
    assert _run(short_config, out, "--force") == 0
    assert (out / "notes.txt").read_text() == "my notes" and (out / "summary.json").is_file()
    assert "notes.txt" not in read_marker(out)["files"] and _beside(out) == []
    assert _run(short_config, out) == 2
    capsys.readouterr()
    # a forced run removes what the forced run before it wrote and it does not write again
    assert main(["run", str(short_config), "--out", str(out), "--quiet", "--no-animation", "--force"]) == 0
    assert (out / "plots" / "legs.png").is_file()
    assert _run(short_config, out, "--force") == 0
    assert not list((out / "plots").glob("*.png")) and (out / "notes.txt").is_file()


@pytest.mark.parametrize("make", ["file", "other_command", "bad_marker", "no_key_file"])
def test_other_folders_klaw_ocp_did_not_write_for_run_are_refused(make, short_config, tmp_path, capsys, no_solving):
    out = tmp_path / "o"
    if make == "file":
        out.write_text("not a folder")
    else:
        out.mkdir()
        if make == "other_command":
            (out / "comparison.csv").write_text("run,step\n")
            (out / MARKER).write_text(json.dumps({"written_by": "klaw-ocp", "command": "compare",
                                                  "files": ["comparison.csv"]}))
        elif make == "bad_marker":
            (out / MARKER).write_text("not json")
        else:
            (out / "walk.bvh").write_text("HIERARCHY")       # a name of ours, but no summary.json
    assert _run(short_config, out) == 2
    assert "--out" in _one_error_line(capsys)


def test_a_folder_written_before_the_marker_is_recognised(short_config, tmp_path, capsys):
    out = tmp_path / "o"
    assert _run(short_config, out) == 0
    (out / MARKER).unlink()
    (out / "walk.gif").write_bytes(b"GIF89a")
    assert inspect_folder(out, "run")[0] == "ours"
    assert _run(short_config, out) == 0
    assert not (out / "walk.gif").exists() and (out / MARKER).is_file()


def test_an_empty_folder_and_a_symlinked_out_are_used(short_config, tmp_path, capsys):
    out = tmp_path / "empty"
    out.mkdir()
    assert _run(short_config, out) == 0 and (out / "summary.json").is_file()
    link = tmp_path / "link"
    link.symlink_to(out)
    assert _run(short_config, link) == 0
    assert link.is_symlink() and (link / "summary.json").is_file() and _beside(out) == []


# ------------------------------------------------------------------------------------ compare

def test_compare_replaces_its_folder_whole_and_refuses_a_foreign_one(short_config, tmp_path, capsys):
    out = tmp_path / "cmp"
    assert main(["compare", str(short_config), "--out", str(out), "--quiet"]) == 0
    runs = sorted(p.name for p in (out / "runs").iterdir())
    assert runs == ["short-multiple-shooting-monitored", "short-plain-shooting-monitored"]
    assert read_marker(out / "runs" / runs[0])["command"] == "run"            # each run is a run folder
    stale = out / "runs" / "short-old-monitored"
    stale.mkdir()
    (stale / "summary.json").write_text("{}")
    assert main(["compare", str(short_config), "--out", str(out), "--quiet", "--method", "plain-shooting",
                 "--stance", "monitored"]) == 2                                # one run: bad input
    assert stale.is_dir()                                                      # nothing touched
    capsys.readouterr()
    # a comparison of the runs inside it: they are carried into the new folder, the stale one is not
    assert main(["compare", *(str(out / "runs" / r) for r in runs), "--out", str(out)]) == 0
    assert sorted(p.name for p in (out / "runs").iterdir()) == runs and not stale.exists()
    assert (out / "comparison.csv").is_file() and _beside(out) == []
    foreign = tmp_path / "foreign"
    foreign.mkdir()
    (foreign / "data.csv").write_text("1\n")
    capsys.readouterr()
    assert main(["compare", *(str(out / "runs" / r) for r in runs), "--out", str(foreign)]) == 2
    assert "--force" in _one_error_line(capsys) and sorted(p.name for p in foreign.iterdir()) == ["data.csv"]
    assert main(["compare", *(str(out / "runs" / r) for r in runs), "--out", str(foreign), "--force"]) == 0
    assert {"data.csv", "comparison.csv", "comparison.png"} <= {p.name for p in foreign.iterdir()}


def test_a_compare_with_a_failed_walk_keeps_the_earlier_comparison(short_config, tmp_path, capsys, fail_at_step):
    out = tmp_path / "cmp"
    assert main(["compare", str(short_config), "--out", str(out), "--quiet"]) == 0
    earlier = _snapshot(out)
    capsys.readouterr()
    fail_at_step(1, "swing1", 0.2)
    assert main(["compare", str(short_config), "--out", str(out), "--quiet"]) == 3
    line = _one_error_line(capsys)
    assert "step 1" in line and "swing1" in line and "kept in" in line
    assert _snapshot(out) == earlier
    partial = out.parent / _beside(out)[0]
    assert (partial / "comparison.csv").is_file()
    for run in (partial / "runs").iterdir():
        assert json.loads((run / "summary.json").read_text())["steps_completed"] == 1


# -------------------------------------------------------------------------------------- sweep

def test_sweep_replaces_its_folder_whole_and_refuses_a_foreign_one(short_config, tmp_path, capsys):
    out = tmp_path / "sw"
    argv = ["sweep", str(short_config), "--vary", "walk.speed=5", "--workers", "1", "--out", str(out), "--quiet"]
    assert main(argv) == 0
    assert sorted(p.name for p in out.iterdir()) == [MARKER, "sweep.csv", "sweep.png"]
    (out / ".sweep.csv.abc.tmp").write_text("half")
    assert main(argv) == 0
    assert sorted(p.name for p in out.iterdir()) == [MARKER, "sweep.csv", "sweep.png"] and _beside(out) == []
    (out / "README.md").write_text("about this sweep")
    capsys.readouterr()
    assert main(argv) == 2
    line = _one_error_line(capsys)
    assert "README.md" in line and "--force" in line
    assert main(argv + ["--force"]) == 0 and (out / "README.md").is_file()


def test_an_interrupted_sweep_keeps_the_finished_walks(short_config, tmp_path, capsys, monkeypatch):
    out = tmp_path / "sw"
    import klaw_ocp.sweep as sweep
    original = sweep.run_walk

    def second_is_interrupted(mapping, method):
        if mapping["walk"]["speed"] == 4:
            raise KeyboardInterrupt
        return original(mapping, method)
    monkeypatch.setattr(sweep, "run_walk", second_is_interrupted)
    assert main(["sweep", str(short_config), "--vary", "walk.speed=5,4", "--workers", "1", "--out", str(out),
                 "--quiet"]) == 130
    assert "1 finished walk(s) written to" in _one_error_line(capsys)
    lines = (out / "sweep.csv").read_text().splitlines()
    assert len(lines) == 2 and lines[1].startswith("5,")


# ---------------------------------------------------------------------------------- reproduce

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture
def quick_reproduce(monkeypatch):
    """``klaw-ocp reproduce`` writing two files instead of solving the paper: the folder rules only."""
    import klaw_ocp.reproduce as rep
    calls = {"fail": None}

    def fake(configs_dir, out_dir, progress=False):
        out = Path(out_dir)
        (out / "numbers.json").write_text("{}\n")
        if calls["fail"] is not None:
            raise calls["fail"]
        (out / "README.md").write_text("# reproduced\n")
        return {"numbers": out / "numbers.json", "readme": out / "README.md"}
    monkeypatch.setattr(rep, "reproduce", fake)
    return calls


def test_reproduce_replaces_its_folder_whole_and_keeps_it_on_failure(tmp_path, capsys, quick_reproduce):
    out = tmp_path / "paper"
    argv = ["reproduce", "--configs", str(ROOT / "configs"), "--out", str(out), "--quiet"]
    assert main(argv) == 0
    (out / "fig8.png").write_bytes(b"an earlier figure")
    assert main(argv) == 0
    assert sorted(p.name for p in out.iterdir()) == [MARKER, "README.md", "numbers.json"]
    earlier = _snapshot(out)
    capsys.readouterr()
    quick_reproduce["fail"] = ConvergenceError(3, "swing2", 0.2, "residual 0.2",
                                               where="long_steps.yaml (multiple-shooting)")
    assert main(argv) == 3
    line = _one_error_line(capsys)
    assert line.startswith("klaw-ocp: error: long_steps.yaml (multiple-shooting): step 3") and "kept in" in line
    assert _snapshot(out) == earlier
    quick_reproduce["fail"] = KeyboardInterrupt()
    assert main(argv) == 130
    assert _one_error_line(capsys).startswith("klaw-ocp: interrupted") and _snapshot(out) == earlier


def test_reproduce_refuses_a_foreign_folder(tmp_path, capsys, quick_reproduce):
    out = tmp_path / "paper"
    out.mkdir()
    (out / "thesis.tex").write_text("\\documentclass{article}")
    argv = ["reproduce", "--configs", str(ROOT / "configs"), "--out", str(out), "--quiet"]
    assert main(argv) == 2
    assert "thesis.tex" in _one_error_line(capsys) and sorted(p.name for p in out.iterdir()) == ["thesis.tex"]
    assert main(argv + ["--force"]) == 0 and (out / "thesis.tex").is_file() and (out / "README.md").is_file()
