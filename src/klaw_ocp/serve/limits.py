"""What keeps the playground's server serving (docs/serve.md, "Serving safely"): the size and rate of
the messages a page may send, how far ahead of the page a walk may run, how many walks at once,
and which pages may open a walk at all (the websocket's Origin)."""
from __future__ import annotations

import ipaddress
import time
from dataclasses import dataclass
from urllib.parse import urlsplit


@dataclass(frozen=True)
class ServeLimits:
    """The server's bounds; each one refused in one line when a page goes past it."""
    #: the longest message a page may send (bytes): the largest, a start with every setting, is
    #: about 400 bytes
    max_message_bytes: int = 4096
    #: messages a page may send per second, on average over ``burst`` messages (a slider dragged
    #: sends about 10 a second; the page throttles it)
    max_messages_per_s: float = 30.0
    burst: int = 60
    #: walks solved at once; a page past it is told so and closed (each walk is a thread of its
    #: own and about 20 MB: docs/serve.md)
    max_sessions: int = 4
    #: how far past the steps sent a page may ask: the step after the one on screen, nothing
    #: further, so a page that stops reading (a background tab, a slow browser) holds one step
    steps_ahead: int = 1


class MessageRate:
    """A token bucket: ``allow()`` is False once a page sends faster than the limit."""

    def __init__(self, per_s: float, burst: int, clock=time.monotonic):
        self.per_s, self.burst, self.clock = per_s, burst, clock
        self.tokens, self.last = float(burst), clock()

    def allow(self) -> bool:
        now = self.clock()
        self.tokens = min(self.burst, self.tokens + (now - self.last) * self.per_s)
        self.last = now
        if self.tokens < 1.0:
            return False
        self.tokens -= 1.0
        return True


def is_loopback(host: str) -> bool:
    """Whether ``host`` (a name or an address) names this machine only."""
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host.strip("[]")).is_loopback
    except ValueError:
        return False


def origin_allowed(origin: str | None, host_header: str | None) -> bool:
    """Whether a websocket opened with this Origin may walk: a page served by this server (the
    origin's host and port are the request's Host), or one on this machine (localhost, 127.0.0.1,
    ::1) when the server is itself on the loopback. Another site's page, which the browser would
    let open a socket to localhost, is refused; so is a request without an Origin, which no
    browser sends."""
    if not origin or not host_header:
        return False
    parts = urlsplit(origin)
    if parts.scheme not in ("http", "https") or not parts.hostname:
        return False
    own = urlsplit(f"http://{host_header}")
    if parts.hostname == own.hostname and (parts.port or 80) == (own.port or 80):
        return True
    return is_loopback(parts.hostname) and own.hostname is not None and is_loopback(own.hostname)
