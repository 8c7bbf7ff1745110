"""Serving the explorer: ``serve(host, port)`` on 127.0.0.1 by default, every resource
from this server (no CDN: the page works offline)."""
from __future__ import annotations

import panel as pn

from .app import Explorer

__all__ = ["serve", "make_page"]


def make_page(preset: str | None = None):
    """A new session's page (Panel calls it once per browser tab)."""
    explorer = Explorer(preset)
    page = explorer.page()
    pn.state.onload(explorer.start)
    return page


def serve(host: str = "127.0.0.1", port: int = 5006, preset: str | None = None,
          show: bool = False, on_ready=None) -> None:
    """Serve the explorer at ``http://host:port/`` until interrupted; ``show`` opens a
    browser; ``on_ready(url)`` is called once the server listens."""
    pn.config.inline = True
    url = f"http://{host}:{port}/"
    origins = [f"{host}:{port}", f"localhost:{port}"]
    server = pn.serve({"/": lambda: make_page(preset)}, address=host, port=port, show=show,
                      start=False, websocket_origin=origins, title="fsicas explore",
                      threaded=False, print_url=False)
    if on_ready is not None:
        on_ready(url)
    server.start()
    server.io_loop.start()
