"""The playground's server through its ASGI test client (#38 items 2, 4, 5, 6): steps streamed one
ahead of the page, parameter changes, refusals that leave the walk going, a session exported and
reproduced by `klaw-ocp run` byte for byte, the limits, sessions that end."""
from __future__ import annotations

import base64
import contextlib
import json
import time
from collections import deque

import numpy as np
import pytest

pytest.importorskip("starlette")
pytest.importorskip("httpx")

from starlette.testclient import TestClient  # noqa: E402

from klaw_ocp.cli import main  # noqa: E402
from klaw_ocp.commands.serve import DEFAULT_WALK  # noqa: E402
from klaw_ocp.config import ExperimentConfig  # noqa: E402
from klaw_ocp.serve.app import create_app  # noqa: E402
from klaw_ocp.serve.limits import MessageRate, ServeLimits, origin_allowed  # noqa: E402
from klaw_ocp.serve.protocol import STRIP_COLUMNS, step_text, strips_text  # noqa: E402

ORIGIN = {"origin": "http://testserver"}
WALK = {**DEFAULT_WALK, "walk": {"speed": 5.0, "steps": 1}}


def app(**limits):
    return create_app(ExperimentConfig.from_mapping(WALK), ServeLimits(**limits))


class Page:
    """What a page does with the websocket: it reads every message as it comes and asks for the
    next step when it shows one. A step that arrives while the page waits for another message
    (a refusal, an acceptance, an export) is kept for showing, not lost: the server solves a step
    only when asked, so a page that dropped one would never ask for the next and would wait
    forever (how the order of a step and a refusal, which depends on the machine, once hung CI)."""

    def __init__(self, ws):
        self.ws, self.pending = ws, deque()

    def send(self, message) -> None:
        self.ws.send_text(message if isinstance(message, str) else json.dumps(message))

    def receive(self, kind: str, skip=("accepted", "stopping")) -> dict:
        """The next message of type ``kind``; steps that come first are kept for :meth:`walk`,
        the listed kinds passed over."""
        if kind == "step" and self.pending:
            return self.pending.popleft()
        for _ in range(200):
            message = json.loads(self.ws.receive_text())
            if message["type"] == "skeleton":      # a new walk: the old one's steps are dropped
                self.pending.clear()
            if message["type"] == kind:
                return message
            assert message["type"] in ("step", "skeleton", *skip), message
            if message["type"] == "step":
                self.pending.append(message)
        raise AssertionError(f"no {kind} message")

    def walk(self, count: int) -> list:
        """Show ``count`` steps, asking for the next one while showing one."""
        steps = []
        for _ in range(count):
            step = self.receive("step")
            self.send({"type": "need", "step": step["index"] + 1})
            steps.append(step)
        return steps


@contextlib.contextmanager
def open_page(client):
    with client.websocket_connect("/walk", headers=ORIGIN) as ws:
        yield Page(ws)


@pytest.fixture
def client():
    with TestClient(app()) as c:
        yield c


def test_the_page_and_its_three_js_are_served_from_the_package(client):
    page = client.get("/")
    assert page.status_code == 200 and "importmap" in page.text
    assert "//" not in "".join(part.split('"')[1] for part in page.text.split("src=")[1:])   # nothing from elsewhere
    assert '"three": "/static/' in page.text
    assert client.get("/static/vendor/three/three.module.js").status_code == 200
    assert client.get("/static/vendor/three/three.core.js").status_code == 200
    assert "MIT" in client.get("/static/vendor/three/LICENSE").text
    assert client.get("/info").json()["envelope"]["speed"]["allowed"] == [0.5, 9.0]


def float64s(text: str, columns: int) -> np.ndarray:
    """A step message's base64 frames as the page reads them: little-endian float64s, C order."""
    return np.frombuffer(base64.b64decode(text, validate=True), dtype="<f8").reshape(-1, columns)


def test_steps_stream_one_ahead_of_the_page_with_the_bodys_frames(client):
    from klaw_ocp.stepwise import StepwiseWalk
    with open_page(client) as page:
        skeleton = page.receive("skeleton")
        assert len(skeleton["joints"]) == 37
        sent = [page.receive("step")]
        assert sent[0]["index"] == 0 and sent[0]["planned"]["step"] == 2
        page.send({"type": "need", "step": 5})    # no further than the step after those sent
        sent.append(page.receive("step"))
        assert sent[1]["index"] == 1
        page.send({"type": "export"})              # the walk so far, while it walks
        assert page.receive("export")["steps"] == 2
        page.send({"type": "need", "step": 2})
        sent.append(page.receive("step"))
        assert sent[2]["index"] == 2
    # each frame's root position and 56 angles, the step-wise walk's own to the bit (no joint
    # positions: the page makes them, static/kinematics.js)
    live = StepwiseWalk(ExperimentConfig.from_mapping(WALK))
    for step in sent:
        ready = live.next_step()
        frames, n = step["frames"], len(step["frames"]["t"])
        assert set(frames) == {"t", "root", "angles"} and ready.index == step["index"] and n > 10
        root, angles = float64s(frames["root"], 3), float64s(frames["angles"], 56)
        assert root.shape == (n, 3) and angles.shape == (n, 56)
        assert np.isfinite(root).all() and np.isfinite(angles).all()
        assert root.tobytes() == np.ascontiguousarray(ready.frames.root, "<f8").tobytes()
        assert angles.tobytes() == np.ascontiguousarray(ready.frames.angles, "<f8").tobytes()
        assert frames["t"] == np.round(np.asarray(ready.frames.t, float), 6).tolist()
        # the strips, which the server writes once the step is solved whole, spliced into the message
        strips = strips_text(ready.dynamics)
        assert step["dynamics"] == json.loads(strips) and set(step["dynamics"]) == {*STRIP_COLUMNS, "subphase"}
        text = step_text(ready, live.attributes, step["planned"], strips)
        assert text == step_text(ready, live.attributes, step["planned"]) and json.loads(text)["dynamics"] == step["dynamics"]


def page_forward_kinematics(skeleton: dict, root: np.ndarray, angles: np.ndarray) -> np.ndarray:
    """The page's forward kinematics (static/kinematics.js) written again from the skeleton message
    alone, one joint and frame at a time with its own elementary rotations: (n, joints + end sites, 3)."""
    def rotation(axis: int, a: float) -> np.ndarray:     # about x (0), y (1) or z (2)
        c, s, r = np.cos(a), np.sin(a), np.eye(3)
        i, j = [(1, 2), (2, 0), (0, 1)][axis]
        r[i, i], r[i, j], r[j, i], r[j, j] = c, -s, s, c
        return r

    parents, offsets = skeleton["parents"], np.array(skeleton["offsets"])
    out = []
    for frame_root, frame_angles in zip(root, angles):
        zxy = np.zeros((len(parents), 3))       # each joint's signed z, x, y angles (slots 0, 1, 2)
        for a, (joint, slot, sign) in enumerate(zip(skeleton["angle_joint"], skeleton["angle_slot"], skeleton["angle_sign"])):
            zxy[joint, slot] = sign * frame_angles[a]
        rotations, positions = [], []
        for j, parent in enumerate(parents):
            local = rotation(2, zxy[j, 0]) @ rotation(0, zxy[j, 1]) @ rotation(1, zxy[j, 2])
            if parent < 0:
                rotations.append(local)
                positions.append(frame_root)
            else:
                rotations.append(rotations[parent] @ local)
                positions.append(positions[parent] + rotations[parent] @ offsets[j])
        ends = [positions[j] + rotations[j] @ np.array(o) for j, o in zip(skeleton["end_sites"], skeleton["end_site_offsets"])]
        out.append(positions + ends)
    return np.array(out)


@pytest.mark.parametrize("height", [1.8, 1.2])
def test_the_skeleton_message_carries_the_bodys_forward_kinematics(height):
    """The page's forward kinematics from the skeleton message (as JSON carries it) places every
    joint and end site where the server's does, at angles far from a walk's in every slot."""
    from klaw_ocp.body import Body
    from klaw_ocp.body_motion.skeleton import END_SITES, forward_kinematics, rest_root_position
    from klaw_ocp.serve.protocol import skeleton_message
    body = Body(height, 60.0)
    skeleton = json.loads(json.dumps(skeleton_message(body)))
    assert len(skeleton["offsets"]) == 37 and len(skeleton["end_site_offsets"]) == len(skeleton["end_sites"])
    assert len(skeleton["angle_joint"]) == len(skeleton["angle_slot"]) == len(skeleton["angle_sign"]) == 56
    rng = np.random.default_rng(7)
    root = rest_root_position(body) + rng.uniform(-0.5, 0.5, (6, 3))
    angles = rng.uniform(-1.2, 1.2, (6, 56))
    angles[0] = 0.0                          # the rest pose
    server = forward_kinematics(body, root, angles)
    expected = np.concatenate([server.positions] + [server.end_sites[n][:, None] for n in END_SITES], axis=1)
    page = page_forward_kinematics(skeleton, root, angles)
    assert page.shape == (6, 37 + len(END_SITES), 3)
    assert np.abs(page - expected).max() < 1e-12
    assert page[0, :, 1].min() == pytest.approx(root[0, 1] - rest_root_position(body)[1], abs=1e-12)   # soles at y = 0


def test_a_speed_change_reaches_the_walk_ramped_and_a_refusal_leaves_it_walking(client):
    with open_page(client) as page:
        page.walk(2)
        page.send({"type": "set", "values": {"speed": 30}})
        refused = page.receive("refused")
        assert refused["field"] == "walk.speed" and refused["message"].startswith("walk.speed: got 30")
        page.send({"type": "set", "values": {"speed": 3.0}})
        assert page.receive("accepted")["target"]["speed"] == 3.0
        speeds = [s["speed"] for s in page.walk(6)]
        assert speeds[-1] == pytest.approx(3.0) and all(abs(b - a) <= 1.0 + 1e-9 for a, b in zip(speeds, speeds[1:]))


def test_a_determinant_changes_the_walk_from_a_later_step_without_a_new_walk(client):
    """A page's pelvic list and arm swing sliders change the walk on (#38 item 1: attributes before
    each step), the step message saying which ones it walks with; the walk is not restarted."""
    with open_page(client) as page:
        page.walk(2)
        page.send({"type": "set", "values": {"attributes.pelvic_list": 9, "attributes.arm_swing_amplitude": 25}})
        target = page.receive("accepted")["target"]
        assert target["attributes"]["pelvic_list"] == 9.0 and "speed" not in target
        steps = page.walk(4)
        assert [s["index"] for s in steps] == [2, 3, 4, 5]             # the same walk, going on
        lists = [s["attributes"]["pelvic_list"] for s in steps]
        assert lists[0] == 5.0 and lists[-1] == 9.0


@pytest.mark.parametrize("text, field", [
    ("x" * 5000, "message"), ("not json", "message"), ("[1, 2]", "type"), ('{"type": "fly"}', "type"),
    ('{"type": "set", "values": {"speed": "fast"}}', "walk.speed"),
    ('{"type": "set", "values": {"cadence": 100}}', "values"),
    ('{"type": "start", "settings": {"body.height": 3.0}}', "body.height"),
    ('{"type": "start", "settings": {"output.dir": "/etc"}}', "settings"),
    ('{"type": "start", "settings": {"attributes.pelvic_list": 90}}', "attributes.pelvic_list"),
    ('{"type": "set", "values": {"attributes.pelvic_list": 90}}', "attributes.pelvic_list"),
    ('{"type": "set", "values": {"attributes.sf_max": 100}}', "values"),
    ('{"type": "need", "step": -1}', "step"),
])
def test_bad_messages_are_refused_in_one_line_and_the_walk_goes_on(client, text, field):
    with open_page(client) as page:
        page.walk(1)
        page.send(text)
        refused = page.receive("refused")
        assert refused["field"] == field and "\n" not in refused["message"], refused
        assert len(page.walk(2)) == 2


@pytest.mark.parametrize("stopped", [True, False], ids=["stopped at rest", "mid-walk"])
def test_a_session_exported_reproduces_with_klaw_ocp_run_byte_for_byte(client, tmp_path, monkeypatch, stopped):
    with open_page(client) as page:
        page.walk(2)
        page.send({"type": "set", "values": {"speed": 4.0, "step_length": 0.7, "attributes.pelvic_rotation": 7}})
        page.walk(2)
        if stopped:
            page.send({"type": "stop"})
            while (step := page.receive("step", skip=("accepted", "stopping", "ended")))["closing"] is False:
                page.send({"type": "need", "step": step["index"] + 1})
        else:
            assert page.receive("step")["index"] == 4       # on the page; step 5 not asked for yet
        page.send({"type": "export"})
        exported = page.receive("export", skip=("accepted", "stopping", "ended"))
        if not stopped:     # the walk so far, and the walk goes on after it
            assert exported["steps"] == 5
            page.send({"type": "need", "step": 5})
            assert page.receive("step")["index"] == 5
    config = tmp_path / "session.yaml"
    config.write_text(exported["config"], encoding="utf-8")
    monkeypatch.chdir(tmp_path)
    assert main(["run", str(config), "--no-plots", "--no-animation", "--quiet", "--out", str(tmp_path / "run")]) == 0
    assert (tmp_path / "run" / "walk.bvh").read_text(encoding="utf-8") == exported["bvh"]


def test_a_step_that_does_not_converge_ends_its_walk_in_one_line_and_a_new_one_walks(client, fail_at_step):
    fail_at_step(3, "swing2", 1e-3)
    with open_page(client) as page:
        page.walk(2)                       # and asks for step 2, whose next step fails
        failed = page.receive("failed")
        assert "swing2" in failed["message"] and "\n" not in failed["message"]
        page.send({"type": "start", "settings": {"walk.speed": 4.0}})
        assert page.receive("skeleton")["type"] == "skeleton"
        assert page.receive("step")["index"] == 0


def test_swings_that_fail_after_their_step_was_sent_end_the_walk_once(client, monkeypatch):
    """The server solves the next step's swings after sending a step (StepwiseWalk.finish_ahead):
    where they fail, the page hears it once, after the steps already sent, and gets no more."""
    from klaw_ocp.control.step import StepController
    from klaw_ocp.errors import ConvergenceError
    original = StepController.solve_swing_stage

    def failing(self, stage):
        if stage.index == 3:
            raise ConvergenceError(3, "swing1", 2e-3, "forced for the test")
        return original(self, stage)
    monkeypatch.setattr(StepController, "solve_swing_stage", failing)
    with open_page(client) as page:
        assert [s["index"] for s in page.walk(3)] == [0, 1, 2]     # step 2 went out with step 3's stance half
        failed = page.receive("failed")
        assert "step 3" in failed["message"] and "swing1" in failed["message"]
        page.send({"type": "need", "step": 3})
        page.send({"type": "start", "settings": {}})
        # nothing of the failed walk comes after (no step 3, no second "failed", no "ended")
        assert json.loads(page.ws.receive_text())["type"] == "skeleton"
        assert page.receive("step")["index"] == 0


def test_a_new_walk_with_other_settings_replaces_the_old_one(client, monkeypatch):
    from klaw_ocp.serve import session

    class SlowToBuild(session.StepwiseWalk):
        def __init__(self, *args, **kwargs):
            time.sleep(0.3)
            super().__init__(*args, **kwargs)
    # the new walk is built slowly, so the old walk's step 2 (asked for with step 1) always
    # arrives before the new skeleton, as it may on any machine: the page drops it
    monkeypatch.setattr(session, "StepwiseWalk", SlowToBuild)
    with open_page(client) as page:
        page.walk(2)
        page.send({"type": "start", "settings": {"body.height": 1.6, "attributes.arm_swing_amplitude": 30,
                                                 "walk.start_from_rest": True, "walk.speed": 3.0}})
        skeleton = page.receive("skeleton")
        assert skeleton["height"] == 1.6 and skeleton["start_from_rest"] is True
        assert page.receive("step")["index"] == 0


def test_a_foreign_origin_is_refused(client):
    from starlette.websockets import WebSocketDisconnect
    for headers in ({"origin": "http://evil.example"}, {}):
        with pytest.raises(WebSocketDisconnect) as err:
            with client.websocket_connect("/walk", headers=headers) as ws:
                ws.receive_text()
        assert err.value.code == 1008


def test_origin_rules():
    assert origin_allowed("http://127.0.0.1:8765", "127.0.0.1:8765")
    assert origin_allowed("http://localhost:8765", "127.0.0.1:8765")
    assert not origin_allowed("http://localhost:9999", "10.0.0.5:8765")
    assert not origin_allowed("http://attacker.example", "127.0.0.1:8765")
    assert not origin_allowed("null", "127.0.0.1:8765") and not origin_allowed(None, "127.0.0.1:8765")


def test_sessions_past_the_limit_are_told_so_and_the_first_ones_go_on():
    from starlette.websockets import WebSocketDisconnect
    with TestClient(app(max_sessions=1)) as c:
        with open_page(c) as first:
            first.walk(1)
            with pytest.raises(WebSocketDisconnect) as err:
                with c.websocket_connect("/walk", headers=ORIGIN) as second:
                    second.receive_text()
            assert err.value.code == 1013 and "sessions" in err.value.reason
            assert len(first.walk(1)) == 1
        assert c.get("/info").json()["sessions"] == 0
        with open_page(c) as again:       # the slot is free again
            assert again.receive("step")["index"] == 0


def test_a_page_that_sends_too_fast_is_refused_and_keeps_walking():
    with TestClient(app(max_messages_per_s=1.0, burst=3)) as c:
        with open_page(c) as page:
            for _ in range(6):
                page.send('{"type": "need", "step": 0}')
            refused = page.receive("refused")
            assert refused["field"] == "message" and "messages a second" in refused["message"]


def test_the_message_rate_refills():
    now = [0.0]
    rate = MessageRate(2.0, 2, clock=lambda: now[0])
    assert rate.allow() and rate.allow() and not rate.allow()
    now[0] += 0.5
    assert rate.allow() and not rate.allow()


def test_serve_refuses_a_bad_port_in_one_line(capsys):
    assert main(["serve", "--port", "70000"]) == 2
    assert capsys.readouterr().err.strip() == "klaw-ocp: error: --port: got 70000, allowed an integer from 0 to 65535"


def test_serve_refuses_a_port_in_use_in_one_line(capsys):
    import socket
    with socket.create_server(("127.0.0.1", 0)) as taken:
        port = taken.getsockname()[1]
        assert main(["serve", "--port", str(port)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"klaw-ocp: error: --port: got {port}, allowed a port free on 127.0.0.1") and "\n" not in err


def test_closed_tabs_free_their_walks_at_once(client):
    import gc
    import time
    for k in range(6):
        with open_page(client) as page:
            page.receive("step")
            if k % 2:       # closed with the next step being solved
                page.send({"type": "need", "step": 1})
    deadline = time.monotonic() + 10
    while True:             # a step being solved when its page closed finishes in its thread first
        gc.collect()
        if not len(client.app.state.walks) or time.monotonic() > deadline:
            break
        time.sleep(0.05)
    assert len(client.app.state.walks) == 0 and client.get("/info").json()["sessions"] == 0


def test_the_real_server_keeps_serving_through_abuse():
    """uvicorn itself: more pages than walks allowed, an oversized frame, garbage, pages closed
    mid-step; then a new page walks as the first did."""
    import contextlib
    import urllib.request

    from websockets.exceptions import ConnectionClosed
    from websockets.sync.client import connect

    from _serve_support import running_server
    with running_server(app(max_sessions=2)) as url, contextlib.ExitStack() as stack:
        ws_url = url.replace("http", "ws") + "/walk"
        pages = [stack.enter_context(connect(ws_url, origin=url, open_timeout=20)) for _ in range(5)]
        refused = 0
        for page in pages:
            try:
                assert json.loads(page.recv(timeout=20))["type"] == "skeleton"
            except ConnectionClosed as err:        # a page past the limit: closed, try again later
                refused += err.rcvd.code == 1013
        assert refused == 3
        for page in pages:
            page.close()
        with connect(ws_url, origin=url, open_timeout=20) as big:
            big.send("x" * 200_000)      # over uvicorn's frame limit: this connection is closed unread
            with pytest.raises(ConnectionClosed):
                for _ in range(10):
                    big.recv(timeout=20)
        with connect(ws_url, origin=url, open_timeout=20) as junk:
            for text in ("\x00", "{", '{"type": "need", "step": 99999999}', '{"type": "set"}', "[]" * 100):
                junk.send(text)
            junk.send(json.dumps({"type": "need", "step": 1}))
        # closed mid-step
        assert urllib.request.urlopen(url + "/", timeout=10).status == 200
        # a closed page's walk ends once the server reads the close, after the message or the
        # walk's start it was handling (tens of milliseconds): the sessions count says when
        deadline = time.monotonic() + 20
        while json.loads(urllib.request.urlopen(url + "/info", timeout=10).read())["sessions"] and time.monotonic() < deadline:
            time.sleep(0.02)
        with connect(ws_url, origin=url, open_timeout=20) as page:
            kinds = [json.loads(page.recv(timeout=30))["type"] for _ in range(2)]
            assert kinds == ["skeleton", "step"]


def test_serve_warns_when_asked_to_serve_other_machines(capsys, monkeypatch):
    """--host other than the loopback: served, with a warning (the server stubbed: it would block)."""
    import klaw_ocp.serve.server as server_module

    class Stub:
        started, should_exit, servers = False, True, []

        def run(self, sockets):
            sockets[0].close()

    monkeypatch.setattr(server_module, "make_server", lambda app, host, port: Stub())
    assert main(["serve", "--host", "0.0.0.0", "--port", "0"]) == 0
    err = capsys.readouterr().err
    assert err.startswith("klaw-ocp: warning: serving on 0.0.0.0: any machine that reaches it can open walks")
    assert main(["serve", "--port", "0"]) == 0 and "warning" not in capsys.readouterr().err
