"""The live page: ``rll-bt view`` and ``rll-bt sim --view``.

A small web page this project serves itself (:mod:`.server`, the standard
library's HTTP server; the page is plain HTML, SVG, JavaScript and CSS in
``static/``, no build step) showing a game as it is played or replayed:
the field with its stations and the robots (true pose, estimate and path),
the orders and their delivery windows, the score over time, and each
robot's behaviour tree with the running branch highlighted.  It follows a
:class:`~.state.ViewState`, fed by

- a lockstep game's watch (``rll-bt sim --view``: :func:`attach`, through
  :attr:`rll_bt.watch.sink.Watch.listeners`),
- a recording (``rll-bt view game.mcap``: :class:`~.sources.Playback`),
- a Foxglove WebSocket server (``rll-bt view ws://localhost:8765``, any
  ``--live`` game, agent or team server: :class:`~.sources.FoxgloveSource`).
"""
from __future__ import annotations

from .server import ViewServer
from .state import ViewState

DEFAULT_PORT = 8766


def attach(watch, *, port: int, profile: str, meta: dict | None = None, host: str = "127.0.0.1") -> ViewServer:
    """Serve the page of what ``watch`` (a :class:`~rll_bt.watch.sink.Watch`) carries on ``port``."""
    state = ViewState(profile, meta={"source": "live", **(meta or {})})
    watch.listeners.append(state.feed)
    return ViewServer(state, port=port, host=host)


__all__ = ["DEFAULT_PORT", "ViewServer", "ViewState", "attach"]
