"""Recovering a lost or wrong pose: spread the particles, look around, and
use the station tags the camera sees.

:class:`Relocalise` re-initialises the localiser around its last estimate
(``spread``, standard deviations in m, m, rad), or over the whole field
with ``global_search`` (weighted toward the last estimate, so the mirror
image of the robot's place in the other half does not win on a tie), with
more particles and beams than usual (:meth:`Localiser.boost`), then turns
the robot on the spot (one full turn) while the filter updates.

Every sighting of the tag of a station whose pose is known gives the
robot's pose directly (:func:`pose_from_tag`): when that disagrees with the
filter's estimate and the laser agrees with it clearly better than with
the estimate, the filter starts again around it (the laser then refines
it).  A station's known pose may itself be off (a zone centre from the
team server), so a tag is believed only within ``tag_reach`` metres of
where the robot believed itself when it started relocalising, or
anywhere when the tags of two stations agree on the pose.

It succeeds once the estimate is confident (the localiser's ``confident``
level) and compact (``std_xy`` below ``max_std``) for ``settle`` filter
updates in a row, and either a known tag agrees with it or the estimate
never fell below ``hold`` confidence while the robot turned by
``look_around`` radians (a wrong pose often fits the part of the field in
view, and fits badly somewhere else; the laser's 240 degrees plus half a
turn see all round).
While the localiser is ``side_unsure`` (a restarted robot's global search:
the laser alone cannot tell the robot's place from its mirror image in the
other half) only a tag decides: a tag is believed wherever the robot thought
it was and even when the laser fits both places, and success needs a tag
that agrees (:meth:`Localiser.confirm`).
It fails with LOCALISATION_LOST when a full turn did not do it.
"""
from __future__ import annotations

import math

from rll_bt.backend import Pose2D, wrap_angle

from ..activity import Activity, Status
from ..errors import SkillError, SkillFailure
from ..manipulation.tagview import tag_pose_in_robot
from ..navigation.motions import Turn
from ..perception.tags.geometry import tag_pose_on_machine


def pose_from_tag(ctx, detections) -> list[Pose2D]:
    """Robot poses (field frame) implied by the tags in ``detections`` of
    stations whose pose ``ctx.machines`` knows, one per such tag."""
    out = []
    for det in detections.tags:
        owner = ctx.profile.machine_for_tag(det.tag_id)
        if owner is None:
            continue
        machine = ctx.machines.get(owner[0])
        seen = tag_pose_in_robot(detections, det.tag_id)
        if machine is None or seen is None:
            continue
        tag, _ = tag_pose_on_machine(machine, owner[1], ctx.profile.mps)
        out.append(tag.compose(seen.inverse()))
    return out


class Relocalise(Activity):
    name = "relocalise"

    def __init__(self, ctx, spread: tuple[float, float, float] = (0.5, 0.5, 0.6),
                 global_search: bool = False, timeout: float | None = 40.0, particles: int | None = None,
                 max_std: float = 0.12, settle: int = 3, tag_disagreement: float = 0.3,
                 look_around: float = math.pi, hold: float = 0.3, tag_fit: float = 0.6,
                 tag_reach: float = 2.0, tag_agreement: float = 0.06):
        super().__init__(ctx, timeout)
        self.spread = spread
        self.global_search = global_search
        self.particles = particles or (6000 if global_search else 1500)
        self.max_std = max_std
        self.settle = settle
        self.tag_disagreement = tag_disagreement
        self.look_around = look_around
        self.hold = hold
        self.tag_fit = tag_fit          # laser agreement a tag's pose needs to be believed
        self.tag_reach = tag_reach
        self.tag_agreement = tag_agreement      # m and rad: a tag this close confirms the estimate
        self.last: Pose2D | None = None
        self.turn: Turn | None = None
        self.tag_fixes = 0

    def _on_start(self) -> None:
        loc = self.ctx.pose_source
        if not hasattr(loc, "filter"):
            raise SkillFailure(SkillError.LOCALISATION_LOST, "the pose source cannot relocalise")
        last = self.last = loc.pose()
        loc.boost(self.particles, beams=60)
        if self.global_search or last is None:
            loc.initialise_global(prior=last)
        else:
            loc.initialise(last, self.spread)
        self._good = 0                    # filter updates in a row with a confident estimate
        self._fair_from: float | None = None   # turned (rad) when the estimate last became fair
        self._agreed = False              # a tag confirmed the current estimate
        self._seen = loc.filter_updates
        self._last_tags = None
        self.tag_fixes = 0
        self.turn = Turn(self.ctx, by=2.0 * math.pi, omega=0.5).start()

    def _look(self) -> None:
        """Restart the filter around a tag's answer when it disagrees."""
        tags = getattr(self.ctx, "tags", None)
        dets = tags.detections() if tags is not None else None
        if dets is None or dets.stamp == self._last_tags:
            return
        self._last_tags = dets.stamp
        loc = self.ctx.pose_source
        odom_then = self.ctx.odometry_history.at(dets.stamp)
        odom_now = self.ctx.backend.odometry().pose
        moved = odom_now.relative_to(odom_then) if odom_then is not None else Pose2D()
        est = loc.pose() if loc.estimate() is not None else None
        fixes = [f.compose(moved) for f in pose_from_tag(self.ctx, dets)]     # from the image's time to now
        unsure = getattr(loc, "side_unsure", False)
        for fix in fixes:
            vouched = unsure or any(o is not fix and o.distance_to(fix) < 0.2
                                    and abs(wrap_angle(o.theta - fix.theta)) < 0.1 for o in fixes)
            if self.last is not None and fix.distance_to(self.last) > self.tag_reach and not vouched:
                continue
            d, a = ((math.inf, math.inf) if est is None
                    else (fix.distance_to(est), abs(wrap_angle(fix.theta - est.theta))))
            fits = loc.fit_now(fix) or 0.0
            if d > self.tag_disagreement or a > self.tag_disagreement:
                here = (loc.fit_now(est) or 0.0) if est is not None else 0.0
                if fits >= self.tag_fit and (unsure or fits >= here + 0.2):
                    loc.initialise(fix, (0.15, 0.15, 0.1))
                    if unsure:
                        loc.confirm()
                    self.tag_fixes += 1
                    self._good = 0
                    self._fair_from = None
                    self._agreed = False
                    return
            elif d <= self.tag_agreement and a <= self.tag_agreement and fits >= self.tag_fit:
                self._agreed = True
                if unsure:
                    loc.confirm()
                return

    def _step(self, now: float) -> Status:
        loc = self.ctx.pose_source
        self._look()
        loc.update(force=True)            # (the context's own update may have run it already)
        if loc.filter_updates != self._seen:
            self._seen = loc.filter_updates
            est = loc.estimate()
            fair = est.confidence >= self.hold and est.std_xy <= self.max_std
            good = fair and est.confidence >= loc.config.confident
            turned = abs(self.turn.by - self.turn.remaining)
            if not fair:
                self._fair_from = None
            elif self._fair_from is None:
                self._fair_from = turned
            self._good = self._good + 1 if good else 0
            # never doubtful while the robot turned far enough to see all round
            looked = (self._fair_from is not None and turned - self._fair_from >= self.look_around
                      and not getattr(loc, "side_unsure", False))
            if self._good >= self.settle and (self._agreed or looked):
                self.message = (f"relocalised, confidence {est.confidence:.2f}"
                                + (f" ({self.tag_fixes} tag fixes)" if self.tag_fixes else ""))
                return Status.SUCCESS
        if self.turn.poll() is not Status.RUNNING:
            raise SkillFailure(SkillError.LOCALISATION_LOST,
                               f"still lost after a full turn (confidence {loc.confidence:.2f})")
        return Status.RUNNING

    def _on_stop(self, status: Status) -> None:
        if self.turn is not None and self.turn.status is Status.RUNNING:
            self.turn.cancel()
        loc = self.ctx.pose_source
        if hasattr(loc, "unboost"):
            loc.unboost()
        if status is not Status.SUCCESS and self.last is not None and loc.pose() is None:
            # stopped before the search had a first estimate (cancelled, or no scan came): track
            # from where the robot was believed to be, as before, rather than leave it with no pose
            loc.initialise(self.last, self.spread)
        self.ctx.stop_base()
