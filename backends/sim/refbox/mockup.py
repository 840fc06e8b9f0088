"""Mockup stations: production without robots, as the real refbox plays it in simulation.

Standalone (``rll-bt refbox sim``), the refbox's world has no robots, so no
workpiece ever reaches an RS, CS or DS.  In mockup mode a *virtual robot*
per team does the carrying, and a team that only sends PrepareMachine
messages can play production.  Stations keep every rule they have
(validation, breaking, down periods, lights, scoring); the mockup only
takes products off outputs and feeds inputs.

The model (times are production game seconds):

- **Take.**  ``take_after`` seconds after a BS, RS or CS product is READY-AT-OUTPUT
  it is taken off the output (the station goes WAIT-IDLE, then IDLE) and the
  team *holds* it, one held workpiece per station output it came from (a newer
  product of the same station replaces the older one, which is dropped).  The
  cap-less carrier a RETRIEVE_CAP leaves is taken too but not held: a robot
  would discard it or put it on a slide (see the ring cost below).
- **Feed.**  A prepared RS, CS or DS of the team waits until the team holds a
  workpiece it can work on, then reserves the newest such workpiece and is fed
  it ``feed_after`` seconds later (the robot's drive).  RS: no cap, fewer than
  three rings.  CS MOUNT_CAP: no cap.  DS: the newest capped one, else the
  newest of any kind.  CS RETRIEVE_CAP is fed a cap carrier from its shelf
  (the station's cap colour), without touching what the team holds.  A
  workpiece whose station is no longer PREPARED when it arrives (broken,
  reset) is dropped.  A station whose team holds nothing fitting stays
  PREPARED, as a real one waiting for a robot.
- **Ring cost.**  A PrepareMachine of an RS stands for the additional bases
  the instructed ring costs: the slide is topped up to the cost, each base a
  slide feed as a robot's would be (+``additional_base`` points, 2 in 2016 and
  2025; bases already loaded count, so nothing is fed twice).  The mount
  then consumes them as usual.
- **Scoring** is the rule set's: rings, pre-cap (2016) and cap points come with
  a delivery that counts for an order, judged on the virtual workpiece the
  DS consumed (2016: by colours and gate; 2025: by the instructed order id);
  2025 scores a retrieved cap at the CS.

Every take, feed and drop is a ``workpiece`` event with ``mockup=True``.
"""
from __future__ import annotations

import heapq
import itertools

from rll_bt.rules import TEAMS

from . import events as E
from .stations import DOWN, PREPARED, READY_AT_OUTPUT, Station
from .world import Workpiece, describe

#: station kinds the mockup drives (the 2025 storage station is left alone)
KINDS = ("BS", "RS", "CS", "DS")
TAKE, FEED = "take", "feed"


class Mockup:
    """The virtual robots of a :class:`~.game.RefboxGame` (``game``) in mockup mode.

    ``take_after``: game s a product waits at an output before it is taken;
    ``feed_after``: game s from a prepared station finding a workpiece to that
    workpiece on its input.  The game calls :meth:`on_state` on every station
    state change, :meth:`fire` once its stations are updated, stops game time
    at :meth:`next_due`, and calls :meth:`clear` when PRODUCTION ends.
    """

    def __init__(self, game, take_after: float = 5.0, feed_after: float = 10.0):
        if take_after < 0 or feed_after < 0:
            raise ValueError("mockup delays must be >= 0 game seconds")
        self.game = game
        self.take_after, self.feed_after = float(take_after), float(feed_after)
        #: team -> station whose output it came from -> (workpiece, game time taken)
        self.held: dict[str, dict[str, tuple[Workpiece, float]]] = {t: {} for t in TEAMS}
        self._waiting: dict[str, None] = {}      # prepared stations without a workpiece, in order
        self._timers: list = []                  # heap of (due, seq, action, machine, payload)
        self._seq = itertools.count()

    # -- game hooks ------------------------------------------------------------------
    def next_due(self) -> float | None:
        """Game time of the next take or feed, None when nothing is pending."""
        return self._timers[0][0] if self._timers else None

    def clear(self) -> None:
        """Forget pending takes, feeds and held workpieces (production is over)."""
        self._timers.clear()
        self._waiting.clear()
        for h in self.held.values():
            h.clear()

    def on_state(self, st: Station, previous: str) -> None:
        """``st`` changed state at its game time ``st.now``."""
        if st.kind not in KINDS:
            return
        if not st.awaits_workpiece():
            self._waiting.pop(st.name, None)
        if previous == DOWN:             # back up: what was pending goes on
            return
        if st.state == READY_AT_OUTPUT:
            discard = getattr(st.instruction, "operation", None) == "RETRIEVE_CAP"
            self._schedule(st.now + self.take_after, TAKE, st.name, discard)
        elif st.state == PREPARED and st.kind != "BS":
            if st.kind == "RS":
                need = self.game.ring_cost(st.instruction.ring_color)
                while st.slide_loaded < need and st.state == PREPARED:
                    st.load_slide()
            if getattr(st.instruction, "operation", None) == "RETRIEVE_CAP":
                self._schedule(st.now + self.feed_after, FEED, st.name,
                               (st.instruction, st.carrier()))
            else:
                self._waiting[st.name] = None
                self._match(st.team, st.now)

    def fire(self, game_time: float) -> None:
        """Run every take and feed due by ``game_time``, in time order."""
        while self._timers and self._timers[0][0] <= game_time:
            due, _, action, machine, payload = heapq.heappop(self._timers)
            st = self.game.stations[machine]
            if action == TAKE:
                self._take(st, due, payload)
            else:
                self._feed(st, *payload)

    # -- internals ----------------------------------------------------------------------
    def _schedule(self, due: float, action: str, machine: str, payload) -> None:
        heapq.heappush(self._timers, (due, next(self._seq), action, machine, payload))

    def _take(self, st: Station, t: float, discard: bool) -> None:
        if st.state != READY_AT_OUTPUT and not (st.state == DOWN
                                                and st.prev_state == READY_AT_OUTPUT):
            return                       # broken or reset meanwhile: the product is gone
        slot = st.out_slot
        taken = self.game.world.remove_workpiece(st.name, slot)
        if taken is None:
            return
        wp = describe(taken)
        st.on_take(slot, taken)
        if discard:
            self._event(st, f"mockup: {st.team} took {wp} off {st.name} {slot} and discarded it",
                        wp, "discarded")
            return
        held = self.held[st.team]
        old = held.pop(st.name, None)
        if old is not None:
            self._event(st, f"mockup: {st.team} dropped {old[0]} (a newer product of {st.name})",
                        old[0], "dropped")
        held[st.name] = (wp, t)
        self._event(st, f"mockup: {st.team} took {wp} off {st.name} {slot}", wp, "taken")
        self._match(st.team, t)

    def _match(self, team: str, t: float) -> None:
        """Give each waiting prepared station of ``team`` the newest held workpiece it can
        work on; it arrives ``feed_after`` later."""
        for name in list(self._waiting):
            st = self.game.stations[name]
            if st.team != team:
                continue
            source = self._pick(st, self.held[team])
            if source is None:
                continue
            wp, _ = self.held[team].pop(source)
            del self._waiting[name]
            self._event(st, f"mockup: {team} carries {wp} from {source} to {name}", wp,
                        "carried", source=source)
            self._schedule(t + self.feed_after, FEED, name, (st.instruction, wp))

    @staticmethod
    def _pick(st: Station, held: dict[str, tuple[Workpiece, float]]) -> str | None:
        def fits(wp: Workpiece) -> bool:
            if st.kind == "RS":
                return wp.cap is None and len(wp.rings) < 3
            if st.kind == "CS":
                return wp.cap is None
            return True

        def rank(item):
            (wp, since) = item[1]
            return (st.kind == "DS" and wp.cap is not None, since)
        choice = [item for item in held.items() if fits(item[1][0])]
        return max(choice, key=rank)[0] if choice else None

    def _feed(self, st: Station, instruction, wp: Workpiece) -> None:
        prepared = st.awaits_workpiece() or (st.state == DOWN and st.prev_state == PREPARED)
        if not prepared or st.instruction is not instruction:
            self._event(st, f"mockup: {st.team} dropped {wp}, {st.name} is no longer prepared",
                        wp, "dropped")
            return
        self._event(st, f"mockup: {st.team} fed {wp} to {st.name}", wp, "fed")
        st.feed(wp)

    def _event(self, st: Station, text: str, wp: Workpiece, what: str, **data) -> None:
        self.game.emit(E.WORKPIECE, text, team=st.team, machine=st.name, workpiece=wp,
                       mockup=True, what=what, **data)


__all__ = ["Mockup", "KINDS"]
