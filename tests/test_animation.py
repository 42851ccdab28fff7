"""walk.gif (issue #23, docs/gif.md): the body walking, side and front views and the view from
above, drawn from the run's results at the GIF's own frame rate; ``output.animation`` and ``run
--no-animation`` switch it off, ``plot --animation`` redraws it from a results folder."""
import math
import os

import numpy as np
import pytest
import yaml
from PIL import Image

from klaw_ocp.cli import main
from klaw_ocp.io.animation import GIF_FILE, GIF_FPS, animation_figure, footprints, write_animation
from klaw_ocp.io.plot_style import LEG_COLOURS
from klaw_ocp.io.run_data import RunData

TITLE_ROWS = 40          # the title and the time counter are above this pixel row


def _config(folder, **output):
    path = folder / "short.yaml"
    data = {"name": "short", "body": {"height": 1.8, "mass": 80}, "walk": {"speed": 5.0, "steps": 2}}
    if output:
        data["output"] = output
    path.write_text(yaml.safe_dump(data), encoding="utf-8")
    return path


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    """A two-step walk run with output.animation on and --no-plots: walk.gif without the plots."""
    folder = tmp_path_factory.mktemp("gif")
    out = folder / "out"
    assert main(["run", str(_config(folder, animation=True)), "--out", str(out), "--quiet", "--no-plots"]) == 0
    return out


def _frames(path) -> list[np.ndarray]:
    with Image.open(path) as gif:
        frames = []
        for k in range(gif.n_frames):
            gif.seek(k)
            frames.append(np.asarray(gif.convert("RGB")).astype(int))
    return frames


def _rgb(colour: str) -> np.ndarray:
    return np.array([int(colour[i:i + 2], 16) for i in (1, 3, 5)])


def test_the_gif_has_a_frame_per_gif_frame_time_at_the_gif_rate(run_dir):
    from klaw_ocp.commands.run import GIF_FILE as RUN_WRITES      # kept apart: run does not load matplotlib
    assert RUN_WRITES == GIF_FILE
    path = run_dir / GIF_FILE
    assert not (run_dir / "plots").exists() or not any((run_dir / "plots").iterdir())   # --no-plots kept
    expected = math.floor(RunData.from_folder(run_dir).duration * GIF_FPS + 1e-9) + 1   # first to last heel strike
    with Image.open(path) as gif:
        assert gif.format == "GIF" and gif.n_frames == expected and expected >= 10
        durations = []
        for k in range(gif.n_frames):
            gif.seek(k)
            durations.append(gif.info["duration"])
        assert gif.info.get("loop") == 0
    assert durations == [1000 / GIF_FPS] * expected        # played back in real time
    mask = os.umask(0)
    os.umask(mask)
    assert path.stat().st_mode & 0o777 == 0o666 & ~mask    # a normal file, not mkstemp's 0600
    assert sorted(p.name for p in run_dir.iterdir() if p.name.startswith(".")) == [".klaw-ocp"]   # no temporary left
    assert path.stat().st_size < 1_000_000


def test_every_frame_draws_the_body_and_consecutive_frames_move(run_dir):
    frames = _frames(run_dir / GIF_FILE)
    width = frames[0].shape[1]
    side, front = slice(0, int(0.55 * width)), slice(int(0.6 * width), int(0.8 * width))
    right = _rgb(LEG_COLOURS["right"])
    for k, frame in enumerate(frames):
        assert frame.mean(axis=2).var() > 300, f"frame {k} is nearly blank"
        for name, columns in (("side", side), ("front", front)):
            leg = np.all(frame[TITLE_ROWS:, columns] == right, axis=2).sum()
            assert leg > 100, f"frame {k}: {leg} pixels of the right leg in the {name} view"
    for k in range(1, len(frames)):
        # the front view's window stands still: what changes there is the body moving
        for name, columns, least in (("side", side, 200), ("front", front, 500)):
            moved = np.any(frames[k][TITLE_ROWS:, columns] != frames[k - 1][TITLE_ROWS:, columns], axis=2).sum()
            assert moved > least, f"frames {k - 1} and {k} differ in {moved} pixels of the {name} view"


def test_the_gif_rate_is_its_own_whatever_the_angles_rate(run_dir):
    """The angles' frames (output.fps) are resampled to GIF_FPS: 7, 30 or 50 frames per second of
    angles.csv give the same frames."""
    from klaw_ocp.config import load_config
    from klaw_ocp.walk import simulate_walk, walk_spec
    walk = simulate_walk(walk_spec(load_config(run_dir / "config.resolved.yaml")))
    counts = {fps: animation_figure(RunData.from_walk(walk, fps=fps)).frames for fps in (30.0, 50.0, 7.0)}
    with Image.open(run_dir / GIF_FILE) as gif:
        assert set(counts.values()) == {gif.n_frames}, counts


def test_footprints_lie_on_the_ground_where_each_foot_was_planted(run_dir):
    from klaw_ocp.io.body_plots import skeleton_at
    run = RunData.from_folder(run_dir)
    prints = footprints(run)
    events = run.summary["events"]
    strikes = [e for e in events if e["event"] == "heel_strike"]
    # every heel strike, the one that closes the walk, and the hind foot standing at the start
    assert len(prints) == len(strikes) + 2
    assert [p.t for p in prints] == sorted(p.t for p in prints)
    assert {p.side for p in prints[:2]} == {"right", "left"} and prints[0].t == prints[1].t == 0.0
    first = skeleton_at(run, [0.0])
    foot = float(np.linalg.norm(first.end_sites["r_toes"][0] - first.landmarks["r_heel"][0]))
    for p in prints:
        assert p.heel[1] == 0.0 and p.toe[1] == 0.0
        assert np.linalg.norm(p.toe - p.heel) == pytest.approx(foot, abs=1e-3)
        assert p.toe[0] - p.heel[0] > 0.95 * foot                  # pointing forward, nearly straight
    # where a foot lay flat (its foot flat after its heel strike), its footprint is that foot
    for strike in strikes:
        flat = next(e["time"] for e in events if e["side"] == strike["side"] and e["event"] == "foot_flat"
                    and e["time"] > strike["time"])
        p = next(p for p in prints if p.side == strike["side"] and p.t == strike["time"])
        at = skeleton_at(run, [flat])
        s = strike["side"][0]
        np.testing.assert_allclose(p.heel[[0, 2]], at.landmarks[f"{s}_heel"][0, [0, 2]], atol=2e-3)
        np.testing.assert_allclose(p.toe[[0, 2]], at.end_sites[f"{s}_toes"][0, [0, 2]], atol=2e-3)
        assert abs(at.landmarks[f"{s}_heel"][0, 1]) < 0.01 and abs(at.end_sites[f"{s}_toes"][0, 1]) < 0.01
    lines = {side: np.mean([p.heel[2] for p in prints if p.side == side]) for side in ("right", "left")}
    assert lines["right"] > 0.02 and lines["left"] < -0.02      # each foot on its own line (z right)


def test_output_animation_false_or_no_animation_writes_no_gif_and_removes_a_stale_one(tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["run", str(_config(tmp_path)), "--out", str(out), "--quiet", "--no-plots"]) == 0
    assert not (out / GIF_FILE).exists()                   # output.animation's default: off
    (out / GIF_FILE).write_bytes(b"GIF89a from another walk")
    on = _config(tmp_path, animation=True)
    assert main(["run", str(on), "--out", str(out), "--quiet", "--no-animation"]) == 0
    assert not (out / GIF_FILE).exists()                   # switched off, and the stale one gone
    assert {"legs.png", "body.png"} <= {p.name for p in (out / "plots").iterdir()}   # plots unaffected
    assert GIF_FILE not in capsys.readouterr().out
    assert main(["run", str(on), "--out", str(out), "--quiet", "--no-plots", "--set", "output.animation=false"]) == 0
    assert not (out / GIF_FILE).exists()


def test_plot_redraws_the_gif_from_the_results_folder_without_solving(run_dir, tmp_path, monkeypatch, capsys):
    import klaw_ocp.walk
    monkeypatch.setattr(klaw_ocp.walk, "simulate_walk", lambda *a, **k: pytest.fail("solved"))
    redrawn = tmp_path / "redrawn"
    assert main(["plot", str(run_dir), "--out", str(redrawn), "--animation"]) == 0
    assert GIF_FILE in capsys.readouterr().out
    with Image.open(redrawn / GIF_FILE) as again, Image.open(run_dir / GIF_FILE) as first:
        assert again.n_frames == first.n_frames
    assert main(["plot", str(run_dir), "--out", str(tmp_path / "plain")]) == 0
    assert not (tmp_path / "plain" / GIF_FILE).exists()    # only when asked for


def test_the_gif_is_written_atomically(run_dir, tmp_path, monkeypatch):
    """A failure while writing leaves the previous walk.gif as it was and no temporary file."""
    import klaw_ocp.io.writers as writers                  # the GIF is renamed into place there (atomic_path)
    target = tmp_path / GIF_FILE
    target.write_bytes(b"the previous walk.gif")

    def broken_replace(src, dst):
        raise OSError("disk full")
    monkeypatch.setattr(writers.os, "replace", broken_replace)
    with pytest.raises(OSError, match="disk full"):
        write_animation(RunData.from_folder(run_dir), target)
    assert target.read_bytes() == b"the previous walk.gif"
    assert [p.name for p in tmp_path.iterdir()] == [GIF_FILE]


def test_no_body_no_gif(run_dir, tmp_path):
    run = RunData.from_folder(run_dir)
    run.angles = None                                       # a results folder from before angles.csv
    assert write_animation(run, tmp_path / GIF_FILE) is None
    assert not (tmp_path / GIF_FILE).exists()
