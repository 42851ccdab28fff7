"""One page's walk (docs/serve.md): a :class:`~klaw_ocp.stepwise.StepwiseWalk` driven over a
websocket, one step ahead of what the page shows.

Two tasks per connection: one reads the page's messages (each checked, refused in one line, never
a crash), one hands out steps. A step is made ready in a worker thread only when the page asks for
it (``{"type": "need", "step": k}``, at most ``ServeLimits.steps_ahead`` beyond the steps sent),
which it does a little before the step on screen ends: so the steps waiting for a slow page are
bounded, a page that stops reading stops its own walk and no other, and a change made during a
step reaches the walk as early as the plan allows (the step solved is the one after the next,
docs/serve.md). A step's frames need the next step's stance half only; that step's swings are
solved once the step is sent (:meth:`~klaw_ocp.stepwise.StepwiseWalk.finish_ahead`), so an ask
waits for less. A closed page cancels both tasks; the step being solved, if any, finishes in its
thread (a few milliseconds) and is dropped with the walk.
"""
from __future__ import annotations

import asyncio
import json

from starlette.websockets import WebSocketDisconnect

from ..config import ExperimentConfig
from ..errors import ConfigError, ConvergenceError
from ..result_files.bvh import bvh_text
from ..body_motion import body_motion
from ..stepwise import StepwiseWalk
from .limits import MessageRate, ServeLimits
from .protocol import Refused, apply_settings, parse, skeleton_message, step_text, strips_text


class LiveSession:
    """The walk of one websocket connection."""

    def __init__(self, websocket, base: dict, limits: ServeLimits):
        self.ws, self.base, self.limits = websocket, base, limits
        self.rate = MessageRate(limits.max_messages_per_s, limits.burst)
        self.live: StepwiseWalk | None = None
        self.asked = 0               # the last step the page asked for (step 0 it needs at once)
        self.sent = -1               # the last step sent
        self.strips: dict = {}       # step -> its strips' JSON, written once it was solved whole
        self.wake = asyncio.Event()  # something changed: the sender looks again
        self.send_lock = asyncio.Lock()

    async def send(self, message: dict) -> None:
        async with self.send_lock:
            await self.ws.send_text(json.dumps(message, allow_nan=False))

    async def run(self) -> None:
        """Serve the connection until the page closes it."""
        sender = asyncio.create_task(self._hand_out())
        try:
            await self._start({})
            await self._read()
        finally:
            sender.cancel()
            self.live = None

    # -- reading the page ---------------------------------------------------------------------
    async def _read(self) -> None:
        while True:
            event = await self.ws.receive()
            if event["type"] == "websocket.disconnect":
                return
            text = event.get("text") if event.get("text") is not None else event.get("bytes")
            if not self.rate.allow():
                await self._refuse(Refused("message", f"message: got more than {self.limits.max_messages_per_s:g} "
                                                      f"messages a second, allowed at most that; this one was dropped"))
                continue
            try:
                await self._handle(parse(text, self.limits.max_message_bytes))
            except Refused as err:
                await self._refuse(err)
            except ConfigError as err:        # a value outside the envelope or the config's ranges
                await self._refuse(Refused(str(err).split(":", 1)[0], str(err)))
            except Exception as err:          # noqa: BLE001 - one page's bad message never ends the server
                await self._refuse(Refused("message", f"message: could not be handled "
                                                      f"({type(err).__name__}: {err}); the walk goes on"))

    async def _refuse(self, err: Refused) -> None:
        await self.send({"type": "refused", "field": err.field, "message": " ".join(str(err).split())})

    async def _handle(self, message: dict) -> None:
        kind = message["type"]
        if kind == "start":
            await self._start(message["settings"])
        elif kind == "set":
            if self.live is None or self.live.ended:
                raise Refused("walk", "walk: got a change with no walk going on, allowed once a walk is started")
            values = message["values"]
            parameters = {k: v for k, v in values.items() if not k.startswith("attributes.")}
            attributes = {k.split(".", 1)[1]: v for k, v in values.items() if k.startswith("attributes.")}
            # all checked before any is taken: a refused value changes nothing
            target = self.live.request(attributes or None, **parameters)
            await self.send({"type": "accepted", "target": target})
        elif kind == "stop":
            if self.live is not None:
                self.live.stop()
                await self.send({"type": "stopping"})
        elif kind == "need":
            self.asked = max(self.asked, min(message["step"], self.sent + self.limits.steps_ahead))
            self.wake.set()
        elif kind == "export":
            await self._export()

    async def _start(self, settings: dict) -> None:
        """A new walk with ``settings``; refused (the old walk going on) if they are not a walk."""
        config = ExperimentConfig.from_mapping(apply_settings(self.base, settings))
        live = await asyncio.to_thread(StepwiseWalk, config)
        self.live, self.asked, self.sent, self.strips = live, 0, -1, {}
        await self.send({**skeleton_message(live.body), "fps": live.spec.fps, "method": live.spec.method,
                         "start_from_rest": live.spec.start_from_rest})
        self.wake.set()

    async def _export(self) -> None:
        """The walk so far, every step the page has been sent (the whole walk once it ended), as
        walk.bvh and as the config that ``klaw-ocp run`` solves into the same walk.bvh, byte for
        byte (:meth:`~klaw_ocp.stepwise.StepwiseWalk.walk_so_far`)."""
        live = self.live
        if live is None or self.sent < 0:
            raise Refused("export", "export: got a walk with no step on the page yet, allowed once its first "
                                    "step is shown")
        steps = self.sent + 1
        config = live.reproducing_config(steps)
        fps = live.spec.fps
        bvh = await asyncio.to_thread(lambda: bvh_text(body_motion(live.walk_so_far(steps), fps), live.body, fps))
        header = ("The walk of a klaw-ocp serve session: `klaw-ocp run` of this file solves the same steps\n"
                  "and writes the same walk.bvh, byte for byte (docs/serve.md).")
        await self.send({"type": "export", "bvh": bvh, "config": config.resolved_yaml(header),
                         "name": config.name, "steps": steps})

    # -- handing out steps --------------------------------------------------------------------
    async def _hand_out(self) -> None:
        """Solve and send each step the page asks for. A step that fails ends its walk with one
        line ("failed"); a page gone mid-send ends the task; nothing here ends the server."""
        try:
            while True:
                await self.wake.wait()
                self.wake.clear()
                await self._send_asked(self.live)
        except (WebSocketDisconnect, RuntimeError, OSError):   # the page closed while a step was sent
            return

    async def _send_asked(self, live) -> None:
        while live is not None and live is self.live and self.sent < self.asked:
            ready = await self._solving(live, live.next_step)
            if live is not self.live or ready is None:   # failed, a new walk started meanwhile, or none left
                return
            self.sent = ready.index
            planned = live.last_planned
            async with self.send_lock:
                await self.ws.send_text(step_text(ready, live.attributes,
                                                  {"step": planned.index, "step_frequency": planned.parameters.step_frequency_spm,
                                                   "speed": planned.parameters.speed_kmh}, self.strips.pop(ready.index, None)))
            if live.ended and self.sent == len(live.walk.steps) - 1:
                await self.send({"type": "ended", "steps": len(live.walk.steps)})
                return
            # the rest of the next step now, while the page shows the step before this one (its frames
            # read only its stance half: StepwiseWalk.finish_ahead), and its strips' text: the page's
            # next ask waits for less (a failure is said in _solving; next_step then has none)
            finished = await self._solving(live, lambda: self._finish_ahead(live))
            if finished is not None and live is self.live:
                self.strips[finished[0]] = finished[1]

    @staticmethod
    def _finish_ahead(live) -> tuple | None:
        """The rest of the next step, and its strips' JSON (in the worker thread)."""
        result = live.finish_ahead()
        return None if result is None else (result.index, strips_text(live.rows(result.index)))

    async def _solving(self, live, solve):
        """``solve()`` in a worker thread; a fault ends this walk with one line ("failed"), never the server."""
        try:
            return await asyncio.to_thread(solve)
        except Exception as err:     # noqa: BLE001 - ConvergenceError, or any fault of one walk
            live.ended = True
            words = str(err) if isinstance(err, (ConvergenceError, ConfigError)) else f"{type(err).__name__}: {err}"
            await self.send({"type": "failed", "message": " ".join(words.split())})
            return None
