"""A whole game against a refbox elsewhere (``rll-bt sim --refbox external``).

    game = ExternalGame(GameOptions(refbox="external", refbox_host="127.0.0.1",
                                    profile="rcll2025", team_name="GRIPS", key="..."))
    result = game.run()                  # until the refbox says POST_GAME
    game.close()

As :class:`~games.processes.ProcessGame` (the team server and every agent
are processes of their own, this process holds the world and serves the
robots' backends), but the refbox is not ours to start: it runs already,
the league's own or ``rll-bt refbox sim`` in its network mode, at
``refbox_host`` on its own ports (the refbox's ``sim`` layout, TCP 4444,
UDP public 4444/4445 and cyan 4441/4446, all moved by
``refbox_port_offset``).  The simulator's ``refbox="external"``
(``backends.sim.external``) connects to its controller stream, names the
team and starts SETUP (``refbox_control="auto"``), builds the world on the
field the refbox announces, serves it the world's stations (MQTT through
the broker at ``mqtt``, or OPC-UA PLCs) and sends it the world's time
(SimTimeSync).  The team server and the agents send to ``refbox_host`` and
hear the refbox's broadcasts (its peers must send to a broadcast address
the machine hears, e.g. 127.255.255.255 on one host: see docs/league.md).
When every robot is up the game switches SETUP to the next phase and runs
until the refbox says POST_GAME.  The refbox's view (points, deliveries,
states) is what its controller stream said; the wire carries no reasons
for points.

:meth:`hold` holds the world for a while: SimTimeSync says paused, and
a refbox following it stops its clock.
"""
from __future__ import annotations

from rll_bt.comm import SIM, Layout
from rll_bt.contracts import load_simulator

from .processes import ProcessGame

#: s without the refbox's controller stream before the game counts it lost
LOST_AFTER = 10.0


class ExternalGame(ProcessGame):
    """See the module doc."""

    @property
    def refbox_host(self) -> str:          # where the team server and the agents send
        return self.options.refbox_host

    def _open_simulation(self):
        o = self.options
        return load_simulator(o.simulator)(
            profile=o.profile, seed=o.seed, team_name=o.team_name, key=o.key, perception=o.perception,
            gui=o.gui, phases=o.phases(), world_step=o.world_step, robot_options={"laser_rate": o.laser_rate},
            refbox="external", external=o.external())

    def _refbox_layout(self) -> Layout:
        return SIM.moved(int(self.options.refbox_port_offset))

    def _start_refbox(self) -> None:
        self._refbox_log = None            # its messages are not ours to log; the team server's are
        self._lost_since = None

    def _dead(self) -> list[str]:
        dead = [name for name in ("teamserver",) if name not in self._alive()]
        connected = self.refbox.link.stream.connected
        now = self.wall.now()
        if connected:
            self._lost_since = None
        elif self._lost_since is None:
            self._lost_since = now
        elif now - self._lost_since > LOST_AFTER:
            dead.append("refbox")
        return dead

    def hold(self, seconds: float) -> None:
        """Hold the world ``seconds`` of wall time (the backends and the stations are
        still served): the refbox hears the world's time paused."""
        self.refbox.pause(True)
        end = self.wall.now() + seconds
        while self.wall.now() < end:
            self._serve(0.01)
        self.refbox.pause(False)
        self._last = self.wall.now()
        self.recorder.note("world held", seconds=seconds)


__all__ = ["ExternalGame"]
