"""A whole game through emulated hardware (``rll-bt sim --hardware emulated``).

Everything :mod:`.processes` does (the refbox, the team server and every
agent as processes of their own, on the wall clock), but each agent runs
the ``robotino`` backend, the code a real robot runs, on a robot
configuration whose devices are emulators fed by the world
(:meth:`~.interfaces.Simulation.emulated_hardware`): the base firmware and
the gripper Arduino on ptys, the laser (URG on a pty or TiM on a TCP port)
and the camera (MJPEG over HTTP), each robot's in a process of its own.  Serial frames, laser telegrams and
camera frames cross real file descriptors; the agents see no simulator.
Perception is the camera's (tags and lights detected on the frames).

This process steps the world and, after each step, lets the devices take
what it computed (:meth:`_tick`).  Unlike a sim-backend process game it
catches up the wall time it fell behind (:attr:`catch_up`): the devices'
motors run on the wall clock, and a world that dropped time moved the
robots less than their odometry said.  A restarted agent (:meth:`start_agent`)
is not handed its pose: it localises globally.  :attr:`hardware_stats`
holds each robot's serial, laser and camera counts at the end, :attr:`world_lag`
how far the world stood behind the wall clock (the report's ``world_lag``).
"""
from __future__ import annotations

from pathlib import Path

from rll_bt.contracts.world import STALE_CAST

from .lockstep import TEAM
from .processes import ProcessGame
from .world_pace import WorldLag


class HardwareGame(ProcessGame):
    def __init__(self, options, **kw):
        # each agent brings up four devices (the base's handshake, the gripper, the laser's stream, the
        # camera's first frame; 30 s each at most): three agents starting at once on a loaded machine
        # took more than the process game's 120 s to be ACTIVE (load 16: none was, after 271 s of wall time)
        kw.setdefault("connect_timeout", 60.0 + 60.0 * options.robots)
        self.hw = None
        self.hardware_stats: dict = {}
        self._configs: dict[int, Path] = {}
        self._hw_t0: float | None = None
        self.world_lag = WorldLag(STALE_CAST)     # how far the world stood behind the devices' wall clock
        super().__init__(options, **kw)

    def _start_children(self) -> None:
        import yaml
        o = self.options
        # each robot's devices in a process of their own: as threads of this process they waited for
        # the world's renders and ray casts (one interpreter lock) and, on a loaded machine, went
        # seconds without reading their ptys (backends/sim/hardware_process.py)
        self.hw = self.world.emulated_hardware(laser=o.laser, camera_fps=o.camera_fps, devices="process")
        for n in self.robots:
            rig = self.hw.add((TEAM, n))
            path = self.dir / f"robot{n}.yaml"
            path.write_text(f"# the emulated devices of robot {n} (rll-bt sim --hardware emulated)\n"
                            + yaml.safe_dump(rig.config(), sort_keys=False))
            self._configs[n] = path
        self._hw_t0 = self.wall.now()
        super()._start_children()

    def _agent_backend_args(self, n: int, team: str = TEAM) -> list[str]:
        return ["--backend", "robotino", "--robot-config", str(self._configs[n])]

    #: the devices run on the wall clock (the base firmware turns its motors, the host integrates them):
    #: a world that dropped wall time moved the robots less than their odometry said (the world fell 262 s
    #: behind in a 1164 s game at load 10-16, and the robots were lost most of the game); it catches up,
    #: in steps of at most 0.1 s each followed by the devices' sync, up to 2 s behind
    catch_up = 2.0

    def _tick(self, last: float) -> float:
        last = super()._tick(last)
        if self.hw is not None:
            self.hw.sync(at=last)      # the world stands at wall time ``last``: its casts are of then
            if self._started:
                self.world_lag.add(self.wall.now(), last)
        return last

    def start_agent(self, number: int, known_pose: bool = False) -> None:
        """A new agent process on the same devices; it localises globally."""
        super().start_agent(number, known_pose=known_pose)

    def result(self, finished: bool):
        if self.hw is not None:
            span = max(self.wall.now() - (self._hw_t0 or self.wall.now()), 1e-9)
            stats = self.hw.stats()
            for s in stats.values():
                s["serial_polls_per_s"] = round(s["base_frames"] / span, 1)
                s["scans_per_s"] = round(s["scans_sent"] / span, 2)
                s["frames_per_s"] = round(s["frames_sent"] / span, 2)
            self.hardware_stats = stats
        res = super().result(finished)
        res.snapshot["hardware"] = self.hardware_stats
        res.snapshot["world_lag"] = self.world_lag.summary()
        return res

    def close(self) -> None:
        try:
            super().close()
        finally:
            if self.hw is not None:
                self.hw.stop()
                self.hw = None
