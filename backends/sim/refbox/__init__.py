"""The simulated referee box: the 2016 rules (``rcll2016``) and today's (``rcll2025``)
on the real wire protocol.

Layers (each usable alone):

- :class:`RefboxGame` (:mod:`.game`): the pure game core.  No threads, no
  sockets; it takes a clock and moves only in :meth:`RefboxGame.tick`.
  What differs between rule sets is ``game.rules`` (:mod:`.rulesets`, one
  module per rule set: :mod:`.rulesets.rcll2016`; :mod:`.rulesets.rcll2025`:
  no EXPLORATION phase, zone + rotation reports in the first 180 s of
  PRODUCTION (:mod:`.exploration2025`), orders by id (:mod:`.orders2025`),
  the storage station (:mod:`.stations.ss`)).  Stations are a package with
  one module per station type (:mod:`.stations`).
- :class:`RefboxNode` (:mod:`.node`): the game behind the refbox's channels
  (public plain, cyan/magenta AES-128-CBC, TCP control stream) over UDP or the
  in-process bus.
- ``rll-bt refbox sim`` (:mod:`.cli`): a standalone refbox process.  Its world
  has no robots, so it runs in mockup mode by default (``--mockup auto``):
  ``RefboxGame(..., mockup=True)`` (:mod:`.mockup`) has virtual robots take
  products off outputs and feed each team's prepared stations with the
  workpiece its preparations built, so a team playing by PrepareMachine alone
  can produce and deliver.  Off by default (games with robots).  With
  ``--world remote:HOST:PORT`` it drives the stations of a world in another
  process over the station link (:mod:`.link`), as ``rll-bt sim
  --processes`` runs it; :mod:`.view` reads the game as ``rll-bt sim``
  reports it, live or from the ``--snapshot`` file.

Lockstep (one process, one simulated clock, the PyBullet world)::

    from backends.sim import World
    from backends.sim.refbox import RefboxGame, RefboxNode, Timing
    from rll_bt.comm import Bus

    world = World("rcll2016", seed=7)
    game = RefboxGame("rcll2016", world.clock, world, seed=7,
                      team_cyan="Caro", team_magenta="Grips",
                      timing=Timing.from_profile(world.profile, production=300))
    bus = Bus(world.clock)
    node = RefboxNode.on_bus(game, bus, keys={"Caro": "k1", "Grips": "k2"})
    game.start()                        # or a SetGameState RUNNING on the "refbox" stream
    while game.phase != "POST_GAME":
        world.step(0.05)                # the world owns the clock
        node.step()                     # receive, game.tick(), send what is due
        ...                             # team server and agents poll their bus endpoints

  Robots join ``bus.peer("public", registry=...)`` and
  ``bus.peer("cyan", registry=..., key="k1")``; a controller
  ``bus.stream_client("refbox", registry=...)``.  Without a world,
  ``RefboxGame(profile, clock)`` builds an in-memory :class:`TableWorld` with
  the same seeded layout.

Network (own process, wall clock)::

    game = RefboxGame("rcll2016", WallClock(), world, seed=7, team_cyan="Caro")
    node = RefboxNode.on_udp(game, host="127.0.0.1", layout="sim",   # or "competition"
                             keys={"Caro": "k1"}, stream_port=None)  # None: layout's 4444
    while True:
        node.step(); node.channels.public.wait(0.02)
    node.close()

Reading the game: ``game.phase``, ``game.state``, ``game.game_time`` (game s
in the phase), ``game.points("CYAN")`` (per-phase floored total),
``game.points_by_phase(team)``, ``game.ledger.entries`` (every
:class:`~.ledger.PointsEntry` with reason), ``game.events`` /
``game.pop_events()`` (:class:`Event`: phase, state, points, attention,
machine, lights, robot, order, report, delivery, workpiece),
``game.stations[name]`` (``state``, ``lights``, ``slide_loaded``,
``cap_buffer``), ``game.orders`` / ``game.active_orders()``,
``game.ring_costs``, ``game.rs_colors(machine)``, ``game.layout``,
``game.exploration`` (2016: light codes, type strings, reports; 2025: name
and type reports, ``released``), ``game.exploring`` (reports taken now),
``game.pending_deliveries`` (unconfirmed), ``game.order(id)``,
``game.robots``.  Plain-value inputs (what the node calls):
``game.beacon(...)``, ``game.machine_report(team, [ReportEntry], channel_team)``,
``game.prepare(team, machine, instruction, channel_team, sent_at=None)`` ->
"prepared" | "broken" | "done" | "ignored: ...",
``game.reset_machine(team, machine, channel_team)`` -> "broken" | "ignored: ...",
``game.set_team``, ``game.set_state``, ``game.set_phase``,
``game.advance(game_seconds)``.  Instructions: :class:`BSInstruction`,
:class:`RSInstruction`, :class:`CSInstruction`, :class:`DSInstruction`
(``gate`` in 2016, ``order_id`` in 2025, 0 = consume only),
:class:`SSInstruction` (2025).
"""
from .events import Event
from .exploration2016 import ReportEntry
from .game import PendingDelivery, RefboxGame
from .node import RefboxNode
from .rulesets import Rules2016, Rules2025, rules_for
from .stations import (
    BSInstruction,
    CSInstruction,
    DSInstruction,
    RSInstruction,
    SSInstruction,
    StationConfig,
)
from .timing import Timing, parse_phase_lengths
from .world import RefboxWorld, SlotEvent, TableWorld, Workpiece

__all__ = ["RefboxGame", "RefboxNode", "Event", "ReportEntry", "BSInstruction", "CSInstruction",
           "DSInstruction", "RSInstruction", "SSInstruction", "StationConfig", "Timing",
           "parse_phase_lengths", "RefboxWorld", "SlotEvent", "TableWorld", "Workpiece",
           "PendingDelivery", "Rules2016", "Rules2025", "rules_for"]
