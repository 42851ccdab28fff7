"""The first run on a machine (issue #32): compiling the solver kernels is said on the terminal
before the pause, timed in summary.json's ``compile_s`` and left out of the real-time factor; a
run with the kernels cached says nothing of it. And the progress bar advances step by step.

One test compiles the real kernels (a fresh process with an empty cache, as a new machine); the
others use a one-line library or the session's cached kernels. No test asserts a time."""
import json
import os
import shutil
import stat
import subprocess
import sys
from pathlib import Path

import casadi as ca
import pytest

from klaw_ocp.console import CompileNotice
from klaw_ocp import kernels

NOTICE = "klaw-ocp: compiling the solver kernels for this machine, once"
SAID_BESIDE = "compiling the solver kernels once for this machine"


def _compiler():
    """The C compiler klaw_ocp would use (None: KLAW_OCP_JIT off, or none on PATH)."""
    if os.environ.get("KLAW_OCP_JIT", "1").strip().lower() in ("0", "off", "false", "no"):
        return None
    names = [os.environ["CC"]] if os.environ.get("CC") else ["cc", "gcc", "clang"]
    return next((shutil.which(name) for name in names if shutil.which(name)), None)


requires_compiler = pytest.mark.skipif(_compiler() is None, reason="no C compiler on this machine")


def _tiny_library(tag: str) -> kernels.KernelLibrary:
    """A library of one small function: compiles in a fraction of a second."""
    def build(compiling):
        x = ca.SX.sym("x", 2)
        return [ca.Function("klaw_test_twice", [x], [2 * x])]
    return kernels.KernelLibrary(["tests/test_first_run.py", tag], ["klaw_test_twice"], build)


@requires_compiler
def test_compiling_is_announced_before_it_starts_and_timed(tmp_path, monkeypatch):
    monkeypatch.setenv("KLAW_OCP_CACHE_DIR", str(tmp_path / "cache"))
    library = _tiny_library("announce")
    told = []

    def listener(folder):
        # at the notice nothing is compiled yet: it comes before the pause
        told.append((Path(folder), library.library_path().exists()))

    before = kernels.compile_seconds()
    assert library.will_compile()
    with kernels.compile_notices(listener):
        assert list(library.functions()["klaw_test_twice"]([1.0, 2.0])[0]) == [2.0, 4.0]
        assert library.compiled and not library.will_compile()
        after = kernels.compile_seconds()
        # the same library again, as a later run finds it in the cache: loaded, not compiled
        again = _tiny_library("announce")
        assert not again.will_compile() and again.load() is not None
    assert told == [(kernels.cache_dir(), False)]
    assert after > before and kernels.compile_seconds() == after
    # outside the block no one is told any more
    with_no_listener = _tiny_library("no listener")
    with_no_listener.load()
    assert len(told) == 1


def test_the_notice_is_one_line_once(capsys, monkeypatch):
    monkeypatch.setenv("HOME", "/home/walker")
    notice = CompileNotice("klaw-ocp")
    for _ in range(3):          # the four subphases' libraries start compiling in parallel threads
        notice(Path("/home/walker/.cache/klaw_ocp/casadi-3.8.2"))
    err = capsys.readouterr().err.splitlines()
    assert notice.told and len(err) == 1 and err[0].startswith(NOTICE)
    assert "cached in ~/.cache/klaw_ocp/casadi-3.8.2" in err[0] and " s;" in err[0]


@requires_compiler
def test_a_first_run_says_it_compiles_then_a_second_run_does_not(short_config, tmp_path):
    """Two runs as whole processes sharing an empty kernel cache, as on a new machine. The
    compiler is a wrapper that keeps what the run had written on stderr when it was first asked
    to compile: the notice must be there already."""
    seen, err_file = tmp_path / "stderr-at-compile.txt", tmp_path / "stderr.txt"
    wrapper = tmp_path / "cc-wrapper"
    wrapper.write_text(f'#!/bin/sh\ncase " $* " in *" -shared "*) [ -e "{seen}" ] || cat "{err_file}" > "{seen}";; '
                       f'esac\nexec "{_compiler()}" "$@"\n')
    wrapper.chmod(wrapper.stat().st_mode | stat.S_IXUSR)
    env = dict(os.environ, KLAW_OCP_CACHE_DIR=str(tmp_path / "cache"), CC=str(wrapper))

    def run(out):
        with err_file.open("w") as err:
            done = subprocess.run([sys.executable, "-m", "klaw_ocp", "run", str(short_config), "--out", str(out),
                                   "--quiet", "--no-plots", "--no-animation"],
                                  env=env, stdout=subprocess.PIPE, stderr=err, text=True, timeout=600)
        assert done.returncode == 0, err_file.read_text()
        return done.stdout, err_file.read_text(), json.loads((out / "summary.json").read_text())

    out, err, summary = run(tmp_path / "first")
    assert err.splitlines() == [err.splitlines()[0]] and err.startswith(NOTICE), err
    assert str(tmp_path / "cache") in err
    assert seen.read_text().startswith(NOTICE)          # said before the first compile began
    assert summary["compile_s"] > 0 and summary["wall_s"] > 0
    assert summary["real_time_factor"] == pytest.approx(summary["simulated_s"] / summary["wall_s"])
    assert SAID_BESIDE in out and f"plus {summary['compile_s']:.1f} s" in out

    out, err, summary = run(tmp_path / "second")
    assert err == "" and summary["compile_s"] == 0.0 and SAID_BESIDE not in out


def test_the_progress_bar_advances_as_steps_are_solved(monkeypatch, tmp_path):
    """A walk that ends at rest has one step more than its plan (the closing step): the bar
    counts it, and stands at one step after the first (it used to fill before the first solve)."""
    import tqdm

    from klaw_ocp.walk import simulate_walk
    bars = []

    class Recorded(tqdm.tqdm):
        def __init__(self, *args, **kwargs):
            super().__init__(*args, **kwargs)
            bars.append(self)
    monkeypatch.setattr(tqdm, "tqdm", Recorded)
    seen = []
    config = {"name": "bar", "body": {"height": 1.8, "mass": 80},
              "walk": {"speed": 5.0, "steps": 2, "end_at_rest": True}}
    walk = simulate_walk(config, progress=True, on_step=lambda w: seen.append((bars[0].n, bars[0].total)))
    assert len(walk.steps) == 3 and len(bars) == 1
    assert seen == [(1, 3), (2, 3), (3, 3)]
    assert walk.compile_s >= 0 and walk.wall_s > 0


def test_a_walk_without_progress_makes_no_bar(monkeypatch):
    import tqdm

    from klaw_ocp.walk import simulate_walk

    def refuse(*args, **kwargs):
        raise AssertionError("a progress bar")
    monkeypatch.setattr(tqdm, "tqdm", refuse)
    config = {"name": "quiet", "body": {"height": 1.8, "mass": 80}, "walk": {"speed": 5.0, "steps": 1}}
    assert len(simulate_walk(config).steps) == 1
