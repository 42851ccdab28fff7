"""Import walk.bvh into Blender headless with its bundled importer (io_anim_bvh) and print what an
animator would see, as JSON (docs/animation.md, section "Blender").

Run it with Blender (no numpy inside; Blender's own Python, 3.11 on Debian 12's Blender 3.4)::

    blender -b --factory-startup --python tests/blender_import_check.py -- results/x/walk.bvh \\
        --events results/x/events.csv

or with any Python, which starts ``blender`` (on PATH, or ``--blender PATH``) itself::

    python tests/blender_import_check.py results/x/walk.bvh --events results/x/events.csv

Printed on one line after ``BLENDER_BVH_CHECK``: the number of bones; the scene's frame rate and
the action's keyed frames; the root's mean speed (its horizontal travel from the first to the last
frame over the duration, m/s) and direction in Blender's axes; the rest pose's height (the top of
the head, C1's tail, above the lowest toe tip); with ``--events`` (klaw-ocp run's events.csv) each
stance foot's drift while flat (from its ``foot_flat`` to its ``heel_off``: the largest distance of
the ankle, the first metatarsal head (the ankle bone's tail) and the toe tip (the toes bone's
tail) from where they were at the window's first frame, mm); with ``--frames 0,10`` every bone's
head and every leaf bone's tail at those BVH frames (0-based), in Blender's world axes (m).

Import settings (the dialog's defaults except the two "Update Scene" boxes): scale 1, forward
-Z, up Y, Euler (Native) rotation, frame 1 = the BVH's first frame, no FPS scaling, Update Scene
FPS and Update Scene Duration on. Blender 3.4's importer opens the file with mode 'rU', which
Python 3.11 refuses (``ValueError: invalid mode: 'rU'``): this script maps 'rU' to 'r' in
``builtins.open`` for the import.
"""
from __future__ import annotations

import argparse
import json
import shutil
import subprocess
import sys

MARKER = "BLENDER_BVH_CHECK"
IMPORT_SETTINGS = dict(axis_forward="-Z", axis_up="Y", global_scale=1.0, frame_start=1, use_fps_scale=False,
                       update_scene_fps=True, update_scene_duration=True, rotate_mode="NATIVE")
FEET = {"right": "r", "left": "l"}


def _arguments(argv):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("bvh")
    p.add_argument("--events", help="klaw-ocp run's events.csv: report each stance foot's drift while flat")
    p.add_argument("--frames", default="", help="comma-separated BVH frames (0-based) whose bone positions to print")
    p.add_argument("--json", help="also write the result to this file")
    p.add_argument("--blender", default="blender", help="the Blender executable (outside Blender only)")
    return p.parse_args(argv)


# -- outside Blender -----------------------------------------------------------------------------------
def run_in_blender(bvh, events=None, frames=(), blender="blender", timeout=600) -> dict:
    """Run this script in ``blender -b`` on ``bvh``; returns the printed dict (RuntimeError with
    Blender's output if it printed none)."""
    exe = shutil.which(blender)
    if exe is None:
        raise FileNotFoundError(f"blender: {blender!r} is not on PATH")
    cmd = [exe, "-b", "--factory-startup", "--python-exit-code", "1", "--python", __file__, "--", str(bvh)]
    if events is not None:
        cmd += ["--events", str(events)]
    if frames:
        cmd += ["--frames", ",".join(str(int(k)) for k in frames)]
    done = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    for line in done.stdout.splitlines():
        if line.startswith(MARKER + " "):
            return json.loads(line[len(MARKER) + 1:])
    raise RuntimeError(f"blender printed no {MARKER} line (exit {done.returncode}):\n"
                       f"{done.stdout[-3000:]}\n{done.stderr[-3000:]}")


# -- inside Blender ------------------------------------------------------------------------------------
def _flat_windows(events_path, duration):
    """(side, start s, end s) from each foot_flat to the same foot's next heel_off (or the end)."""
    import csv
    with open(events_path, newline="", encoding="utf-8") as handle:
        events = [(float(r["time"]), r["side"], r["event"]) for r in csv.DictReader(handle)]
    events.sort()
    windows = []
    for k, (t, side, event) in enumerate(events):
        if event != "foot_flat":
            continue
        end = next((u for u, s, e in events[k + 1:] if s == side and e == "heel_off"), duration)
        windows.append((side, t, min(end, duration)))
    return windows


def _import(path):
    import builtins

    import bpy
    original = builtins.open

    def open_without_u(file, mode="r", *args, **kwargs):
        return original(file, "r" if mode == "rU" else mode, *args, **kwargs)
    builtins.open = open_without_u
    try:
        bpy.ops.wm.read_factory_settings(use_empty=True)
        result = bpy.ops.import_anim.bvh(filepath=path, **IMPORT_SETTINGS)
    finally:
        builtins.open = original
    if result != {"FINISHED"}:
        raise RuntimeError(f"import_anim.bvh returned {result}")
    armatures = [o for o in bpy.context.scene.objects if o.type == "ARMATURE"]
    if len(armatures) != 1:
        raise RuntimeError(f"expected one armature, got {len(armatures)}")
    return armatures[0]


def check(args) -> dict:
    import bpy
    arm = _import(args.bvh)
    scene = bpy.context.scene
    bones = arm.data.bones
    first, last = (int(round(v)) for v in arm.animation_data.action.frame_range)
    frames = last - first + 1
    fps = scene.render.fps / scene.render.fps_base
    frame_time = 1.0 / fps
    world = arm.matrix_world

    def head(name):
        return world @ arm.pose.bones[name].head

    def tail(name):
        return world @ arm.pose.bones[name].tail

    leaves = [b.name for b in bones if not b.children]
    rest_tips = {name: list(world @ bones[name].tail_local) for name in leaves}
    toe_tips = [rest_tips[name][2] for name in ("r_toes", "l_toes") if name in rest_tips]
    # every frame, the root and the feet
    track = {"root": [], **{f"{s}_{p}": [] for s in FEET.values() for p in ("ankle", "metatarsal", "toe_tip")}}
    wanted = {int(k) for k in args.frames.split(",") if k.strip()}
    positions = {}
    for k in range(frames):
        scene.frame_set(first + k)
        track["root"].append(head("pelvis"))
        for s in FEET.values():
            track[f"{s}_ankle"].append(head(f"{s}_ankle"))
            track[f"{s}_metatarsal"].append(tail(f"{s}_ankle"))
            track[f"{s}_toe_tip"].append(tail(f"{s}_toes"))
        if k in wanted:
            frame = {b.name: list(head(b.name)) for b in bones}
            frame.update({f"{name}_end": list(tail(name)) for name in leaves})
            positions[str(k)] = frame
    duration = (frames - 1) * frame_time
    travel = track["root"][-1] - track["root"][0]
    horizontal = (travel.x ** 2 + travel.y ** 2) ** 0.5
    out = {"blender": bpy.app.version_string, "file": args.bvh, "settings": IMPORT_SETTINGS,
           "bones": len(bones), "fps": fps, "fps_setting": [scene.render.fps, scene.render.fps_base],
           "frames": frames, "keyed_frames": [first, last], "scene_frames": [scene.frame_start, scene.frame_end],
           "duration_s": duration,
           "root_speed_m_s": horizontal / duration if duration > 0 else None,
           "root_direction": [v / horizontal for v in (travel.x, travel.y)] if horizontal > 0 else None,
           "height_m": rest_tips["C1"][2] - min(toe_tips) if "C1" in rest_tips and toe_tips else None,
           "head_top_rest": rest_tips.get("C1"), "toe_tips_rest_z": toe_tips}
    if args.events:
        windows = []
        for side, t0, t1 in _flat_windows(args.events, duration):
            ks = [k for k in range(frames) if t0 - 1e-9 <= k * frame_time <= t1 + 1e-9]
            if len(ks) < 2:
                continue
            s = FEET[side]
            drift = {}
            for point in ("ankle", "metatarsal", "toe_tip"):
                path = track[f"{s}_{point}"]
                drift[point] = 1000 * max((path[k] - path[ks[0]]).length for k in ks)
            heights = [track[f"{s}_toe_tip"][k].z for k in ks]
            windows.append({"side": side, "from_s": t0, "to_s": t1, "frames": [ks[0], ks[-1]],
                            "drift_mm": drift, "toe_tip_height_mm": [1000 * min(heights), 1000 * max(heights)]})
        out["foot_flat"] = windows
        out["foot_drift_max_mm"] = max((max(w["drift_mm"].values()) for w in windows), default=None)
    if wanted:
        out["positions"] = positions
    return out


def main(argv) -> int:
    args = _arguments(argv)
    try:
        import bpy  # noqa: F401
        in_blender = True
    except ImportError:       # plain Python: run ourselves inside Blender
        in_blender = False
    result = check(args) if in_blender else run_in_blender(
        args.bvh, args.events, [k for k in args.frames.split(",") if k.strip()], args.blender)
    text = json.dumps(result)
    if args.json:
        with open(args.json, "w", encoding="utf-8") as handle:
            handle.write(json.dumps(result, indent=2) + "\n")
    print(f"{MARKER} {text}", flush=True)
    return 0


if __name__ == "__main__":
    arguments = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
    sys.exit(main(arguments))
