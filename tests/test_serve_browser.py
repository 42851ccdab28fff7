"""The playground in a real browser (#38 item 6): headless Chromium (Debian's chromium and
chromium-driver, which .ci/run installs) opens the page, waits for the body to walk, moves the
speed slider and sees the cadence on screen change, then keeps a screenshot that is not blank.

Skipped, with the reason, where no Chromium or driver is installed; KLAW_OCP_REQUIRE_BROWSER=1
(set by .ci/run where it could install them) turns that skip into a failure."""
from __future__ import annotations

import os
import shutil
import sys
import time
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent))
from _serve_support import running_server  # noqa: E402

CHROMIUM = next((p for p in (shutil.which("chromium"), shutil.which("chromium-browser"),
                             shutil.which("google-chrome")) if p), None)
DRIVER = shutil.which("chromedriver") or next((p for p in ("/usr/lib/chromium/chromedriver",) if os.path.exists(p)), None)
REQUIRED = os.environ.get("KLAW_OCP_REQUIRE_BROWSER") == "1"


def _missing() -> str | None:
    try:
        import selenium  # noqa: F401
        import starlette  # noqa: F401
        import uvicorn  # noqa: F401
    except ImportError as err:
        return f"{err.name} is not installed (pip install '.[test]')"
    if CHROMIUM is None or DRIVER is None:
        return "no Chromium and chromedriver here (Debian: apt-get install chromium chromium-driver; .ci/run does)"
    return None


@pytest.fixture(scope="module")
def browser():
    missing = _missing()
    if missing:
        if REQUIRED:
            pytest.fail(f"the browser test must run here (KLAW_OCP_REQUIRE_BROWSER=1): {missing}")
        pytest.skip(missing)
    from selenium import webdriver
    from selenium.webdriver.chrome.options import Options
    from selenium.webdriver.chrome.service import Service
    options = Options()
    options.binary_location = CHROMIUM
    for flag in ("--headless=new", "--no-sandbox", "--disable-dev-shm-usage", "--window-size=1200,760",
                 "--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--disable-gpu"):
        options.add_argument(flag)
    driver = webdriver.Chrome(service=Service(DRIVER), options=options)
    driver.set_page_load_timeout(30)
    yield driver
    driver.quit()


def wait_for(driver, script: str, timeout: float = 20.0):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        value = driver.execute_script(script)
        if value:
            return value
        time.sleep(0.1)
    raise AssertionError(f"timed out waiting for: {script}; the page has {driver.execute_script('return JSON.stringify(window.klaw)')}")


def test_the_body_walks_and_the_speed_slider_changes_the_cadence(browser, tmp_path):
    from klaw_ocp.commands.serve import DEFAULT_WALK
    from klaw_ocp.config import ExperimentConfig
    from klaw_ocp.serve.app import create_app
    app = create_app(ExperimentConfig.from_mapping({**DEFAULT_WALK, "walk": {"speed": 5.0, "steps": 1}}))
    with running_server(app) as url:
        browser.get(url + "/")
        wait_for(browser, "return window.klaw && window.klaw.shown.length >= 3")      # walking
        before = browser.execute_script("return window.klaw.shown[0].step_frequency")
        # the speed slider moved to 3 km/h, as a hand drags it (the page sends on 'input'), by the
        # page itself on the frame a step begins on screen, well before the page asks for the
        # step after it (0.25 s before its end); the natural step length then (no second
        # parameter), so the cadence follows eq. 1
        browser.set_script_timeout(10)
        browser.execute_async_script("""
            const done = arguments[arguments.length - 1], n = window.klaw.shown.length;
            (function poll() {
                if (window.klaw.shown.length === n) { requestAnimationFrame(poll); return; }
                document.querySelector("input[name=second][value=none]").checked = true;
                const s = document.getElementById("speed"); s.value = 3.0;
                s.dispatchEvent(new Event("input"));
                done();
            })();""")
        accepted = wait_for(browser, "return window.klaw.accepted")
        on_screen, planned_before = accepted["on_screen"], len(browser.execute_script("return window.klaw.planned"))
        wait_for(browser, f"return window.klaw.shown.length >= {on_screen + 5}", timeout=30)
        shown = browser.execute_script("return window.klaw.shown")
        planned = browser.execute_script("return window.klaw.planned")
        # the next step planned after the change has its new cadence (the page shows it at once)
        assert abs(planned[planned_before]["step_frequency"] - before) > 1.0, planned
        # on screen: the step on screen is drawn, the next is solved, the one after is planned and
        # is planned again with the change before it is solved, so the second step after the one
        # on screen is the first that can change (docs/serve.md, "When a change shows")
        first = next(s["index"] for s in shown if abs(s["step_frequency"] - before) > 1.0)
        print(f"cadence changed on screen {first - on_screen} steps after the step on screen at the change")
        assert 1 <= first - on_screen <= 2, (on_screen, [round(s["step_frequency"]) for s in shown])
        # the page asks for the next step a few deliveries' time before the step on screen ends
        # (app.js needBeforeEnd), within its bounds whatever the machine's speed
        lead = browser.execute_script("return window.klaw.need_before_end_s")
        print(f"the page asks for the next step {1000 * lead:.0f} ms before the step on screen ends")
        assert 0.06 <= lead <= 0.25
        assert browser.execute_script("return window.klaw.refusals.length") == 0
        # a determinant's slider (pelvic list) changes the walk going on from a later step, with
        # no new walk (the step indices run on)
        walked = len(browser.execute_script("return window.klaw.shown"))
        browser.execute_script("""const s = document.getElementById("attr-pelvic_list"); s.value = 10;
                                  s.dispatchEvent(new Event("input")); s.dispatchEvent(new Event("change"));""")
        wait_for(browser, f"return window.klaw.shown.length >= {walked + 3}", timeout=30)
        shown = browser.execute_script("return window.klaw.shown")
        assert [s["index"] for s in shown] == list(range(len(shown)))
        assert shown[walked - 1]["pelvic_list"] == 5.0 and shown[-1]["pelvic_list"] == 10.0, shown
        # past the envelope: the CLI's one line under the slider, and the walk goes on
        browser.execute_script("""const s = document.getElementById("speed"); s.value = 11.5;
                                  s.dispatchEvent(new Event("input"));""")
        line = wait_for(browser, """return document.querySelector('.control[data-field="walk.speed"] .refusal').textContent""")
        assert line == "walk.speed: got 11.5 km/h, allowed 0.5 to 9 km/h (attributes.speed_min/speed_max)"
        # the slider back at the speed the walk has (3 km/h, taken above), its label with it
        slider = browser.execute_script("""const s = document.getElementById("speed");
                                           return [s.value, s.closest("label").querySelector("output").textContent];""")
        assert slider == ["3", "3.00"], slider
        walked = len(browser.execute_script("return window.klaw.shown"))
        wait_for(browser, f"return window.klaw.shown.length >= {walked + 1}")
        # the walk so far, downloaded while it walks (the config that reproduces it)
        browser.find_element("id", "download-config").click()
        exported = wait_for(browser, "return window.klaw.exported")
        assert exported["file"] == "config" and exported["steps"] >= walked and exported["config_chars"] > 500
        browser.execute_script("window.klaw.exported = null")
        # stop at rest, then the downloads: walk.bvh from the page's button
        browser.find_element("id", "stop").click()
        wait_for(browser, "return window.klaw.ended", timeout=30)
        # both files asked for at once: each arrives as the file asked for, in order
        browser.execute_script("window.klaw.exports = []")
        browser.find_element("id", "download-bvh").click()
        browser.find_element("id", "download-config").click()
        exports = wait_for(browser, "return window.klaw.exports.length === 2 && window.klaw.exports")
        assert [e["file"] for e in exports] == ["bvh", "config"], exports
        assert all(e["bvh_chars"] > 10_000 and e["config_chars"] > 500 for e in exports)
        shot = tmp_path / "playground.png"
        browser.save_screenshot(str(shot))
    _not_blank(shot)


def test_the_page_places_the_joints_as_the_servers_forward_kinematics(browser):
    """The page makes each frame's joint and end-site positions from the step's root and angles
    (static/kinematics.js): those of a step it received, and of poses far from a walk's for another
    body, are the server's (klaw_ocp.body_motion.skeleton.forward_kinematics) to 1e-9 m."""
    import base64

    import numpy as np

    from klaw_ocp.body import Body
    from klaw_ocp.body_motion.skeleton import END_SITES, forward_kinematics, rest_root_position
    from klaw_ocp.commands.serve import DEFAULT_WALK
    from klaw_ocp.config import ExperimentConfig
    from klaw_ocp.serve.app import create_app
    from klaw_ocp.serve.protocol import skeleton_message

    def server_points(body, root, angles):
        s = forward_kinematics(body, root, angles)
        return np.concatenate([s.positions] + [s.end_sites[n][:, None] for n in END_SITES], axis=1).reshape(len(root), -1)

    def float64s(text, columns):
        return np.frombuffer(base64.b64decode(text), dtype="<f8").reshape(-1, columns)

    app = create_app(ExperimentConfig.from_mapping({**DEFAULT_WALK, "walk": {"speed": 5.0, "steps": 1}}))
    with running_server(app) as url:
        browser.get(url + "/")
        wait_for(browser, "return window.klaw && window.klaw.shown.length >= 2")
        step = browser.execute_script("""const m = window.klaw.last_step;
            return {index: m.index, root: m.frames.root, angles: m.frames.angles,
                    points: m.frames.points.map((p) => Array.from(p))};""")
        root, angles = float64s(step["root"], 3), float64s(step["angles"], 56)
        page = np.array(step["points"])
        expected = server_points(Body(**DEFAULT_WALK["body"]), root, angles)
        assert len(root) > 10 and page.shape == expected.shape == (len(root), 3 * (37 + len(END_SITES)))
        print(f"step {step['index']}: the page's joints within {np.abs(page - expected).max():.1e} m of the server's")
        assert np.abs(page - expected).max() < 1e-9
        # another body, every angle far from the walk's (up to 1.4 rad) and the root anywhere
        body = Body(1.5, 50.0)
        rng = np.random.default_rng(3)
        root = rest_root_position(body) + rng.uniform(-2, 2, (5, 3))
        angles = rng.uniform(-1.4, 1.4, (5, 56))
        frames = {name: base64.b64encode(np.ascontiguousarray(a, "<f8").tobytes()).decode("ascii")
                  for name, a in (("root", root), ("angles", angles))}
        page = np.array(browser.execute_script(
            "return window.klawForwardKinematics(arguments[0], arguments[1]).map((p) => Array.from(p));",
            skeleton_message(body), frames))
        expected = server_points(body, root, angles)
        assert page.shape == expected.shape and np.abs(page - expected).max() < 1e-9


def _not_blank(path: Path) -> None:
    from PIL import Image
    image = Image.open(path).convert("RGB")
    colours = image.getcolors(maxcolors=1 << 20) or []
    assert image.size[0] >= 800 and len(colours) > 50, f"{path}: {len(colours)} colours"
    # the 3D view itself is drawn (WebGL): its middle holds more than the background's colour
    w, h = image.size
    middle = image.crop((w // 4, h // 8, w // 2, h // 2)).getcolors(maxcolors=1 << 20) or []
    assert len(middle) > 10, f"{path}: the 3D view's middle has {len(middle)} colours"
