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
from klaw_ocp.figures.animation import GIF_FILE, GIF_FPS, animation_figure, footprints, write_animation
from klaw_ocp.figures.plot_style import LEG_COLOURS
from klaw_ocp.result_files.run_data import RunData

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
    from klaw_ocp.figures.body_plots import skeleton_at
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
    import klaw_ocp.result_files.atomic as atomic    # the GIF is renamed into place there (atomic_path)
    target = tmp_path / GIF_FILE
    target.write_bytes(b"the previous walk.gif")

    def broken_replace(src, dst):
        raise OSError("disk full")
    monkeypatch.setattr(atomic.os, "replace", broken_replace)
    with pytest.raises(OSError, match="disk full"):
        write_animation(RunData.from_folder(run_dir), target)
    assert target.read_bytes() == b"the previous walk.gif"
    assert [p.name for p in tmp_path.iterdir()] == [GIF_FILE]


def test_no_body_no_gif(run_dir, tmp_path):
    run = RunData.from_folder(run_dir)
    run.angles = None                                       # a results folder from before angles.csv
    assert write_animation(run, tmp_path / GIF_FILE) is None
    assert not (tmp_path / GIF_FILE).exists()


# -- a long walk: memory and drawing that do not grow with it (issue 32) -----------------------------
def test_frames_go_to_the_file_as_they_are_drawn_and_decode_as_given():
    """GifStream writes each frame when the next one comes: it holds two, whatever the length."""
    import io
    from klaw_ocp.figures.gif_file import GifStream
    frames = []
    for x in (0, 4, 8, 8, 12, 16):               # a square moving right, standing still once
        frame = np.full((30, 40, 4), 255, np.uint8)
        frame[5:15, 3 + x:13 + x, :3] = (0, 114, 178)
        frame[20:, :, :3] = (140, 109, 70)
        frames.append(frame)
    assert np.array_equal(frames[2], frames[3])               # shown twice as long, as one frame
    handle = io.BytesIO()
    gif = GifStream(handle, GIF_FPS)
    written = []
    for frame in frames:
        gif.add_frame(frame)
        written.append(len(handle.getvalue()))
    gif.finish()
    # the header comes with the first frame, each frame when the next one differs from it
    assert written[0] > 0 and written[1] > written[0] and written[2] > written[1]
    assert written[3] == written[2] and written[4] > written[3] and written[5] > written[4]
    assert len(handle.getvalue()) > written[5] and gif.frames == 5
    with Image.open(handle) as decoded:
        assert decoded.n_frames == 5 and decoded.info.get("loop") == 0
        durations, pixels = [], []
        for k in range(decoded.n_frames):
            decoded.seek(k)
            durations.append(decoded.info["duration"])
            pixels.append(np.asarray(decoded.convert("RGB")))
    assert durations == [80, 80, 160, 80, 80]
    for shown, frame in zip(pixels, [frames[0], frames[1], frames[2], frames[4], frames[5]]):
        assert np.array_equal(shown, frame[..., :3])


def test_write_animation_streams_the_frames_into_its_temporary_file(run_dir, tmp_path, monkeypatch):
    import klaw_ocp.figures.animation as animation
    original = animation.animation_figure
    sizes = []

    def recording(run, fps=GIF_FPS):
        made = original(run, fps)
        move = made.frame

        def frame(i):
            sizes.append(sum(p.stat().st_size for p in tmp_path.glob(f".{GIF_FILE}.*")))
            move(i)
        made.frame = frame
        return made
    monkeypatch.setattr(animation, "animation_figure", recording)
    write_animation(RunData.from_folder(run_dir), tmp_path / GIF_FILE)
    assert len(sizes) >= 10 and sizes[0] == 0
    assert all(b > a for a, b in zip(sizes[2:], sizes[3:]))     # a frame reaches the file while the next is drawn


def test_poses_and_labels_in_chunks_give_the_same_gif(run_dir, tmp_path, monkeypatch):
    import klaw_ocp.figures.animation as animation
    from klaw_ocp.figures.gif_pixels import MovingLabels
    run = RunData.from_folder(run_dir)
    write_animation(run, tmp_path / "whole.gif")
    monkeypatch.setattr(animation, "POSE_CHUNK", 4)
    monkeypatch.setattr(MovingLabels, "BLOCK", 1)
    write_animation(run, tmp_path / "chunks.gif")
    assert (tmp_path / "chunks.gif").read_bytes() == (tmp_path / "whole.gif").read_bytes()


def test_a_frame_of_a_long_walk_draws_only_what_its_views_show():
    """A 198-step walk (110 s): a frame's footprints, ground ticks, path, poses and metre labels are
    those about the walker, so that a frame costs the same at any length of walk."""
    from pathlib import Path
    from _long_walks import tiled
    from klaw_ocp.figures.animation import POSE_CHUNK
    from klaw_ocp.walk import simulate_walk
    natural = RunData.from_walk(simulate_walk(Path(__file__).resolve().parents[1] / "configs" / "natural_walk.yaml"))
    long = tiled(natural, 9)
    animation = animation_figure(long)
    assert animation.frames == math.floor(long.duration * GIF_FPS + 1e-9) + 1 > 1300
    for i in (animation.frames // 2, animation.frames - 1):
        animation.frame(i)
        animation.pixels()
        for drawn in animation.blitter.moving:
            artist = getattr(drawn, "artist", drawn)
            if hasattr(artist, "get_segments"):
                assert len(artist.get_segments()) <= 40, artist
            elif hasattr(artist, "get_xdata"):
                assert len(artist.get_xdata()) <= 120, artist
        labels = animation.overlays[0]
        assert 1 <= len(labels.shown()) <= 4 and len(labels.blocks) <= 2
    assert all(len(points) <= POSE_CHUNK for points in animation.poses.chains.values())


def test_a_metre_label_is_drawn_whole_while_its_tick_is_in_the_side_view_and_not_at_all_after(run_dir):
    animation = animation_figure(RunData.from_folder(run_dir))
    labels = animation.overlays[0]
    side = labels.ax
    box = side.bbox
    metre = 1.0
    k = int(np.flatnonzero(np.isclose(labels.values, metre))[0])
    _, _, (_, _, _, alpha) = labels._block(k // labels.BLOCK)[k % labels.BLOCK]
    ink_width = int(np.any(alpha[..., 0] > 0.5, axis=0).sum())
    per_px = (side.get_xlim()[1] - side.get_xlim()[0]) / box.width
    for px_inside in (2.0, -2.0):                     # the tick 2 px inside the view's right edge, then outside
        right = metre + px_inside * per_px
        side.set_xlim(right - (box.width * per_px), right)
        labels.place()
        canvas = np.full((int(animation.fig.bbox.height), int(animation.fig.bbox.width), 3), 255, np.uint8)
        labels.blend(canvas)
        near_edge = np.any(canvas[:, int(box.x1) - 25:] < 170, axis=(0, 2))   # alpha > 0.5 over white
        if px_inside > 0:                             # whole, reaching past the edge as an axis' tick label does
            assert near_edge.sum() == ink_width and near_edge[25:].any()
        else:
            assert not near_edge.any()
