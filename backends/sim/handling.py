"""How a robot's gripper picks up and puts down workpieces (a mixin of
:class:`~backends.sim.world.World`).

When a close finishes, the nearest workpiece not in a gripper whose centre
is within ``grab_tolerance`` (horizontally) of the gripper point and whose
mid-base height is within ``grab_tolerance_z`` of the gripper's is taken,
unless the grab fails (probability ``grab_failure``); the gripper's workpiece
sensor (``GripperStatus.sensed``) tells whether there is one (:meth:`within_grip`).  When an open finishes
with a workpiece held, it goes to the nearest free station slot within
``place_tolerance`` / ``place_tolerance_z`` of the gripper point, or else
onto the floor below it.  Takes from and puts on slots, and drops on the
floor, become :class:`~backends.sim.stationapi.SlotEvent` s.
"""
from __future__ import annotations

import math

from rll_bt.rules import WORKPIECE

from .robot import SimRobot
from .stationapi import SlotEvent
from .store import grab_height, horizontal
from .workpieces import Workpiece


class GripperHandling:
    """Needs ``store``, ``_station_list``, ``_events``, ``time`` and
    ``robot()`` from the world."""

    def gripper_point(self, r: SimRobot, bottom: bool = False) -> tuple[float, float, float]:
        """The gripper point in the field frame (``bottom``: where the bottom
        of a held workpiece is)."""
        gx, gy, gz = r.gripper.position
        fx = r.config.geometry.gripper_reach + gx
        c, s = math.cos(r.pose.theta), math.sin(r.pose.theta)
        z = gz - WORKPIECE.base_height / 2.0 if bottom else gz
        return (r.pose.x + c * fx - s * gy, r.pose.y + s * fx + c * gy, z)

    def within_grip(self, r: SimRobot) -> int | None:
        """The workpiece a close would take now (not counting ``grab_failure``): the
        nearest one not in a gripper within the grab tolerances of the gripper point."""
        gp = self.gripper_point(r)
        cfg = r.config
        best, best_d = None, math.inf
        for wp_id, pos in self.store.loose():
            d = horizontal(gp, pos)
            if d <= cfg.grab_tolerance and abs(gp[2] - grab_height(pos)) <= cfg.grab_tolerance_z and d < best_d:
                best, best_d = wp_id, d
        return best

    def _grab(self, r: SimRobot) -> None:
        if r.holding is not None:
            return
        best = self.within_grip(r)
        if best is None:
            return
        cfg = r.config
        if cfg.grab_failure > 0.0 and r.rng.random() < cfg.grab_failure:
            return
        loc = self.store.location(best)
        wp = self.store.hold(best, r.key, self.gripper_point(r, bottom=True))
        r.holding = best
        if loc.kind == "slot":
            self._events.append(SlotEvent("take", loc.machine, loc.slot, wp, r.key, self.time))

    def _release(self, r: SimRobot) -> None:
        if r.holding is None:
            return
        gp = self.gripper_point(r)
        cfg = r.config
        best, best_d = None, math.inf
        for st in self._station_list:
            if math.hypot(gp[0] - st.pose.x, gp[1] - st.pose.y) > 1.0:
                continue
            for slot in st.slots:
                sp = self.store.slot_position(st.name, slot, 0)
                d = horizontal(gp, sp)
                if (d <= cfg.place_tolerance and abs(gp[2] - grab_height(sp)) <= cfg.place_tolerance_z
                        and d < best_d and self.store.free_capacity(st.name, slot) > 0):
                    best, best_d = (st.name, slot), d
        wp = self.store.get(r.holding)
        r.holding = None
        if best is None:
            self.store.put_floor(wp, gp[0], gp[1])
            self._events.append(SlotEvent("drop", None, None, wp, r.key, self.time))
            return
        self.store.put(wp, *best)
        self._events.append(SlotEvent("put", best[0], best[1], wp, r.key, self.time))

    def held_workpiece(self, team: str, number: int) -> Workpiece | None:
        r = self.robot(team, number)
        return None if r.holding is None else self.store.get(r.holding)

