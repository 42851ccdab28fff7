"""The uvicorn server of the playground, set up once for ``klaw-ocp serve`` and the tests alike."""
from __future__ import annotations

#: uvicorn closes a connection whose websocket frame is larger than this, before reading it
#: (the page's messages are checked against ServeLimits.max_message_bytes after)
MAX_FRAME_BYTES = 64 * 1024


def make_server(app, host: str, port: int):
    import uvicorn
    from uvicorn.config import WS_PROTOCOLS
    # the websockets library's current implementation where this uvicorn has it (its legacy one is deprecated)
    ws = "websockets-sansio" if "websockets-sansio" in WS_PROTOCOLS else "websockets"
    return uvicorn.Server(uvicorn.Config(app, host=host, port=port, log_level="warning", ws=ws,
                                         ws_max_size=MAX_FRAME_BYTES, lifespan="off"))
