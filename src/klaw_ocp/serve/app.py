"""The playground's web application (docs/serve.md): the page and its files, and the websocket
that streams a walk to it. Starlette (ASGI) for the routes and uvicorn with ``websockets`` to
serve them: docs/serve.md says why."""
from __future__ import annotations

import asyncio
import weakref
from importlib import resources

from starlette.applications import Starlette
from starlette.responses import FileResponse, JSONResponse, Response
from starlette.routing import Mount, Route, WebSocketRoute
from starlette.staticfiles import StaticFiles
from starlette.websockets import WebSocket

from ..config import ExperimentConfig
from ..gait.attributes import ATTRIBUTES
from ..gait.envelope import SUPPORTED_HEIGHT_M, SUPPORTED_MASS_KG, SUPPORTED_SF_MAX
from .. import choices
from .limits import ServeLimits, origin_allowed
from .session import LiveSession

#: websocket close codes: policy violation (a foreign page), try again later (too many walks)
CLOSE_ORIGIN, CLOSE_BUSY = 1008, 1013
#: the attributes the page has sliders for (the ones that show most on the body)
PAGE_ATTRIBUTES = ("pelvic_list", "pelvic_rotation", "arm_swing_amplitude", "toe_clearance")


def static_dir():
    return resources.files("klaw_ocp.serve") / "static"


def envelope(config: ExperimentConfig) -> dict:
    """The sliders: their starting values, the envelope's limits (shown beside them) and a range
    reaching past those limits on purpose: a value outside is refused in one line, the walk goes on."""
    attrs, l1 = config.attributes_model(), config.body_model().l1
    first = config.plan()[0].parameters

    def slider(value, low, high, reach_low, reach_high, unit):
        return {"value": value, "min": reach_low, "max": reach_high, "allowed": [low, high], "unit": unit}

    return {
        "speed": slider(first.speed_kmh, attrs.speed_min, attrs.speed_max, 0.2, 12.0, "km/h"),
        "step_length": slider(first.step_length_m, attrs.step_length_min_rel * l1, attrs.step_length_max_rel * l1,
                              0.2, 1.6, "m"),
        "step_frequency": slider(first.step_frequency_spm, attrs.sf_min, SUPPORTED_SF_MAX, 20.0, 200.0, "steps/min"),
        "height": slider(config.body.height, *SUPPORTED_HEIGHT_M, 1.2, 2.3, "m"),
        "mass": slider(config.body.mass, *SUPPORTED_MASS_KG, 30.0, 170.0, "kg"),
        "attributes": {name: slider(attrs.get(name), ATTRIBUTES[name].low, ATTRIBUTES[name].high,
                                    ATTRIBUTES[name].low, ATTRIBUTES[name].high, ATTRIBUTES[name].unit)
                       for name in PAGE_ATTRIBUTES},
        "methods": list(choices.METHODS), "method": config.solver.method,
        "start_from_rest": config.walk.start_from_rest,
    }


def create_app(config: ExperimentConfig, limits: ServeLimits = ServeLimits()) -> Starlette:
    """The application serving ``config``'s walk (its body, attributes, solver and first
    parameters; the page changes them)."""
    base = config.model_dump(mode="json", exclude_none=True)
    # the page is the schedule and decides the walk's length: one step planned to start with
    base["walk"] = {k: v for k, v in base["walk"].items() if k in ("speed", "step_length", "step_frequency",
                                                                   "start_from_rest")}
    base["walk"]["steps"] = 1
    base["output"] = {"fps": config.output.fps}
    slots = asyncio.Semaphore(limits.max_sessions)
    state = {"sessions": 0}
    #: every page's walk while something holds it: empty again once the pages are closed (the tests' check)
    walks = weakref.WeakSet()
    ranges = envelope(config)

    async def page(request):
        return FileResponse(static_dir() / "index.html")

    async def info(request):
        return JSONResponse({"envelope": ranges, "sessions": state["sessions"], "max_sessions": limits.max_sessions,
                             "max_message_bytes": limits.max_message_bytes,
                             "max_messages_per_s": limits.max_messages_per_s})

    async def walk_socket(websocket: WebSocket):
        if not origin_allowed(websocket.headers.get("origin"), websocket.headers.get("host")):
            await websocket.close(code=CLOSE_ORIGIN, reason="origin: not this server's page")
            return
        if slots.locked():
            await websocket.accept()
            await websocket.close(code=CLOSE_BUSY, reason=f"sessions: {limits.max_sessions} walks "
                                                          f"already, allowed at most that; try again later")
            return
        async with slots:
            state["sessions"] += 1
            try:
                await websocket.accept()
                session = LiveSession(websocket, base, limits)
                walks.add(session)
                await session.run()
            finally:
                state["sessions"] -= 1

    async def no_icon(request):
        return Response(status_code=204)

    routes = [Route("/", page), Route("/info", info), Route("/favicon.ico", no_icon), WebSocketRoute("/walk", walk_socket),
              Mount("/static", app=StaticFiles(directory=str(static_dir())), name="static")]
    app = Starlette(routes=routes)
    app.state.sessions, app.state.walks = state, walks
    return app
