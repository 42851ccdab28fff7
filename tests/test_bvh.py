"""walk.bvh (docs/animation.md): the 37-joint skeleton in the one token layout Blender's importer
reads, read back by an independent reader (bvhio) and by our own (klaw_ocp.result_files.bvh.read_bvh), whose
forward kinematics reproduce the skeleton's joint positions; and, where Blender is installed,
imported into Blender headless (tests/blender_import_check.py)."""
import math
import os
import re
import shutil
import stat
import sys
from pathlib import Path

import numpy as np
import pytest

from klaw_ocp.body import Body
from klaw_ocp.body_motion.skeleton import ANGLE_NAMES, JOINTS, forward_kinematics
from klaw_ocp.result_files.bvh import AXES, BVH_FILE, Bvh, bvh_text, read_bvh, write_bvh
from klaw_ocp.result_files.run_data import RunData
from klaw_ocp.result_files import render_run, write_rendered
from klaw_ocp.result_files.tables import events_csv

FPS = 30.0
CONFIG = {"name": "t", "body": {"height": 1.8, "mass": 80}, "walk": {"speed": 5.0, "steps": 3}}
BODY = Body(height=1.8, mass=80)
LEAVES = {"r_toes", "l_toes", "C1", "r_elbow", "l_elbow"}
ROOT_CHANNELS = ["Xposition", "Yposition", "Zposition", "Xrotation", "Zrotation", "Yrotation"]
JOINT_CHANNELS = ["Xrotation", "Zrotation", "Yrotation"]
#: BVH axes -> Blender's after the import with forward -Z, up Y: X stays, -Z becomes +Y, Y becomes +Z.
BVH_TO_BLENDER = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])


@pytest.fixture(scope="module")
def walk():
    from klaw_ocp import simulate_walk
    return simulate_walk(CONFIG)


@pytest.fixture(scope="module")
def motion(walk):
    from klaw_ocp.body_motion import body_motion
    return body_motion(walk, FPS)


@pytest.fixture(scope="module")
def written(motion, tmp_path_factory):
    path = tmp_path_factory.mktemp("bvh") / BVH_FILE
    write_bvh(path, motion, BODY, fps=FPS)
    return path


def skeleton_in_bvh_axes(table: dict) -> tuple:
    """The skeleton's own forward kinematics of angles.csv's columns, mapped into BVH axes:
    joint positions (n, 37, 3) and end sites (leaf -> (n, 3))."""
    root = np.column_stack([table["root_x"], table["root_y"], table["root_z"]])
    angles = np.radians(np.column_stack([table[name] for name in ANGLE_NAMES]))
    frames = forward_kinematics(BODY, root, angles)
    return frames.positions @ AXES.T, {k: v @ AXES.T for k, v in frames.end_sites.items()}


def significant_digits(number: str) -> int:
    return len(number.lstrip("+-").split("e")[0].replace(".", "").lstrip("0"))


# -- the text -----------------------------------------------------------------------------------------
def test_the_text_has_the_one_layout_blenders_importer_reads(written, motion):
    lines = written.read_text(encoding="utf-8").splitlines()
    stripped = [line.strip() for line in lines]
    assert lines[0] == "HIERARCHY"
    motion_at = stripped.index("MOTION")
    hierarchy = stripped[1:motion_at]
    # every brace alone on its line, balanced
    depth = 0
    for line in hierarchy:
        assert ("{" not in line and "}" not in line) or line in ("{", "}"), line
        depth += (line == "{") - (line == "}")
        assert depth >= 0
    assert depth == 0
    # ROOT/JOINT: "{" on the next line, then OFFSET x y z, then CHANNELS n ...
    names, channels, leaves_with_end = [], {}, set()
    for k, line in enumerate(hierarchy):
        tokens = line.split()
        if tokens[0] in ("ROOT", "JOINT"):
            assert (tokens[0] == "ROOT") == (k == 0) and len(tokens) == 2
            names.append(tokens[1])
            assert hierarchy[k + 1] == "{"
            offset = hierarchy[k + 2].split()
            assert offset[0] == "OFFSET" and len(offset) == 4 and all(math.isfinite(float(v)) for v in offset[1:])
            chans = hierarchy[k + 3].split()
            assert chans[0] == "CHANNELS" and int(chans[1]) == len(chans) - 2
            channels[tokens[1]] = chans[2:]
        elif line == "End Site":
            assert hierarchy[k + 1] == "{" and hierarchy[k + 2].split()[0] == "OFFSET" and hierarchy[k + 3] == "}"
            # the End Site belongs to the joint opened last whose block is still open
            opened = [h.split()[1] for h in hierarchy[:k] if h.split()[0] in ("ROOT", "JOINT")]
            leaves_with_end.add(opened[-1])
    assert names == [j.name for j in JOINTS] and len(names) == 37
    assert leaves_with_end == LEAVES == {j.name for j in JOINTS} - {j.parent for j in JOINTS}
    assert hierarchy.count("End Site") == len(LEAVES)
    assert channels["pelvis"] == ROOT_CHANNELS
    assert all(channels[name] == JOINT_CHANNELS for name in names[1:])
    # MOTION: frame count, a frame time of at least 10 significant digits that is 1/30 s, the values
    n = len(motion.t)
    assert stripped[motion_at + 1] == f"Frames: {n}"
    frame_time = stripped[motion_at + 2].split()
    assert frame_time[:2] == ["Frame", "Time:"] and len(frame_time) == 3
    assert significant_digits(frame_time[2]) >= 10 and float(frame_time[2]) == 1 / 30
    rows = stripped[motion_at + 3:]
    assert len(rows) == n and all(len(r.split()) == 6 + 3 * 36 for r in rows)


def test_a_frame_rate_the_times_contradict_is_refused(motion):
    with pytest.raises(ValueError, match="equally spaced"):
        bvh_text(motion, BODY, fps=12.5)
    table = motion.table()
    table["time"] = table["time"] * 30 / 12.5            # the same frames at 12.5 fps
    line = next(l for l in bvh_text(table, BODY, 12.5).splitlines() if l.startswith("Frame Time:"))
    assert float(line.split()[2]) == 0.08 and significant_digits(line.split()[2]) >= 10
    uneven = dict(table, time=table["time"] + np.where(np.arange(len(table["time"])) == 5, 0.01, 0.0))
    with pytest.raises(ValueError, match="frame 5"):
        bvh_text(uneven, BODY, 12.5)


def test_the_frame_rate_is_the_runs_never_one_guessed_from_the_times(walk, motion):
    # a RunData carries the rate it was built at; a table or a BodyMotion has none, so it is asked for
    run = RunData.from_walk(walk, fps=12.5)
    assert run.fps == 12.5
    assert "Frame Time: 0.080000000000000002\n" in bvh_text(run)
    with pytest.raises(ValueError, match="fps: required"):
        bvh_text(motion, BODY)


# -- read back: bvhio and ours ----------------------------------------------------------------------
def test_bvhio_reads_it_back_and_its_kinematics_are_the_skeletons(written, motion):
    bvhio = pytest.importorskip("bvhio")    # a test dependency (pyproject's test extra)
    container = bvhio.readAsBvh(str(written))
    layout = container.Root.layout()
    assert [j.Name for j, _, _ in layout] == [j.name for j in JOINTS]
    assert [j.Channels for j, _, _ in layout] == [ROOT_CHANNELS] + [JOINT_CHANNELS] * 36
    assert {j.Name for j, _, _ in layout if not j.Children} == LEAVES
    assert container.FrameCount == len(motion.t) and container.FrameTime == 1 / 30
    expected, _ = skeleton_in_bvh_axes(motion.table())
    hierarchy = bvhio.readAsHierarchy(str(written))
    n = len(motion.t)
    for k in (0, n // 4, n // 2, 3 * n // 4, n - 1):
        hierarchy.loadPose(k)
        got = np.array([list(j.PositionWorld) for j, _, _ in hierarchy.layout()])
        # bvhio computes in float32 (PyGLM vec3/quat): 2 m to ~2.4e-7 m per operation, over a
        # 30-joint chain; measured at most 1.2e-6 m on this walk, against 1e-9 m in double precision
        np.testing.assert_allclose(got, expected[k], atol=5e-6, rtol=0, err_msg=f"frame {k}")


def test_our_reader_reads_it_back_and_its_kinematics_are_the_skeletons(written, motion):
    bvh = read_bvh(written)
    n = len(motion.t)
    assert bvh.names == [j.name for j in JOINTS] and len(bvh.joints) == 37
    assert [j.channels for j in bvh.joints] == [tuple(ROOT_CHANNELS)] + [tuple(JOINT_CHANNELS)] * 36
    assert [bvh.names[j.parent] if j.parent >= 0 else None for j in bvh.joints] == [j.parent for j in JOINTS]
    assert {j.name for j in bvh.joints if j.end_site is not None} == LEAVES
    assert bvh.frames == n and bvh.frame_time == 1 / 30 and 1 / bvh.frame_time == 30.0
    expected, ends = skeleton_in_bvh_axes(motion.table())
    frames = [0, n // 4, n // 2, 3 * n // 4, n - 1]
    positions, end_sites = bvh.forward_kinematics(frames)
    np.testing.assert_allclose(positions, expected[frames], atol=1e-6, rtol=0)
    for leaf in LEAVES:
        np.testing.assert_allclose(end_sites[leaf], ends[leaf][frames], atol=1e-6, rtol=0, err_msg=leaf)
    # the whole walk, and the rest pose: the top of the head at the body's height, the soles at 0
    np.testing.assert_allclose(bvh.forward_kinematics()[0], expected, atol=1e-6, rtol=0)
    still = np.zeros((1, bvh.motion.shape[1]))
    still[0, :3] = bvh.joints[0].offset                 # the root at its rest offset, every angle 0
    _, rest_ends = Bvh(bvh.joints, 1.0, still).forward_kinematics()
    assert rest_ends["C1"][0, 1] == pytest.approx(1.8, abs=1e-9)
    assert rest_ends["r_toes"][0, 1] == pytest.approx(0.0, abs=1e-9)


def test_every_angle_maps_onto_its_bvh_channel():
    """Random angles on every one of the 56 (the walk leaves the pelvis level and square): BVH's
    forward kinematics is still the skeleton's, so each angle reaches its channel with its axis
    and sign."""
    rng = np.random.default_rng(23)
    n = 6
    table = {"time": np.arange(n) / FPS, "root_x": rng.uniform(-1, 3, n), "root_y": rng.uniform(0.8, 1, n),
             "root_z": rng.uniform(-0.1, 0.1, n)}
    table.update({name: rng.uniform(-40, 40, n) for name in ANGLE_NAMES})
    expected, ends = skeleton_in_bvh_axes(table)
    positions, end_sites = read_bvh(bvh_text(table, BODY, FPS)).forward_kinematics()
    np.testing.assert_allclose(positions, expected, atol=1e-6, rtol=0)
    for leaf in LEAVES:
        np.testing.assert_allclose(end_sites[leaf], ends[leaf], atol=1e-6, rtol=0, err_msg=leaf)
    # and one angle at a time lands on one channel only
    for name in ANGLE_NAMES:
        one = {c: np.zeros(1) for c in table}
        one[name] = np.array([10.0])
        values = np.array(bvh_text(one, BODY, FPS).splitlines()[-1].split(), dtype=float)
        assert np.count_nonzero(values) == 1, name


def test_the_axes_are_a_proper_rotation_with_the_walk_along_plus_z(written, motion):
    assert np.allclose(AXES @ AXES.T, np.eye(3)) and np.linalg.det(AXES) == pytest.approx(1.0)
    assert np.allclose(AXES @ [1, 0, 0], [0, 0, 1])     # forward -> +Z
    assert np.allclose(AXES @ [0, 1, 0], [0, 1, 0])     # up -> +Y
    assert np.allclose(AXES @ [0, 0, 1], [-1, 0, 0])    # right -> -X (+X is the walker's left)
    positions, _ = read_bvh(written).forward_kinematics()
    travel = positions[-1, 0] - positions[0, 0]
    assert travel[2] > 1.5 and abs(travel[0]) < 0.05 and abs(travel[1]) < 0.05
    right_hip = positions[0, [j.name for j in JOINTS].index("r_hip")] - positions[0, 0]
    assert right_hip[0] < 0                             # the right hip at -X


# -- the inputs: a finished run's folder, a walk in memory ------------------------------------------
def test_a_finished_runs_folder_gives_the_same_file(walk, written, tmp_path):
    run = RunData.from_walk(walk, fps=FPS)
    out = tmp_path / "run"
    write_rendered(render_run(run), out)
    from_folder = RunData.from_folder(out)
    assert from_folder.fps == FPS
    path = write_bvh(out / BVH_FILE, from_folder)             # the body and fps from summary.json
    assert path == out / BVH_FILE
    assert bvh_text(run, fps=FPS) == written.read_text(encoding="utf-8")
    # the folder's angles.csv keeps 12 significant digits: the same file to its last decimal or so
    on_disk, in_memory = read_bvh(path), read_bvh(written)
    head = written.read_text(encoding="utf-8").split("Frame Time:")[0]
    assert path.read_text(encoding="utf-8").startswith(head)
    assert on_disk.frame_time == in_memory.frame_time and on_disk.frames == in_memory.frames
    np.testing.assert_allclose(on_disk.motion, in_memory.motion, atol=2e-9, rtol=0)
    # written atomically with the user's normal mode, no temporary file left
    mask = os.umask(0)
    os.umask(mask)
    assert stat.S_IMODE(path.stat().st_mode) == 0o666 & ~mask
    assert not [p for p in out.iterdir() if p.name.startswith(f".{BVH_FILE}")]


def test_bad_inputs_are_refused_in_one_line(motion):
    table = motion.table()
    with pytest.raises(ValueError, match="body: required"):
        bvh_text(table, fps=FPS)
    with pytest.raises(ValueError, match="missing column"):
        bvh_text({k: v for k, v in table.items() if k != "r_knee_flexion"}, BODY, FPS)
    with pytest.raises(ValueError, match="NaN"):
        bvh_text(dict(table, r_knee_flexion=np.full(len(table["time"]), np.nan)), BODY, FPS)
    with pytest.raises(ValueError, match="no angles"):
        bvh_text(RunData(name="old", summary={"body": {"height": 1.8, "mass": 80}}, table={}))
    with pytest.raises(ValueError, match="fps"):
        bvh_text(table, BODY, fps=0)


@pytest.mark.parametrize("change, message", [
    (lambda t: t.replace("ROOT pelvis\n{", "ROOT pelvis {", 1), "expected 2 tokens"),
    (lambda t: t.replace("JOINT r_hip\n\t{", "JOINT r_hip\n\t{ }", 1), "expected 1 tokens"),
    (lambda t: re.sub(r"(\tOFFSET [^\n]*)\n(\t*CHANNELS [^\n]*)", r"\2\n\1", t, count=1), "expected 'OFFSET'"),
    (lambda t: t.replace("\t\t\t\t\tEnd Site\n\t\t\t\t\t{\n\t\t\t\t\t\tOFFSET 0.000000000 0.000000000 "
                         "0.089280000\n\t\t\t\t\t}\n", "", 1), "no End Site"),
    (lambda t: t.replace("CHANNELS 3 Xrotation Zrotation Yrotation", "CHANNELS 3 Xrotation Zrotation", 1),
     "bad CHANNELS"),
    (lambda t: t.rsplit("\n", 2)[0] + "\n", "ended early"),
    (lambda t: t.replace("HIERARCHY", "HIERARCHY x", 1), "expected 1 tokens"),
])
def test_our_reader_refuses_another_layout(written, change, message):
    text = written.read_text(encoding="utf-8")
    assert change(text) != text
    with pytest.raises(ValueError, match=message):
        read_bvh(change(text))


# -- Blender -----------------------------------------------------------------------------------------
def _flat_windows(summary: dict, duration: float) -> list:
    events = sorted((e["time"], e["side"], e["event"]) for e in summary["events"])
    out = []
    for k, (t, side, event) in enumerate(events):
        if event == "foot_flat":
            end = next((u for u, s, e in events[k + 1:] if s == side and e == "heel_off"), duration)
            out.append((side, t, min(end, duration)))
    return out


@pytest.mark.skipif(shutil.which("blender") is None, reason="Blender is not installed (blender not on PATH)")
def test_blender_imports_the_walk_with_its_size_speed_and_planted_feet(walk, motion, written, tmp_path):
    sys.path.insert(0, str(Path(__file__).parent))
    try:
        from blender_import_check import run_in_blender
    finally:
        sys.path.pop(0)
    run = RunData.from_walk(walk, fps=FPS)
    events = tmp_path / "events.csv"
    events.write_text(events_csv(run.summary), encoding="utf-8")
    n = len(motion.t)
    frames = [0, n // 3, 2 * n // 3, n - 1]
    got = run_in_blender(written, events, frames)
    assert got["bones"] == 37
    assert got["fps"] == pytest.approx(30.0, abs=1e-9) and got["fps_setting"] == [30, 1.0]
    assert got["frames"] == n and got["keyed_frames"] == [1, n]
    # the walk's speed: the root's travel over the frames, as in angles.csv
    table = motion.table()
    travel = math.hypot(table["root_x"][-1] - table["root_x"][0], table["root_z"][-1] - table["root_z"][0])
    speed = travel / (table["time"][-1] - table["time"][0])
    assert got["root_speed_m_s"] == pytest.approx(speed, rel=1e-5)
    assert got["root_speed_m_s"] == pytest.approx(5.0 / 3.6, rel=0.01)      # the config's 5 km/h
    assert got["root_direction"] == pytest.approx([0.0, -1.0], abs=1e-3)     # towards Blender's -Y
    assert got["height_m"] == pytest.approx(1.8, abs=1e-5)
    # every joint where the skeleton puts it (Blender computes in float32)
    expected, ends = skeleton_in_bvh_axes(table)
    for k in frames:
        pose = got["positions"][str(k)]
        for j, joint in enumerate(JOINTS):
            np.testing.assert_allclose(pose[joint.name], BVH_TO_BLENDER @ expected[k, j], atol=1e-5,
                                       err_msg=f"{joint.name} frame {k}")
        for leaf in LEAVES:
            np.testing.assert_allclose(pose[f"{leaf}_end"], BVH_TO_BLENDER @ ends[leaf][k], atol=1e-5)
    # each stance foot planted while flat: the sole's points still, the ankle as in the skeleton
    windows = got["foot_flat"]
    assert len(windows) == len(_flat_windows(run.summary, (n - 1) / FPS)) >= 3
    index = {j.name: i for i, j in enumerate(JOINTS)}
    for w in windows:
        s = w["side"][0]
        ks = np.arange(w["frames"][0], w["frames"][1] + 1)
        own = {"ankle": expected[ks, index[f"{s}_ankle"]], "metatarsal": expected[ks, index[f"{s}_toes"]],
               "toe_tip": ends[f"{s}_toes"][ks]}
        for point, path in own.items():
            drift = 1000 * np.linalg.norm(path - path[0], axis=1).max()
            assert w["drift_mm"][point] == pytest.approx(drift, abs=0.01), (w, point)
        assert w["drift_mm"]["metatarsal"] < 0.01 and w["drift_mm"]["toe_tip"] < 0.01
        assert max(abs(v) for v in w["toe_tip_height_mm"]) < 0.01
    assert got["foot_drift_max_mm"] < 3.0
