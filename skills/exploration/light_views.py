"""A station's light read view by view: when is a reading good enough to tell?

A detector's reading of a signal tower carries its confidence (the light
network's probability of the state it names).  The frames a robot takes
standing at one place are not independent: a glare, a neighbour's glow or
a tinted backdrop that fools one of them fools the next.  So readings are
grouped into *views*: a view of a station's tower is what the robot read
of it from one place; a new view begins when the robot has moved more than
``view_distance`` metres from where the view began, or when it had not read
that tower for ``view_gap`` seconds.

A view's verdict (:meth:`LightViews.verdicts`) is the state that, among its
readings of the last ``window`` seconds, has at least ``min_votes`` and a
``share`` of them, spread over ``span`` seconds (read again after a moment,
not one frame counted thrice); its confidence is the mean probability the
readings give that state (a frame that named another state pulls it down).
A view is *confident* from ``view_confidence`` and *sure* from
``sure_confidence``.

The station's light is *settled* for the robot (:meth:`LightViews.settled`)
by the rule the team server reports with (``teamserver.exploration.lights``):
``min_sure`` (2) sure views read it and no sure view read another state (or
those that read it outnumber those by two): one view, however sure, is not
enough (in the rendered game of seed 1 at 112b3d3 one view read M-DS's
green and yellow as yellow alone at 0.993).  Views below sure neither
settle nor hold back.  A light read but not settled is
:meth:`LightViews.unsure`: the exploration then reads it again after a
moment and from a second place (:class:`~.explore.ExploreZone`) rather
than leave with it.

Where to read a tower from (:func:`light_viewpoints`): the tower stands on
the cabinet near the output face, its lowest lamp just above the cabinet's
top, and the camera (0.57 m) is lower than that top: the cabinet hides the
lamp but from far enough off in front of the output face
(:func:`skills.perception.light.region.lowest_lamp_visible`); from the input
side the belt and the whole cabinet are in between, and from nearer than
about 1.5 m the tower leaves the top of the image.  The camera's perception
does not read a tower hidden in part (``skills.perception.source``): in the
seed-1 world a cap station's green, yellow and red read from its input side
came out as yellow and red at 0.999, its green alone as all dark at 0.99.
"""
from __future__ import annotations

import math
from collections import Counter, deque
from dataclasses import dataclass, field

from rll_bt.backend import Pose2D

from ..perception.light.region import lowest_lamp_visible

#: seconds of a view a verdict looks at
LIGHT_WINDOW = 8.0
#: share of the readings in the window a light state needs
LIGHT_SHARE = 0.8
#: seconds between the first and the last reading of that state in the window
LIGHT_SPAN = 0.35
#: metres the robot moves before its readings are another view
VIEW_DISTANCE = 0.3
#: a view's confidence at which it votes for its state
VIEW_CONFIDENCE = 0.9
#: a view's confidence at which it counts as sure
SURE_CONFIDENCE = 0.99
#: sure views that must agree before a state is settled
MIN_SURE = 2
#: where a tower is read from: metres from the output face to the robot's centre, degrees off its normal
LIGHT_VIEW_DISTANCES = (1.8, 2.1, 2.4, 1.6)
LIGHT_VIEW_ANGLES = (0.0, 15.0, -15.0, 30.0, -30.0, 45.0, -45.0, 60.0, -60.0)


@dataclass(frozen=True)
class Verdict:
    view: int              # the view's number (1, 2, ... per station)
    state: int             # 0..7
    confidence: float      # mean probability of ``state`` over the view's readings
    readings: int


@dataclass
class _View:
    number: int
    x: float | None
    y: float | None
    readings: deque = field(default_factory=lambda: deque(maxlen=200))   # (stamp, state, probabilities)


class LightViews:
    def __init__(self, view_distance: float = VIEW_DISTANCE, view_gap: float = LIGHT_WINDOW,
                 window: float = LIGHT_WINDOW, min_votes: int = 3, share: float = LIGHT_SHARE,
                 span: float = LIGHT_SPAN, view_confidence: float = VIEW_CONFIDENCE,
                 sure_confidence: float = SURE_CONFIDENCE, min_sure: int = MIN_SURE):
        self.min_sure = min_sure
        self.view_distance, self.view_gap, self.window = view_distance, view_gap, window
        self.min_votes, self.share, self.span = min_votes, share, span
        self.view_confidence, self.sure_confidence = view_confidence, sure_confidence
        self._views: dict[str, list[_View]] = {}

    # -- input ------------------------------------------------------------------
    def add(self, machine: str, stamp: float, state: int, probabilities, position=None) -> int:
        """One reading of ``machine``'s tower: ``state`` 0..7 with the reader's
        class ``probabilities`` (8 values), read standing at ``position``
        (x, y; None: unknown, the current view goes on).  Returns the view's number."""
        if not 0 <= int(state) <= 7:
            raise ValueError(f"light state must be 0..7, got {state}")
        views = self._views.setdefault(machine, [])
        x, y = (None, None) if position is None else (float(position[0]), float(position[1]))
        cur = views[-1] if views else None
        if cur is None or self._new_view(cur, stamp, x, y):
            cur = _View(len(views) + 1, x, y)
            views.append(cur)
        elif cur.x is None and x is not None:
            cur.x, cur.y = x, y
        cur.readings.append((float(stamp), int(state), tuple(float(p) for p in probabilities)))
        return cur.number

    def _new_view(self, view: _View, stamp: float, x, y) -> bool:
        if view.readings and stamp - view.readings[-1][0] > self.view_gap:
            return True
        if view.readings and stamp < view.readings[-1][0]:
            return True                                   # time went backwards
        return x is not None and view.x is not None and math.hypot(x - view.x, y - view.y) > self.view_distance

    # -- verdicts -------------------------------------------------------------------
    def verdict(self, machine: str, number: int | None = None) -> Verdict | None:
        """The verdict of view ``number`` (default: the current one), or None."""
        views = self._views.get(machine)
        if not views:
            return None
        view = views[-1] if number is None else next((v for v in views if v.number == number), None)
        return None if view is None else self._verdict(view)

    def _verdict(self, view: _View) -> Verdict | None:
        if not view.readings:
            return None
        latest = view.readings[-1][0]
        recent = [r for r in view.readings if r[0] >= latest - self.window]
        votes = Counter(s for _, s, _p in recent)
        state, n = votes.most_common(1)[0]
        stamps = [t for t, s, _p in recent if s == state]
        if n < self.min_votes or n < self.share * len(recent) or stamps[-1] - stamps[0] < self.span:
            return None
        conf = sum(p[state] if len(p) > state else float(s == state) for _t, s, p in recent) / len(recent)
        return Verdict(view.number, state, conf, len(recent))

    def verdicts(self, machine: str) -> list[Verdict]:
        """The verdict of every view of ``machine``'s tower that has one."""
        return [v for view in self._views.get(machine, []) if (v := self._verdict(view)) is not None]

    def latest(self, machine: str) -> Verdict | None:
        """The newest view's verdict that there is (what to tell the team server now)."""
        found = self.verdicts(machine)
        return found[-1] if found else None

    def settled(self, machine: str) -> int | None:
        """The state the views settle on (see the module doc), or None."""
        sure = [v.state for v in self.verdicts(machine) if v.confidence >= self.sure_confidence]
        for state in sorted(set(sure)):
            agree = sure.count(state)
            against = len(sure) - agree
            if agree >= self.min_sure and (against == 0 or agree - against >= 2):
                return state
        return None

    def read(self, machine: str) -> bool:
        """Has any view of ``machine``'s tower any reading?"""
        return any(v.readings for v in self._views.get(machine, []))

    def unsure(self, machine: str) -> bool:
        """Read, but not settled: worth reading again."""
        return self.read(machine) and self.settled(machine) is None

    def current_view(self, machine: str) -> int | None:
        views = self._views.get(machine)
        return views[-1].number if views else None

    def views(self, machine: str) -> int:
        """How many views of ``machine``'s tower there were."""
        return len(self._views.get(machine, []))


def light_viewpoints(station: Pose2D, profile) -> list[tuple[float, Pose2D]]:
    """Places to read ``station``'s tower from (see the module doc): poses
    in front of its output face (:data:`LIGHT_VIEW_DISTANCES`,
    :data:`LIGHT_VIEW_ANGLES`), facing the tower, each with the share of the
    lowest lamp its camera sees over the station; best first."""
    mps, cam = profile.mps, profile.robot.camera_mount
    c, s = math.cos(station.theta), math.sin(station.theta)

    def world(x, y):
        return station.x + c * x - s * y, station.y + s * x + c * y

    tx, ty = world(mps.tower_x, mps.tower_y)
    fx, fy = world(-mps.depth / 2.0, 0.0)
    normal = station.theta + math.pi
    out = []
    for d in LIGHT_VIEW_DISTANCES:
        for a in LIGHT_VIEW_ANGLES:
            x, y = fx + d * math.cos(normal + math.radians(a)), fy + d * math.sin(normal + math.radians(a))
            heading = math.atan2(ty - y, tx - x)
            ex, ey = x + cam[0] * math.cos(heading), y + cam[0] * math.sin(heading)
            dx, dy = ex - station.x, ey - station.y        # the camera in the machine's frame
            seen = lowest_lamp_visible((c * dx + s * dy, -s * dx + c * dy, cam[2]), mps)
            out.append((seen, Pose2D(x, y, heading)))
    out.sort(key=lambda p: -p[0])
    return out
