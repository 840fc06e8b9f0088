"""A refbox elsewhere, seen from its controller stream (TCP 4444 of the real
refbox, or ``rll-bt refbox sim``'s).

:class:`ControllerLink` is what a world hosting a game against such a
refbox needs of it: it sends the operator's commands (SetTeamName,
SetGamePhase, SetGameState, never encrypted) and reads what the refbox
tells every controller (net.clp): GameState (phase, state, game time,
points), MachineInfo with the restricted information (every machine's zone,
rotation, ring colours and state, once the field is generated), OrderInfo
and AttentionMessage.  From those it keeps the game as a
:class:`~rll_bt.contracts.RefboxView` reads it:

- ``status()``: the last GameState;
- ``awards()``: each change of a team's points, as the refbox announced it
  (the wire carries totals, not the reasons: ``reason`` says so);
- ``deliveries()``: each order's delivered count going up (its points are
  in the award of that moment, not here: 0);
- ``field()``: where the machines stand, as a stored game, once every
  machine has a zone;
- ``orders()``, ``machine_states()``, ``attention`` (every text shown).
"""
from __future__ import annotations

from rll_bt.contracts import Award, Delivery, GameStatus

TEAMS = ("CYAN", "MAGENTA")
REASON = "points announced by the refbox (the wire carries no reason)"


class ControllerLink:
    """The stream at ``host``:``port`` of a refbox playing ``profile`` (a name).
    ``transport``: a ready stream client instead (tests)."""

    def __init__(self, host: str, port: int, profile: str, *, transport=None):
        from rll_bt import msgs
        from rll_bt.comm import MessageRegistry, StreamClient
        self.profile = profile
        self.ms = msgs.message_set(profile)
        self.address = f"{host}:{port}"
        self.stream = transport or StreamClient(host, int(port), registry=MessageRegistry.from_message_set(self.ms),
                                                channel="refbox-stream")
        self.game_state = None
        self.machines: dict[str, object] = {}         # name -> the last Machine message
        self.orders_seen: dict[int, object] = {}      # id -> the last Order message
        self.attention: list[tuple[float, str]] = []
        self._awards: list[Award] = []
        self._deliveries: list[Delivery] = []
        self._points = dict.fromkeys(TEAMS, 0)
        self.received = 0

    # -- sending ---------------------------------------------------------------------
    def wait_connected(self, timeout: float) -> bool:
        return self.stream.wait_connected(timeout)

    def send(self, name: str, **fields) -> bool:
        """An operator command (``"SetGamePhase", phase="PRODUCTION"``)."""
        msg = self.ms.get(name)()
        for key, value in fields.items():
            if isinstance(value, str) and msg.DESCRIPTOR.fields_by_name[key].enum_type is not None:
                value = msg.DESCRIPTOR.fields_by_name[key].enum_type.values_by_name[value].number
            setattr(msg, key, value)
        ok = self.stream.send(msg)
        self.stream.wait(0.0)
        return ok

    # -- receiving ---------------------------------------------------------------------
    def poll(self) -> int:
        """Read what arrived; returns how many messages."""
        self.stream.wait(0.0)
        n = 0
        for rec in self.stream.receive():
            n += 1
            kind = rec.msg.DESCRIPTOR.name
            handler = getattr(self, f"_on_{kind}", None)
            if handler is not None:
                handler(rec.msg)
        self.received += n
        return n

    def _enum(self, msg, field: str) -> str:
        return msg.DESCRIPTOR.fields_by_name[field].enum_type.values_by_number[getattr(msg, field)].name

    def _on_GameState(self, msg) -> None:
        self.game_state = msg
        phase, t = self._enum(msg, "phase"), self._time(msg)
        for team, field in (("CYAN", "points_cyan"), ("MAGENTA", "points_magenta")):
            now = int(getattr(msg, field))
            if now != self._points[team]:
                self._awards.append(Award(team, phase, now - self._points[team], REASON, t))
                self._points[team] = now

    def _on_MachineInfo(self, msg) -> None:
        for m in msg.machines:
            self.machines[m.name] = m

    def _on_OrderInfo(self, msg) -> None:
        t = self._time(self.game_state) if self.game_state is not None else 0.0
        for o in msg.orders:
            before = self.orders_seen.get(o.id)
            for team, field in (("CYAN", "quantity_delivered_cyan"), ("MAGENTA", "quantity_delivered_magenta")):
                was = getattr(before, field) if before is not None else 0
                for _ in range(int(getattr(o, field)) - int(was)):
                    how = "in-time" if t <= o.delivery_period_end else "late"
                    self._deliveries.append(Delivery(team, t, 0, int(o.id), how))
            self.orders_seen[o.id] = o

    def _on_AttentionMessage(self, msg) -> None:
        t = self._time(self.game_state) if self.game_state is not None else 0.0
        self.attention.append((t, msg.message))

    @staticmethod
    def _time(gs) -> float:
        return gs.game_time.sec + gs.game_time.nsec / 1e9

    # -- the view ------------------------------------------------------------------------
    def status(self) -> GameStatus:
        gs = self.game_state
        if gs is None:
            return GameStatus("PRE_GAME", "WAIT_START", 0.0, None, dict(self._points))
        return GameStatus(self._enum(gs, "phase"), self._enum(gs, "state"), self._time(gs), None,
                          dict(self._points))

    def awards(self) -> list[Award]:
        return list(self._awards)

    def deliveries(self) -> list[Delivery]:
        return list(self._deliveries)

    def machine_states(self) -> dict[str, str]:
        return {name: m.state for name, m in self.machines.items()}

    def field(self, machines) -> object | None:
        """The refbox's field as a :class:`~backends.sim.stored.StoredGame` once every one
        of ``machines`` has a zone (the generation is finished), else None."""
        if not all(m in self.machines and self.machines[m].HasField("zone") and self.machines[m].zone
                   for m in machines):
            return None
        from ..stored import StoredGame
        info = self.ms.MachineInfo()
        info.machines.extend(self.machines[m] for m in machines)
        return StoredGame.from_machine_info(info, self.profile)

    def orders(self) -> list[dict]:
        out = []
        for o in sorted(self.orders_seen.values(), key=lambda o: o.id):
            out.append({"id": int(o.id), "complexity": int(o.complexity), "quantity": int(o.quantity_requested),
                        "begin": int(o.delivery_period_begin), "end": int(o.delivery_period_end),
                        "gate": int(o.delivery_gate), "competitive": bool(o.competitive),
                        "delivered": {"CYAN": int(o.quantity_delivered_cyan),
                                      "MAGENTA": int(o.quantity_delivered_magenta)}})
        return out

    def close(self) -> None:
        self.stream.close()


__all__ = ["ControllerLink", "REASON"]
