"""The serving end: backends of a world answered over framed JSON (see
:mod:`backends.remote`), driven from the world's own loop."""
from __future__ import annotations

import json
from collections.abc import Callable

from rll_bt.backend import Backend, BackendError, BackendUnavailable, CapabilityError
from rll_bt.comm.jsonlink import FramedServer

from .codec import ERRORS, METHODS, encode


class BackendServer(FramedServer):
    """Serves backends by (team, number) on ``host:port`` (0: ephemeral, see :attr:`port`)."""

    def __init__(self, resolve: Callable[[str, int], Backend], now: Callable[[], float],
                 host: str = "127.0.0.1", port: int = 0):
        super().__init__(host, port)
        self.resolve = resolve
        self.now = now
        self.calls = 0

    def poll(self, timeout: float) -> int:
        served = super().poll(timeout)
        self.calls += served
        return served

    def answer(self, conn, body: bytes) -> dict:
        try:
            req = json.loads(body)
            rid = req.get("id")
        except ValueError as exc:
            return {"id": None, "e": "BackendError", "msg": f"bad request: {exc}"}
        method = req.get("m")
        if method not in METHODS:
            return {"id": rid, "e": "BackendError", "msg": f"unknown method {method!r}"}
        try:
            team, number = req.get("robot", ["CYAN", 1])
            backend = self.resolve(str(team), int(number))
            target = getattr(backend, method)
            value = target if method == "capabilities" else target(*req.get("a", []))
            return {"id": rid, "r": encode(value), "now": self.now()}
        except (CapabilityError, BackendUnavailable, BackendError) as exc:
            return {"id": rid, "e": type(exc).__name__ if type(exc).__name__ in ERRORS else "BackendError",
                    "msg": str(exc)}
        except Exception as exc:
            return {"id": rid, "e": "BackendError", "msg": f"{type(exc).__name__}: {exc}"}
