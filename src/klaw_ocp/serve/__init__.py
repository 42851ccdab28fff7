"""``klaw-ocp serve``: the live walking playground (issue #38, docs/serve.md). A local web server
streams a walk solved step by step (:mod:`klaw_ocp.stepwise`) to a page that shows the body in
3D; every slider changes the walk from its next step that can still change.

- :mod:`.app`: the routes (the page, its files, the websocket);
- :mod:`.session`: one page's walk over its websocket;
- :mod:`.protocol`: the messages, checked into one-line refusals;
- :mod:`.limits`: message size and rate, walks at once, how far ahead, the Origin check.

It needs the ``serve`` extra (starlette, uvicorn with websockets): ``pip install 'klaw_ocp[serve]'``.
"""
