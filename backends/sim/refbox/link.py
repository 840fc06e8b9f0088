"""The station link: the refbox in one process, the world's stations in another.

In a real game the refbox runs on its own machine and talks to the
production stations over the network.  With ``rll-bt sim --processes`` the
world's process owns PyBullet, the robots and the stations' physical state
and serves the station API over TCP (:class:`StationServer`); the refbox's
process (``rll-bt refbox sim --world remote:HOST:PORT``) sees the stations
only through :class:`RemoteWorld`, a :class:`~.world.RefboxWorld`::

    # the world's process
    server = StationServer(world)          # port 0: ephemeral, see server.port
    while ...:
        world.step(dt)                     # robots' puts and takes are pushed at once
        server.poll(0.005)                 # the refbox's calls answered
    server.command("start")                # operator commands (see below)

    # the refbox's process
    world = RemoteWorld("127.0.0.1:PORT")
    game = RefboxGame(profile, WallClock(), world, ...)
    world.on_command(lambda cmd: ...)
    while ...:
        world.pump()                       # slot events and commands, in order
        node.step()

Wire: the framing of :mod:`rll_bt.comm.jsonlink`, each frame a 4-byte
big-endian length and a UTF-8 JSON object.

- The refbox calls: ``{"id", "m": method, "a": [args], "k": {kwargs}}``,
  answered in order by ``{"id", "r": result}`` or ``{"id", "e": "KeyError" |
  "ValueError" | "RuntimeError", "msg"}``.  Methods: ``hello`` (-> ``{"layout":
  FieldLayout.to_dict(), "robots": [[team, number], ...], "time": world
  seconds}``), ``set_lights(machine, red=, yellow=, green=)``,
  ``lights(machine)``, ``spawn_workpiece(machine, slot, base, rings, cap)``,
  ``remove_workpiece(machine, slot, id)``, ``workpiece_at(machine, slot)``,
  ``workpieces_at(machine, slot)``; workpieces as ``{"id", "base", "rings",
  "cap"}`` (None for none).  A call returns once the world applied it, so a
  base the refbox dispensed is in the world before any robot hears of it.
- The world pushes (frames without ``id``), in the order they happened:
  ``{"ev": "put" | "take" | "drop", "machine", "slot", "wp", "robot": [team, number],
  "t": world seconds}`` when a robot put a workpiece on a slot or took one
  off (pushed while no refbox is connected wait for the first one), and the
  operator's commands of the simulated game, whose host the world's process
  is: ``{"ev": "command", "op": "start"}`` and ``{"ev": "command", "op":
  "down", "machine", "seconds"}``.
- The world's time, ``{"ev": "time", "t": world seconds}``, each time the world
  stepped (:meth:`StationServer.clock`; not kept for a refbox yet to connect).
  The refbox's process runs its clock on it (:attr:`RemoteWorld.time`,
  :meth:`RemoteWorld.on_time`): a world that falls behind the wall clock (a
  loaded machine, a long physics step) holds the game's time with it, so
  the game's seconds are the world's, as in a lockstep game.

Neither side blocks on the other: the server never waits for a slow refbox
(what it has not read waits in its buffer); a call waits for a slow world
up to ``timeout`` seconds.  A world that closed the link (its process
ended) or does not answer in time raises :class:`~.world.WorldLost` from
any call or :meth:`RemoteWorld.pump`.
"""
from __future__ import annotations

import json
from collections.abc import Callable

from rll_bt.comm.jsonlink import FramedClient, FramedServer, LinkClosed, parse_address

from .world import SlotEvent, Workpiece, WorldLost

METHODS = ("hello", "set_lights", "lights", "spawn_workpiece", "remove_workpiece", "workpiece_at",
           "workpieces_at")
ERRORS = {"KeyError": KeyError, "ValueError": ValueError}


def encode_workpiece(wp) -> dict | None:
    if wp is None:
        return None
    return {"id": getattr(wp, "id", None), "base": wp.base, "rings": list(wp.rings), "cap": wp.cap}


def decode_workpiece(d: dict | None) -> Workpiece | None:
    if d is None:
        return None
    return Workpiece(d["base"], tuple(d["rings"]), d["cap"], d.get("id"))


class StationServer(FramedServer):
    """Serves ``world``'s station API (any :class:`~.world.RefboxWorld` with a
    ``layout``; the PyBullet world in ``rll-bt sim --processes``) on
    ``host:port``.  Drive it with :meth:`poll` from the world's loop."""

    def __init__(self, world, host: str = "127.0.0.1", port: int = 0):
        super().__init__(host, port)
        self.world = world
        self._waiting: list[dict] = []         # slot events before any refbox connected
        self._told: float | None = None        # the world time last pushed
        world.add_slot_listener(self._on_slot)

    def _on_slot(self, ev) -> None:
        robot = getattr(ev, "robot", None)
        self._push({"ev": ev.kind, "machine": ev.machine, "slot": ev.slot, "wp": encode_workpiece(ev.workpiece),
                    "robot": list(robot) if robot is not None else None, "t": getattr(ev, "time", None)})

    def _push(self, obj: dict) -> None:
        if not self.push(obj):
            self._waiting.append(obj)

    def connected(self, conn) -> None:
        for obj in self._waiting:
            self.send(conn, obj)
        self._waiting.clear()

    def clock(self, t: float) -> None:
        """Tell the refbox the world's time ``t`` (after each step); dropped while none is connected."""
        if t != self._told:
            self._told = t
            self.push({"ev": "time", "t": float(t)})

    def command(self, op: str, **data) -> None:
        """An operator command to the refbox (``start``; ``down`` with ``machine``
        and ``seconds``).  RuntimeError when no refbox is connected."""
        if not self.push({"ev": "command", "op": op, **data}):
            raise RuntimeError("no refbox is connected to the station link")

    def answer(self, conn, body: bytes) -> dict:
        try:
            req = json.loads(body)
        except ValueError as exc:
            return {"id": None, "e": "ValueError", "msg": f"bad request: {exc}"}
        rid, method = req.get("id"), req.get("m")
        if method not in METHODS:
            return {"id": rid, "e": "ValueError", "msg": f"unknown method {method!r}"}
        try:
            return {"id": rid, "r": self._call(method, req.get("a", []), req.get("k", {}))}
        except KeyError as exc:
            return {"id": rid, "e": "KeyError", "msg": str(exc.args[0]) if exc.args else ""}
        except ValueError as exc:                    # a full slot (SlotError), a bad value
            return {"id": rid, "e": "ValueError", "msg": str(exc)}
        except Exception as exc:
            return {"id": rid, "e": "RuntimeError", "msg": f"{type(exc).__name__}: {exc}"}

    def _call(self, method: str, args: list, kwargs: dict):
        w = self.world
        if method == "hello":
            robots = getattr(w, "robots", None) or {}
            return {"layout": w.layout.to_dict(), "robots": [list(r) for r in robots],
                    "time": getattr(w, "time", None)}
        if method == "set_lights":
            w.set_lights(*args, **kwargs)
            return None
        if method == "lights":
            return w.lights(*args)
        if method == "workpieces_at":
            return [encode_workpiece(wp) for wp in w.workpieces_at(*args)]
        return encode_workpiece(getattr(w, method)(*args))


class RemoteWorld:
    """The stations of a world served at ``address`` ("HOST:PORT") by a
    :class:`StationServer`, as a :class:`~.world.RefboxWorld`.  ``layout``
    and ``robots`` are the world's, as it said at connecting; ``timeout``:
    seconds a call may wait for a slow world."""

    def __init__(self, address: str, timeout: float = 60.0):
        self.address = address
        try:
            host, port = parse_address(address, "the world's address")
        except ValueError as exc:
            raise WorldLost(str(exc)) from None
        try:
            self._link = FramedClient(host, port, timeout)
        except OSError as exc:
            raise WorldLost(f"cannot reach the world at {address}: {exc}") from None
        self._listeners: list[Callable] = []
        self._commands: list[Callable[[dict], None]] = []
        self._clocks: list[Callable[[float], None]] = []
        hello = self._call("hello")
        from ..layout import FieldLayout
        self.layout = FieldLayout.from_dict(hello["layout"])
        self.robots = [tuple(r) for r in hello["robots"]]
        #: the world's time as it last said (None: it never did)
        self.time: float | None = hello.get("time")

    def _call(self, method: str, *args, **kwargs):
        try:
            reply = self._link.call({"m": method, "a": list(args), "k": kwargs})
        except LinkClosed:
            raise WorldLost(f"the world at {self.address} closed the station link") from None
        except TimeoutError:
            self._link.close()
            raise WorldLost(f"the world at {self.address} did not answer {method} "
                            f"in {self._link.timeout:g} s") from None
        except (OSError, ValueError) as exc:
            self._link.close()
            raise WorldLost(f"the station link to {self.address} broke: {exc}") from None
        if "e" in reply:
            raise ERRORS.get(reply["e"], RuntimeError)(reply.get("msg", reply["e"]))
        return reply.get("r")

    # -- RefboxWorld ------------------------------------------------------------------
    def set_lights(self, machine: str, *, red: str = "OFF", yellow: str = "OFF", green: str = "OFF") -> None:
        self._call("set_lights", machine, red=red, yellow=yellow, green=green)

    def lights(self, machine: str) -> dict[str, str]:
        return self._call("lights", machine)

    def spawn_workpiece(self, machine: str, slot: str, base: str, rings=(), cap=None) -> Workpiece:
        return decode_workpiece(self._call("spawn_workpiece", machine, slot, base, list(rings), cap))

    def remove_workpiece(self, machine: str, slot: str, workpiece_id=None) -> Workpiece | None:
        return decode_workpiece(self._call("remove_workpiece", machine, slot, workpiece_id))

    def workpiece_at(self, machine: str, slot: str) -> Workpiece | None:
        return decode_workpiece(self._call("workpiece_at", machine, slot))

    def workpieces_at(self, machine: str, slot: str) -> tuple[Workpiece, ...]:
        return tuple(decode_workpiece(d) for d in self._call("workpieces_at", machine, slot))

    def add_slot_listener(self, fn: Callable) -> None:
        self._listeners.append(fn)

    # -- the link ------------------------------------------------------------------------
    def on_command(self, fn: Callable[[dict], None]) -> None:
        """Call ``fn(command)`` for each operator command (``{"op": "start"}``,
        ``{"op": "down", "machine", "seconds"}``) :meth:`pump` delivers."""
        self._commands.append(fn)

    def on_time(self, fn: Callable[[float], None]) -> None:
        """Call ``fn(world seconds)`` for each time the world pushed, as :meth:`pump` delivers it."""
        self._clocks.append(fn)

    def pump(self) -> int:
        """Deliver what the world pushed since, in order: slot events to the slot
        listeners, commands to :meth:`on_command`'s, the world's time to
        :meth:`on_time`'s.  Returns how many; never waits."""
        try:
            pushed = self._link.pushed()
        except LinkClosed:
            raise WorldLost(f"the world at {self.address} closed the station link") from None
        for msg in pushed:
            if msg.get("ev") == "time":
                self.time = float(msg["t"])
                for fn in list(self._clocks):
                    fn(self.time)
            elif msg.get("ev") == "command":
                cmd = {k: v for k, v in msg.items() if k != "ev"}
                for fn in list(self._commands):
                    fn(cmd)
            elif msg.get("ev") in ("put", "take", "drop"):
                robot = msg.get("robot")
                ev = SlotEvent(msg["ev"], msg["machine"], msg["slot"], decode_workpiece(msg["wp"]),
                               (str(robot[0]), int(robot[1])) if robot else None)
                for fn in list(self._listeners):
                    fn(ev)
        return len(pushed)

    @property
    def closed(self) -> bool:
        return self._link.closed

    def close(self) -> None:
        self._link.close()
