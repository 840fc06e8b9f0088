"""The simulated refbox's game core: pure, clock-driven, no threads, no sockets.

    game = RefboxGame("rcll2016", clock, seed=7, team_cyan="Carologistics")   # or "rcll2025"
    game.start()                  # PRE_GAME -> SETUP, RUNNING
    clock.advance(1.0); game.tick()
    game.points("CYAN"), game.phase, game.pop_events()

:meth:`RefboxGame.tick` moves game time by the clock time passed since the
last tick times ``timing.speed`` (nothing while not RUNNING), switching
phases, firing station timers at their exact times, activating orders.
Robots' beacons, reports, prepare and reset requests come in as plain values
(:meth:`beacon`, :meth:`machine_report`, :meth:`prepare`, :meth:`reset_machine`);
everything that differs between rule sets is asked of ``game.rules``
(:mod:`.rulesets`); the network node
(:mod:`.node`) turns wire messages into these calls and the game state back
into messages.  ``game_time`` is game seconds since the current phase began.
"""
from __future__ import annotations

import logging
import random
from collections import deque

from rll_bt import rules as R
from rll_bt.rules import CYAN, MAGENTA, TEAMS, machine_team

from . import events as E
from . import referee as referee_calls
from . import slot_events, team_requests
from .deliveries import Deliveries, PendingDelivery
from .exploration2016 import ReportEntry
from .ledger import Ledger, PointsEntry
from .mockup import Mockup
from .robots import RobotRegistry
from .rulesets import rules_for
from .stations import CapStation, Station, StationConfig, StorageStation, make_station
from .timing import (
    EXPLORATION,
    INIT,
    PAUSED,
    PHASES,
    POST_GAME,
    PRE_GAME,
    PRODUCTION,
    RUNNING,
    SETUP,
    STATES,
    WAIT_START,
    Timing,
)
from .world import ALL_OFF, TableWorld, Workpiece

log = logging.getLogger("backends.sim.refbox")

REFBOX_TEAM = "LLSF"


class RefboxGame:
    """One game of the simulated refbox.

    ``profile``: a :class:`rll_bt.rules.Profile` or its name.  ``clock``: an
    :class:`rll_bt.clock.Clock`.  ``world``: a
    :class:`~backends.sim.refbox.world.RefboxWorld` (default: an in-memory
    :class:`TableWorld` with a layout generated from the seed).  ``seed``
    fixes placement, light codes, type strings, ring costs, orders and down
    periods.  ``timing``: phase lengths and speed (default: the profile's).
    ``config``: station durations and rules.  ``rules``: the rule set of the
    profile (:func:`~.rulesets.rules_for`).  ``mockup``: play stations without robots
    (:mod:`.mockup`: virtual robots take products off outputs and feed prepared
    stations; off by default, for games with robots in the world); ``game.mockup`` is
    the :class:`~.mockup.Mockup` or None.
    """

    def __init__(self, profile, clock, world=None, *, seed: int = 0,
                 team_cyan: str | None = None, team_magenta: str | None = None,
                 timing: Timing | None = None, config: StationConfig | None = None,
                 feedback_time: float = 5.0, mockup: bool = False):
        self.profile = R.profile(profile) if isinstance(profile, str) or profile is None else profile
        self.clock = clock
        self.seed = int(seed)
        self.rules = rules_for(self.profile)
        self.timing = timing or Timing.from_profile(self.profile)
        self.config = config or StationConfig()
        self.world = world if world is not None else TableWorld.generated(self.profile, self.seed)
        self.layout = self.world.layout
        missing = set(self.profile.machines()) - set(self.layout.machines)
        if missing:
            raise ValueError(f"the world has no station {', '.join(sorted(missing))}")
        self.teams: dict[str, str | None] = {CYAN: team_cyan or None, MAGENTA: team_magenta or None}
        self.phase, self.state = PRE_GAME, WAIT_START
        self.game_time = 0.0
        self.overtime = False
        self.ledger = Ledger()
        self.events: list[E.Event] = []
        self._read = 0
        self.robots = RobotRegistry()
        rs, self.ring_costs = self.profile.ring_setup(self.rng("rings"))
        self._rs_colors = {kind: tuple(colors) for kind, colors in rs.items()}
        self.exploration = self.rules.make_exploration(self.profile, self.layout,
                                                       self.rng("exploration"), feedback_time)
        self.feedback_until: dict[str, float] = {}  # 2016: machine -> time its feedback ends
        self.orders = self.rules.make_orders(self.profile, self.rng("orders"), self.timing,
                                             self.ring_costs)
        self.deliveries = Deliveries(self)
        self.mockup = Mockup(self) if mockup else None
        self.stations: dict[str, Station] = {
            m: make_station(m, machine_team(m), self) for m in self.profile.machines()}
        for m, period in self.rules.down_periods(self.profile, self.rng("down"),
                                                 self.timing).items():
            self.stations[m].down = period
        self._slot_events: deque = deque()
        self.world.add_slot_listener(self._slot_events.append)
        for st in self.stations.values():
            st.set_lights(ALL_OFF)
            if isinstance(st, CapStation):
                st.fill_shelf()
            if isinstance(st, StorageStation):
                for shelf, slot, base, cap in self.profile.prestored:
                    st.put_in_storage(shelf, slot, Workpiece(base, (), cap))
        self._last_now = clock.now()

    def rng(self, stream: str) -> random.Random:
        """A random generator of its own for ``stream``, fixed by the seed."""
        return random.Random(f"{self.seed}/{stream}")

    # -- control -------------------------------------------------------------------
    def set_team(self, color: str, name: str | None) -> bool:
        """Name the team playing ``color`` (SetTeamName); only before PRODUCTION."""
        color = color.upper()
        if color not in TEAMS:
            raise ValueError(f"no team colour {color!r} (CYAN or MAGENTA)")
        if self.phase not in (PRE_GAME, SETUP):
            self._attention(None, f"team names cannot change in {self.phase}")
            return False
        self.teams[color] = name or None
        self.emit(E.STATE, f"team {color} is {name or '(none)'}", team=color)
        return True

    def start(self) -> None:
        """Start the game (the operator's SetGameState RUNNING)."""
        self.set_state(RUNNING)

    def set_state(self, state: str) -> None:
        """SetGameState: RUNNING starts or continues, PAUSED freezes game time."""
        if state not in STATES:
            raise ValueError(f"unknown game state {state!r}")
        self.tick()
        if state == self.state:
            return
        prev, self.state = self.state, state
        self._last_now = self.clock.now()
        self.emit(E.STATE, f"state {prev} -> {state}", previous=prev)
        if state == RUNNING and self.phase == PRE_GAME:
            named = any(self.teams.values())
            self._enter(self.rules.phase_sequence(self.timing)[0] if named
                        else self.rules.training_start(self.timing))
        self._sync_running()

    def set_phase(self, phase: str) -> None:
        """SetGamePhase: switch to ``phase`` now (its game time restarts at 0)."""
        if phase not in PHASES:
            raise ValueError(f"unknown game phase {phase!r}")
        if not self.rules.has_phase(phase):
            raise ValueError(f"{self.profile.name} has no {phase} phase")
        self.tick()
        if phase != self.phase:
            self._enter(phase)

    # -- inputs ---------------------------------------------------------------------
    def beacon(self, *, number: int, team_name: str, peer_name: str, pose=None,
               host: str = "", team_color: str | None = None) -> None:
        """A robot's BeaconSignal; ``pose`` is (x, y, ori) in metres/radians or None."""
        if team_name == REFBOX_TEAM:
            return
        color = self.team_of(team_name)
        robot, what = self.robots.beacon(number=number, team=team_name, name=peer_name,
                                         team_color=color, host=host, now=self.clock.now(),
                                         epoch=self.clock.epoch(), pose=pose)
        if what == "new":
            text = (f"robot {peer_name} ({number}) of {team_name} joined" if color
                    else f"robot {peer_name} ({number}) of unknown team {team_name!r}")
            self.emit(E.ROBOT, text, team=color, number=number, name=peer_name, what="new")
        elif what == "back":
            self.emit(E.ROBOT, f"robot {peer_name} ({number}) of {team_name} is back",
                      team=color, number=number, name=peer_name, what="back")

    def machine_report(self, team_color: str, entries: list[ReportEntry],
                       channel_team: str | None = None) -> int:
        """A MachineReport of ``team_color`` (arrived on ``channel_team``'s channel,
        None for an unencrypted control link).  Returns the points it earned."""
        if channel_team is not None and channel_team != team_color:
            self._attention(channel_team, f"Invalid report for team {team_color} of team "
                                          f"{channel_team}")
            return 0
        if team_color not in TEAMS or not self.exploring:
            return 0
        earned = 0
        for entry in entries:
            j = self.exploration.judge(team_color, entry)
            if j is None:
                continue
            for pts, reason in j.awards:
                self.award(team_color, pts, reason, machine=j.machine)
                earned += pts
            self.emit(E.REPORT, j.text, team=team_color, machine=j.machine, **j.data)
            self.rules.on_report(self, j)
        return earned

    def prepare(self, team_color: str, machine: str, instruction,
                channel_team: str | None = None, *, sent_at: float | None = None) -> str:
        """A PrepareMachine (``sent_at``: its Unix time, 2025).  Returns what became of it:
        "prepared", "broken", "done" (an SS CHANGE_INFO) or "ignored: <why>" (with an
        attention message where the refbox sends one); :mod:`.team_requests`."""
        return team_requests.prepare(self, team_color, machine, instruction, channel_team,
                                     sent_at=sent_at)

    def reset_machine(self, team_color: str, machine: str,
                      channel_team: str | None = None) -> str:
        """A ResetMachine: the team's station goes BROKEN (the usual broken time, then
        IDLE with its slots cleared).  Returns "broken" or "ignored: <why>"."""
        return team_requests.reset_machine(self, team_color, machine, channel_team)

    def station_down(self, machine: str, seconds: float) -> None:
        """The operator takes ``machine`` DOWN now for ``seconds`` of game time (one of
        the refbox's own down periods, ahead of time); only in PRODUCTION."""
        st = self.stations.get(machine)
        if st is None:
            raise ValueError(f"no station {machine!r}")
        if self.phase != PRODUCTION:
            raise RuntimeError(f"stations go DOWN only in PRODUCTION (now {self.phase})")
        now = self.game_time
        st.down, st.down_done = (now, now + float(seconds)), False
        self.tick()
        st.update(self.game_time)

    # -- time ---------------------------------------------------------------------
    def tick(self) -> None:
        """Catch up with the clock: robots lost, slot events, then game time."""
        now = self.clock.now()
        dt = max(0.0, now - self._last_now) * self.timing.speed
        self._last_now = now
        lost, removed = self.robots.check(now)
        for r in lost:
            self.emit(E.ROBOT, f"robot {r.name} ({r.number}) of {r.team} lost", team=r.team_color,
                      number=r.number, name=r.name, what="lost")
        for r in removed:
            self.emit(E.ROBOT, f"robot {r.name} ({r.number}) of {r.team} removed",
                      team=r.team_color, number=r.number, name=r.name, what="removed")
        self._drain_slot_events()
        if self.state == RUNNING:
            self.advance(dt)

    def advance(self, dt: float) -> None:
        """Move game time ``dt`` game seconds on (while RUNNING), crossing phase ends and
        stopping at the rule set's checkpoints (e.g. the end of exploration)."""
        while self.state == RUNNING:
            end = self.phase_end()
            if end is not None and self.game_time >= end:
                self._phase_over()
                continue
            if dt <= 0:
                break
            stops = [t for t in self.rules.checkpoints(self) + self._mockup_due()
                     if t > self.game_time]
            if end is not None:
                stops.append(end)
            stop = min(stops) if stops else None
            if stop is not None and dt >= stop - self.game_time:
                dt -= stop - self.game_time
                self.game_time = stop
            else:
                self.game_time += dt
                dt = 0.0
            self._update()

    def _mockup_due(self) -> list[float]:
        """The mockup's next take or feed, where game time must stop exactly."""
        due = self.mockup.next_due() if self.mockup and self.phase == PRODUCTION else None
        return [] if due is None else [due]

    def phase_end(self) -> float | None:
        """Game time the current phase ends at (with overtime), None without an end."""
        length = self.timing.length(self.phase)
        if length is None:
            return None
        if self.phase == PRODUCTION and self.overtime:
            return length + self.timing.overtime
        return length

    # -- reads -----------------------------------------------------------------------
    def points(self, team: str) -> int:
        """``team``'s score: each phase's points floored at 0, summed."""
        return self.ledger.total(team)

    def points_by_phase(self, team: str) -> dict[str, int]:
        return self.ledger.by_phase(team)

    def team_of(self, name: str) -> str | None:
        for color, n in self.teams.items():
            if n and n == name:
                return color
        return None

    def rs_colors(self, machine: str) -> tuple[str, ...]:
        return self._rs_colors.get(machine[2:], ())

    def ring_cost(self, color: str) -> int:
        return self.ring_costs.get(color, 0)

    def active_orders(self):
        return [o for o in self.orders if o.active]

    def order(self, order_id: int):
        """The order with ``order_id`` (active or not), None when there is none."""
        return next((o for o in self.orders if o.id == order_id), None)

    @property
    def exploring(self) -> bool:
        """Whether machine reports are taken now (2016: EXPLORATION; 2025: the first
        exploration-time seconds of PRODUCTION)."""
        return self.rules.exploring(self)

    def pop_events(self) -> list[E.Event]:
        """Events since the last call."""
        out = self.events[self._read:]
        self._read = len(self.events)
        return out

    @property
    def production_time(self) -> float:
        return self.game_time if self.phase == PRODUCTION else 0.0

    # -- StationHost -------------------------------------------------------------------
    def award(self, team: str, points: int, reason: str, machine: str | None = None,
              game_time: float | None = None, order: int | None = None) -> None:
        gt = self.game_time if game_time is None else game_time
        self.ledger.award(PointsEntry(team, self.phase, int(points), reason, gt, machine, order))
        self.emit(E.POINTS, f"{points:+d} {team}: {reason}", team=team, machine=machine,
                  points=int(points), game_time=gt, order=order)

    def emit(self, kind: str, text: str, *, team: str | None = None, machine: str | None = None,
             game_time: float | None = None, points: int | None = None, **data) -> None:
        gt = self.game_time if game_time is None else game_time
        ev = E.Event(kind, text, self.phase, gt, team, machine, points, data)
        self.events.append(ev)
        log.debug("%s", ev)

    def referee(self, what: str, text: str, *, team: str | None, machine: str | None = None,
                game_time: float | None = None, **data) -> None:
        """Report what a referee would penalise (:mod:`.referee`; the score is untouched)."""
        shown, data = referee_calls.call(self.profile, what, text, team, machine, **data)
        self.emit(E.REFEREE, shown, team=team, machine=machine, game_time=game_time, **data)

    def tally(self, team: str):
        """``team``'s stations gone BROKEN by cause and its referee calls
        (:func:`.referee.tally`)."""
        return referee_calls.tally(self.events, team)

    def station_lights(self, station: Station) -> dict:
        """The tower ``station`` shows now (the rule set's choice)."""
        return self.rules.station_lights(self, station)

    def refresh_lights(self, machine: str | None = None) -> None:
        """Show the rule set's lights on ``machine`` (every station for None) in PRODUCTION."""
        if self.phase != PRODUCTION:
            return
        for name in ([machine] if machine else sorted(self.stations)):
            st = self.stations[name]
            st.set_lights(self.station_lights(st))

    def station_state_changed(self, station: Station, previous: str) -> None:
        """A station changed state (at its game time ``station.now``): tell the mockup."""
        if self.mockup is not None:
            self.mockup.on_state(station, previous)

    def deliver(self, station: Station, wp: Workpiece, gate: int, game_time: float) -> None:
        """The DS ``station`` consumed ``wp`` at ``game_time``: judged now, or listed as
        unconfirmed for ``config.delivery_confirm`` game seconds first (:mod:`.deliveries`)."""
        self.deliveries.deliver(station, wp, gate, game_time)

    @property
    def pending_deliveries(self) -> list[PendingDelivery]:
        """Deliveries the referee has not confirmed yet."""
        return self.deliveries.pending

    # -- internals ---------------------------------------------------------------------
    def _attention(self, team: str | None, text: str, time_to_show: float = 10.0) -> None:
        self.emit(E.ATTENTION, text, team=team, time_to_show=time_to_show)

    def _enter(self, phase: str) -> None:
        prev = self.phase
        if prev == PRODUCTION:
            for st in self.stations.values():
                st.stop_production()
            if self.mockup is not None:
                self.mockup.clear()
        self.phase, self.game_time = phase, 0.0
        self.emit(E.PHASE, f"phase {prev} -> {phase}", previous=prev)
        if phase == EXPLORATION:
            for m in self.stations:
                self.show_exploration_lights(m)
        elif phase == PRODUCTION:
            for st in self.stations.values():
                st.start_production(0.0)
            self.rules.update(self)
            self._activate_orders()
        else:
            for st in self.stations.values():
                st.set_lights(ALL_OFF)
        if phase == POST_GAME:
            if self.state != PAUSED:
                prev_state, self.state = self.state, PAUSED
                self.emit(E.STATE, f"state {prev_state} -> {PAUSED}", previous=prev_state)
            for t in TEAMS:
                if self.teams[t]:
                    self.emit(E.PHASE, f"final score {t} {self.teams[t]}: {self.points(t)}",
                              team=t, points=self.points(t), final=True)
        self._sync_running()

    def _phase_over(self) -> None:
        seq = self.rules.phase_sequence(self.timing)
        if self.phase == PRODUCTION:
            both = all(self.teams.values())
            if (not self.overtime and both and self.timing.overtime > 0
                    and self.points(CYAN) == self.points(MAGENTA)):
                self.overtime = True
                self.emit(E.PHASE, f"overtime: tied at {self.points(CYAN)}", overtime=True)
                self._update()
                return
            self._enter(POST_GAME)
            return
        i = seq.index(self.phase) if self.phase in seq else -1
        self._enter(seq[i + 1] if 0 <= i < len(seq) - 1 else POST_GAME)

    def _update(self) -> None:
        """Everything that follows game time within the phase."""
        if self.phase == EXPLORATION:
            for m, until in list(self.feedback_until.items()):
                if self.game_time >= until:
                    del self.feedback_until[m]
                    self.show_exploration_lights(m)
        elif self.phase == PRODUCTION:
            self.rules.update(self)
            self._activate_orders()
            for name in sorted(self.stations):
                self.stations[name].update(self.game_time)
            if self.mockup is not None:
                self.mockup.fire(self.game_time)
            self.deliveries.confirm_due()

    def _activate_orders(self) -> None:
        for o in self.orders:
            if o.active or (o.overtime and not self.overtime):
                continue
            if self.game_time >= o.activate_at:
                o.active = True
                self.emit(E.ORDER, f"order {o}", order=o.id)
                self._attention(None, f"Order {o.id}: {o.quantity} x C{o.complexity} from "
                                      f"{o.begin} to {o.end}")

    def show_exploration_lights(self, machine: str) -> None:
        """2016 EXPLORATION: ``machine``'s light code, or its report feedback while it lasts."""
        st = self.stations[machine]
        if self.phase != EXPLORATION or self.state != RUNNING:
            st.set_lights(ALL_OFF)
            return
        if machine in self.feedback_until:
            rep = self.exploration.state(st.team, machine)
            st.set_lights(self.exploration.feedback_lights(
                "correct" if rep is not None and rep.fully_correct else "wrong"))
        else:
            st.set_lights(self.exploration.machine_lights(machine))

    def _sync_running(self) -> None:
        running = self.state == RUNNING
        if self.phase == EXPLORATION:
            for m in self.stations:
                self.show_exploration_lights(m)
        for st in self.stations.values():
            st.active = running and self.phase == PRODUCTION
            if st.active:
                st.now = self.game_time
        self.refresh_lights()

    def _drain_slot_events(self) -> None:
        while self._slot_events:
            slot_events.apply(self, self._slot_events.popleft())


__all__ = ["RefboxGame", "PendingDelivery", "REFBOX_TEAM", "INIT", "WAIT_START", "RUNNING", "PAUSED", "PRE_GAME",
           "SETUP", "EXPLORATION", "PRODUCTION", "POST_GAME"]
