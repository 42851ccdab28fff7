"""``klaw-ocp serve``: the live walking playground (docs/serve.md). A local web server whose page
shows the body walking in 3D; every slider changes the walk from its next step."""
from __future__ import annotations

import argparse
import sys
import threading
import webbrowser

from ..errors import ConfigError, out_of_range
from ._common import add_set_option, load

HELP = "open the live walking playground in a browser (a local web server)"
DEFAULT_HOST = "127.0.0.1"
DEFAULT_PORT = 8765
#: the walk the playground starts with when no CONFIG is given
DEFAULT_WALK = {"name": "playground", "body": {"height": 1.8, "mass": 80.0},
                "walk": {"speed": 5.0, "steps": 1, "start_from_rest": True}}


def configure(p: argparse.ArgumentParser) -> None:
    p.description = ("Serve a page on which the body walks in 3D, solved step by step one step ahead "
                     "of what is shown: sliders for speed, step length or frequency, body, attributes and "
                     "solver mode change the walk from its next step; the session downloads as walk.bvh "
                     "and as a config that `klaw-ocp run` solves into the same walk. CONFIG gives the "
                     "body, attributes, solver and first parameters (its length and schedule are the page's).")
    p.add_argument("config", nargs="?", metavar="CONFIG", help="experiment YAML file (default: 5 km/h from rest, "
                                                               "1.8 m, 80 kg)")
    p.add_argument("--host", default=DEFAULT_HOST, help=f"address to listen on (default {DEFAULT_HOST}: this "
                                                        f"machine only; another host is served with a warning)")
    p.add_argument("--port", type=int, default=DEFAULT_PORT, help=f"port (default {DEFAULT_PORT}; 0 picks a free one)")
    p.add_argument("--open", action="store_true", help="open the page in the default browser")
    add_set_option(p)
    p.epilog = "example: klaw-ocp serve --open\n         klaw-ocp serve configs/natural_walk.yaml --port 8000"


def handle(args: argparse.Namespace) -> int:
    try:
        import uvicorn  # noqa: F401 - the serve extra's packages, checked before anything else

        from ..serve.app import create_app
        from ..serve.limits import is_loopback
        from ..serve.server import make_server
    except ImportError as err:
        raise ConfigError(f"serve: got no {err.name} module, allowed with the serve extra installed: "
                          f"pip install 'klaw_ocp[serve]'") from None
    if not 0 <= args.port <= 65535:
        raise ConfigError(out_of_range("--port", args.port, "an integer from 0 to 65535"))
    if args.config is not None:
        config = load(args.config, args.sets)
    else:
        import copy

        from ..config import ExperimentConfig
        from ..config_paths import apply_sets
        config = ExperimentConfig.from_mapping(apply_sets(copy.deepcopy(DEFAULT_WALK), args.sets))
    if not is_loopback(args.host):
        print(f"klaw-ocp: warning: serving on {args.host}: any machine that reaches it can open walks "
              f"(at most a few at once, docs/serve.md); the default {DEFAULT_HOST} serves this machine only",
              file=sys.stderr)
    sock = _bound_socket(args.host, args.port)
    server = make_server(create_app(config), args.host, args.port)
    shown_host = f"[{args.host}]" if ":" in args.host else args.host

    def announce():
        # the port is known once the socket is bound (--port 0)
        while not server.started:
            if server.should_exit:
                return
            threading.Event().wait(0.05)
        port = server.servers[0].sockets[0].getsockname()[1] if server.servers else args.port
        url = f"http://{'127.0.0.1' if args.host in ('0.0.0.0', '::') else shown_host}:{port}/"
        print(f"klaw-ocp: serving the playground at {url} (Ctrl-C stops it)", flush=True)
        if args.open:
            webbrowser.open(url)

    threading.Thread(target=announce, daemon=True).start()
    server.run(sockets=[sock])
    return 0


def _bound_socket(host: str, port: int):
    """The listening socket, bound here so that a port in use or an unknown host is one line
    naming the flag (uvicorn would log it and exit)."""
    import socket
    try:
        family = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM)[0][0]
    except (socket.gaierror, UnicodeError) as err:
        raise ConfigError(out_of_range("--host", host, f"an address or name of this machine ({err})")) from None
    try:
        return socket.create_server((host, port), family=family)
    except OSError as err:
        raise ConfigError(out_of_range("--port", port, f"a port free on {host} ({err.strerror or err})")) from None
