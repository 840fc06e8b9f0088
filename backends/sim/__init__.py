"""The PyBullet RCLL simulation: a field with both teams' stations, the
workpieces, Robotinos with laser, camera and gripper, and the ``sim``
backend.  (The simulated referee box lives in ``backends.sim.refbox``.)

Quick start::

    from backends.sim import World
    from rll_bt.backend import open_backend
    with World("rcll2016", seed=7, perception="oracle") as world:
        bot = open_backend("sim", world=world, robot=("CYAN", 1))
        bot.drive(0.5, 0.0, 0.0)
        world.step(2.0)                      # the world owns time
        world.robot_pose("CYAN", 1)          # ground truth, for tests

World (:class:`backends.sim.world.World`)
    ``World(profile="rcll2016", seed=0, *, layout=None, perception="oracle",
    time_step=0.02, clock=None, gui=False, robot_config=None, blink_hz=2.0)``
    builds the field of ``profile`` with ``layout`` (default
    ``generate_layout(profile, seed)``).  ``perception`` is ``"oracle"`` or
    ``"rendered"``.  ``gui=True`` opens PyBullet's window (raises
    ``BackendUnavailable`` when there is no display).

    - time: ``world.time`` (seconds), ``world.clock`` (a ``SimClock`` only
      the world advances), ``world.step(dt=None)`` (dt in sub-steps of at
      most ``time_step``), ``world.run(seconds, callback=None)``.
    - robots: ``world.add_robot(team, number, pose=None, config=None,
      **RobotConfig fields)``, ``world.robots`` {(team, number): SimRobot},
      ``world.robot(team, n)``, ``world.robot_pose(team, n)`` (ground-truth
      ``Pose2D``), ``world.teleport(team, n, pose)``,
      ``world.clearance(team, n)``, ``world.held_workpiece(team, n)``.
    - collisions: a motion into a wall, station or robot is stopped at the
      contact point; ``SimRobot.collisions`` counts events (a motion blocked
      by a wall, station or robot the robot was not already touching: more
      pushes against the same thing before the robot has left it by
      ``CONTACT_GAP`` are the same contact; two robots touching are one
      contact, counted for the one that ran into the other first),
      ``SimRobot.blocked_steps``
      counts blocked steps, ``world.collision_count`` sums the events,
      ``world.collision_log`` is a list of ``Collision(time, robot,
      obstacle, pose, speed)`` (the robot's true pose at the contact and its
      speed before it).
    - ``world.ray(start, end, ignore=None)`` -> (what, distance).

Station API (for the simulated referee box)
    Machine names as the profile (``"C-BS"``, ``"M-RS2"``); slots
    ``"input"``, ``"output"`` (not on a DS), ``"shelf0".."shelf2"`` (CS),
    ``"slide"`` (RS, holds many); colours as the refbox enums
    (``BASE_RED``, ``RING_BLUE``, ``CAP_GREY``...).

    - ``world.machines``, ``world.station(name)`` -> ``Station`` (``pose``,
      ``zone``, ``rotation``, ``type``, ``team``, ``tag_ids`` (input,
      output), ``slots``, ``slot_point(slot)``, ``tag_frame(side)``).
    - ``world.set_lights(machine, red="OFF", yellow="OFF", green="OFF")``
      with ``"OFF" | "ON" | "BLINK"`` (unnamed lights go off);
      ``world.lights(machine)`` -> {"RED": ..., "YELLOW": ..., "GREEN": ...};
      ``world.visible_light_code(machine)`` -> 0..7 right now.
    - ``world.spawn_workpiece(machine, slot, base, rings=(), cap=None)`` ->
      ``Workpiece(id, base, rings, cap)`` (a base dispensed at the BS,
      cap carriers on the CS shelf); ``world.spawn_workpiece_on_floor(x, y,
      base, ...)``.
    - ``world.modify_workpiece(machine, slot, add_ring=None, rings=None,
      cap=...)`` (ring mounted; ``cap="CAP_BLACK"`` mounted, ``cap=None``
      retrieved) -> the new ``Workpiece`` (same id).
    - ``world.move_workpiece(machine, src, dst)`` (conveyor: input ->
      output), ``world.remove_workpiece(machine, slot, workpiece_id=None)``
      (consumed, e.g. at the DS input or a base counted on the slide) ->
      ``Workpiece | None``.
    - ``world.workpiece_at(machine, slot)``, ``world.workpieces_at(machine,
      slot)``, ``world.workpieces()`` -> [(Workpiece, Location)].
    - ``world.add_slot_listener(fn)`` / ``remove_slot_listener(fn)``:
      ``fn(SlotEvent(kind="put"|"take", machine, slot, workpiece, robot=(team,
      number), time))`` after the step in which a robot's gripper put a
      workpiece at a slot or took one from it.  Listeners may change the
      world (move, modify, remove workpieces, set lights).
    - A full slot raises ``SlotError`` (a ``ValueError``); unknown machines
      and slots raise ``KeyError``.

Backend: :class:`backends.sim.backend.SimBackend` (options documented
there), entry point ``sim``.  Layouts: :mod:`backends.sim.layout`
(``FieldLayout``, ``generate_layout``, ``placement_2016``,
``placement_2025``).  Top view: :func:`backends.sim.topview.draw_layout`.

Attributes are imported lazily, so ``import backends.sim`` (done by the CLI
plug-in) does not load PyBullet.
"""
from __future__ import annotations

import importlib

_EXPORTS = {
    "World": "world", "SlotEvent": "stationapi", "PERCEPTION_MODES": "world",
    "SimBackend": "backend",
    "RobotConfig": "robot", "SimRobot": "robot", "Collision": "robot",
    "FieldLayout": "layout", "MachinePlacement": "layout", "LayoutError": "layout",
    "generate_layout": "layout", "placement_2016": "layout", "placement_2025": "layout",
    "Station": "stations", "LIGHT_COLORS": "stations", "LIGHT_STATES": "stations",
    "Workpiece": "workpieces", "Location": "workpieces",
    "SlotError": "store",
    "draw_layout": "topview",
}

__all__ = sorted([*_EXPORTS, "open_sim", "open_world"])


def __getattr__(name: str):
    if name in _EXPORTS:
        module = importlib.import_module(f"{__name__}.{_EXPORTS[name]}")
        value = getattr(module, name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def open_world(profile=None, seed: int = 0, **options):
    """Entry point ``rll_bt.worlds: pybullet``: a headless :class:`World` of
    ``profile`` (name or Profile) for ``seed``; ``options`` as ``World``'s
    (e.g. ``perception="rendered"``).  Camera views: :mod:`backends.sim.camera`."""
    from .world import World
    return World(profile, seed=seed, **options)


def open_sim(world=None, robot=1, *, profile=None, seed: int = 0, perception: str = "oracle",
             gui: bool = False, clock=None, **options):
    """Entry point ``rll_bt.backends: sim`` (see :class:`SimBackend`).

    With ``world``, a robot in that world (its owner steps it; ``profile``,
    ``seed``, ``perception``, ``gui`` and ``clock`` are not used).  Without, a
    robot in a headless world of its own built from ``profile`` (default
    rcll2016), ``seed`` and ``perception`` that follows ``clock`` (default the
    wall clock): see :mod:`backends.sim.standalone`."""
    if world is not None:
        from .backend import SimBackend
        return SimBackend(world, robot, **options)
    from rll_bt.clock import WallClock

    from .standalone import StandaloneSimBackend
    from .world import World
    own = World(profile, seed=int(seed), perception=perception, gui=bool(gui))
    try:
        return StandaloneSimBackend(own, clock if clock is not None else WallClock(), robot, **options)
    except Exception:
        own.close()
        raise
