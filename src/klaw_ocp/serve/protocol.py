"""The playground's messages (docs/serve.md, "Messages"): what a page may send, checked into one-line
refusals, and what the server sends back, in JSON.

From the page:

- ``{"type": "start", "settings": {PATH: value, ...}}``: a new walk; PATH is one of
  :data:`SETTINGS` (the config's own paths, as ``klaw-ocp run --set`` takes them) or
  ``attributes.NAME``; a bad value is refused with the config's one line and the walk on screen
  goes on;
- ``{"type": "set", "values": {"speed": 4.2, "step_length": 0.7, "attributes.pelvic_list": 8}}``:
  new locomotion parameters (a subset of speed km/h, step_length m, step_frequency steps/min,
  completed with eq. 1) and values of the attributes that may change per step
  (``attributes.NAME``, NAME in :data:`~klaw_ocp.gait.attributes.STEP_ATTRIBUTES`), from the next
  step that can change;
- ``{"type": "stop"}``: end the walk at rest; ``{"type": "need", "step": k}``: the page will show
  step k soon (it asks while the step before is on screen; the server solves nothing further);
  ``{"type": "export"}``: the ended walk as walk.bvh and as the config that ``klaw-ocp run``
  solves into it.
"""
from __future__ import annotations

import base64
import json
import math

import numpy as np

from ..body_motion.skeleton import END_SITES, JOINTS, kinematic_tables
from ..errors import ConfigError, short_repr
from ..gait.attributes import STEP_ATTRIBUTES
from ..gait.plan import PARAMETER_KEYS, stance_leg

#: The settings a walk may be started with, besides ``attributes.NAME`` for any attribute.
SETTINGS = ("body.height", "body.mass", "solver.method", "walk.start_from_rest",
            "walk.speed", "walk.step_length", "walk.step_frequency")
TYPES = ("start", "set", "stop", "need", "export")
#: What a "set" may change from the next step on: the locomotion parameters and the attributes
#: that may change per step.
SET_KEYS = (*PARAMETER_KEYS, *(f"attributes.{name}" for name in STEP_ATTRIBUTES))
#: The dynamics columns a step carries to the page's strips.
STRIP_COLUMNS = ("t", "hip_y", "hip_y_ref", "F_w", "F_theta1", "F_theta2", "F_theta3", "F_theta4")


class Refused(ConfigError):
    """A message refused, with the field it names (the page shows the line beside that field)."""

    def __init__(self, field: str, message: str):
        super().__init__(message)
        self.field = field


def refusal(field: str, value, allowed: str) -> Refused:
    return Refused(field, f"{field}: got {short_repr(value)}, allowed {allowed}")


def parse(text, max_bytes: int) -> dict:
    """A page's message as a checked dict, or :class:`Refused` naming what is wrong."""
    if isinstance(text, bytes):
        raise refusal("message", "binary data", "a JSON text message")
    if len(text.encode("utf-8", "surrogatepass")) > max_bytes:
        raise Refused("message", f"message: got {len(text.encode('utf-8', 'surrogatepass'))} bytes, "
                                 f"allowed at most {max_bytes}")
    try:
        message = json.loads(text)
    except (ValueError, RecursionError):
        raise refusal("message", text[:40], "a JSON object with a type") from None
    if not isinstance(message, dict) or message.get("type") not in TYPES:
        kind = message.get("type") if isinstance(message, dict) else message
        raise refusal("type", kind, f"one of {', '.join(TYPES)}")
    kind = message["type"]
    if kind == "start":
        return {"type": kind, "settings": _settings(message.get("settings", {}))}
    if kind == "set":
        values = message.get("values")
        if not isinstance(values, dict) or not values or set(values) - set(SET_KEYS):
            raise refusal("values", values, f"a mapping of some of {', '.join(SET_KEYS)} to numbers")
        for key, value in values.items():
            _number(key if key.startswith("attributes.") else f"walk.{key}", value)
        return {"type": kind, "values": values}
    if kind == "need":
        step = message.get("step")
        if isinstance(step, bool) or not isinstance(step, int) or step < 0:
            raise refusal("step", step, "an integer >= 0")
        return {"type": kind, "step": step}
    return {"type": kind}


def _number(field: str, value) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise refusal(field, value, "a finite number")
    return float(value)


def _settings(settings) -> dict:
    if not isinstance(settings, dict):
        raise refusal("settings", settings, "a mapping of setting paths to values")
    for path, value in settings.items():
        if path not in SETTINGS and not (isinstance(path, str) and path.startswith("attributes.")):
            raise refusal("settings", path, f"one of {', '.join(SETTINGS)} or attributes.NAME")
        if path == "walk.start_from_rest":
            if not isinstance(value, bool):
                raise refusal(path, value, "true or false")
        elif path == "solver.method":
            if not isinstance(value, str):
                raise refusal(path, value, "a solver mode's name")
        else:
            _number(path, value)
    return settings


def apply_settings(base: dict, settings: dict) -> dict:
    """The config mapping of a new walk: ``base`` (the served config's mapping) with ``settings``.
    A walk speed, step length or frequency given replaces all three of the base (eq. 1 completes
    the ones not given)."""
    data = json.loads(json.dumps(base))
    if any(p in settings for p in ("walk.speed", "walk.step_length", "walk.step_frequency")):
        for key in PARAMETER_KEYS:
            data["walk"].pop(key, None)
    for path, value in settings.items():
        section, name = path.split(".", 1)
        data.setdefault(section, {})[name] = value
    return data


def _finite(values, digits: int) -> list:
    """A float array as a JSON list: rounded, NaN (a leg not driven then) as null."""
    a = np.round(np.asarray(values, float), digits)
    out = a.tolist()
    for i in np.flatnonzero(~np.isfinite(a)).tolist():     # (a test per value took longer)
        out[i] = None
    return out


def _finite_columns(table, names, digits: int) -> dict:
    """:func:`_finite` of each of ``table``'s columns ``names`` (of one length), rounded and tested
    as one array (the same numbers: rounding is elementwise; a call per column cost more)."""
    a = np.round(np.array([table[c] for c in names], float), digits)
    out = a.tolist()
    bad = np.flatnonzero(~np.isfinite(a).ravel())
    if len(bad):
        for i in bad.tolist():
            out[i // a.shape[1]][i % a.shape[1]] = None
    return dict(zip(names, out))


def skeleton_message(body) -> dict:
    """The bones the page draws: each joint's parent, and the end sites (toes, head top, hands); and
    what the page's forward kinematics (static/kinematics.js) needs to place them from a step's
    root and angles, as :func:`~klaw_ocp.body_motion.skeleton.forward_kinematics` does: each joint's
    rest offset from its parent (m, the root's zero), each end site's from its joint, and each of
    the 56 angles' joint, slot in the joint's Z, X, Y order (0, 1, 2) and sign. The offsets are
    sent as Python writes floats (the shortest text that reads back to the same float)."""
    names = [j.name for j in JOINTS]
    return {"type": "skeleton", "joints": names,
            "parents": [-1 if j.parent is None else names.index(j.parent) for j in JOINTS],
            "end_sites": [names.index(name) for name in END_SITES], "height": body.height,
            **{name: table.tolist() for name, table in kinematic_tables(body).items()}}


def _float64s(values) -> str:
    """A float array as base64 of its little-endian float64 bytes, in C order: the numbers exactly,
    for the page to read with a Float64Array (static/kinematics.js, ``float64s``)."""
    return base64.b64encode(np.ascontiguousarray(values, "<f8").tobytes()).decode("ascii")


def strips_text(table) -> str:
    """A step's rows of dynamics.csv for the page's strips (STRIP_COLUMNS and the subphase), as the
    JSON text of a step message's ``dynamics``: they read that step alone, so the server writes them
    once the step is solved whole, before the page asks for it (:func:`step_text`)."""
    return json.dumps({**_finite_columns(table, STRIP_COLUMNS, 4),
                       "subphase": np.asarray(table["subphase"]).astype(str).tolist()}, allow_nan=False)


def step_text(ready, attrs, planned, strips: str | None = None) -> str:
    """A step for the page, as the JSON text sent: its parameters and timings, each frame's root
    position (n, 3) and 56 angles (n, 56) exactly (:func:`_float64s`; the page makes the joints'
    positions from them, static/kinematics.js), its subphases, and its rows of dynamics.csv for
    the strips (``strips``: :func:`strips_text` of them when the caller wrote it already)."""
    result, frames = ready.result, ready.frames
    plan = result.plan
    subphases = [[s.name, result.t_start + float(s.t[0]), result.t_start + float(s.t[-1])] for s in result.subphases]
    half = attrs.foot_lateral_distance / 2
    side = stance_leg(ready.index)
    message = json.dumps({
        "type": "step", "index": ready.index, "closing": ready.closing, "stance_leg": side,
        "t_start": plan.t_start, "t_step": plan.timings.t_step, "t_ds": plan.timings.t_ds,
        "speed": plan.parameters.speed_kmh, "step_length": plan.parameters.step_length_m,
        "step_frequency": plan.parameters.step_frequency_spm,
        # the attributes that may change per step, as this step walks with them
        "attributes": {name: plan.attributes.get(name) for name in STEP_ATTRIBUTES},
        "foot": {"x": result.origin_x, "z": half if side == "right" else -half},
        "frames": {"t": _finite(frames.t, 6), "root": _float64s(frames.root), "angles": _float64s(frames.angles)},
        "subphases": subphases, "solve_ms": round(ready.solve_s * 1000, 2), "planned": planned,
    }, allow_nan=False)
    # the strips' text after the rest: a JSON object's text ends with its closing brace
    return f'{message[:-1]}, "dynamics": {strips_text(ready.dynamics) if strips is None else strips}}}'
