"""One robot on a :class:`~rll_bt.watch.sink.Watch`: what it believes, what
it sees and what its tree does.

- ``/robotN/pose``: the agent's estimated field pose (``foxglove.PoseInFrame``);
- ``/robotN/scan``: every laser scan the robot's skills read
  (``foxglove.LaserScan`` placed in the field at the estimated pose);
- ``/robotN/camera``: camera frames the skills read, JPEG
  (``foxglove.CompressedImage``, at most ``camera_hz``), and with
  ``force_camera_hz`` frames taken for the recording itself;
- ``/robotN/detections``: tags and lights the backend reported (JSON);
- ``/robotN/tree/structure``: a task tree's nodes when it starts (JSON);
- ``/robotN/tree``: every tick: the nodes visited and their status, the
  nodes running afterwards, the blackboard keys written and removed, the
  root's status; the task's outcome when it ends (JSON).

:class:`TappedBackend` passes every call to the robot's backend and shows
the sensor readings to the watch on the way, so recording changes nothing
the robot does.  :class:`RobotWatch` is an observer of a
:class:`~rll_bt.agent.RobotAgent` (``agent.observers``).
"""
from __future__ import annotations

from typing import Any

from py_trees.common import Status

from ..backend import Backend, Pose2D
from ..tree.blackboard import UNSET
from ..tree.ticklog import jsonable

TREE_SCHEMA = {"title": "rllbt.TreeTick", "type": "object", "properties": {
    "task_id": {"type": "integer"}, "kind": {"type": "string"}, "tick": {"type": "integer"},
    "status": {"type": "string"}, "visited": {"type": "array"}, "running": {"type": "array"},
    "bb": {"type": "object"}, "unset": {"type": "array"}, "outcome": {"type": "object"}}}
STRUCTURE_SCHEMA = {"title": "rllbt.TreeStructure", "type": "object", "properties": {
    "task_id": {"type": "integer"}, "kind": {"type": "string"}, "name": {"type": "string"},
    "nodes": {"type": "array"}}}
DETECTIONS_SCHEMA = {"title": "rllbt.Detections", "type": "object", "properties": {
    "tags": {"type": "array"}, "lights": {"type": "array"}}}


class TappedBackend(Backend):
    """A backend that shows its laser scans, camera frames and detections to
    ``robot_watch`` and otherwise is ``inner``."""

    def __init__(self, inner: Backend, robot_watch: RobotWatch):
        self.inner = inner
        self.robot_watch = robot_watch
        self.name = getattr(inner, "name", "tapped")

    @property
    def capabilities(self):
        return self.inner.capabilities

    def drive(self, vx, vy, omega):
        return self.inner.drive(vx, vy, omega)

    def stop(self):
        return self.inner.stop()

    def odometry(self):
        return self.inner.odometry()

    def laser_scan(self):
        scan = self.inner.laser_scan()
        if scan is not None:
            self.robot_watch.saw_scan(scan)
        return scan

    def camera_image(self, camera: str = "front"):
        img = self.inner.camera_image(camera)
        if img is not None:
            self.robot_watch.saw_image(img)
        return img

    def detections(self, camera: str = "front"):
        d = self.inner.detections(camera)
        self.robot_watch.saw_detections(d)
        return d

    def __getattr__(self, name: str) -> Any:     # gripper, bumper, battery, world-specific extras
        return getattr(self.inner, name)

    def close(self):
        return self.inner.close()


def _passes(name: str):
    def call(self, *args, **kw):
        return getattr(self.inner, name)(*args, **kw)
    call.__name__ = name
    return call


for _m in ("bumper", "battery", "gripper_open", "gripper_close", "gripper_move", "gripper_status", "holding"):
    setattr(TappedBackend, _m, _passes(_m))


class RobotWatch:
    """Puts one robot's pose, sensors and trees on ``watch`` (see the module doc)."""

    def __init__(self, watch, number: int, *, pose_hz: float = 10.0, scan_hz: float = 5.0,
                 camera_hz: float = 2.0, force_camera_hz: float = 0.0, detections_hz: float = 2.0):
        self.watch = watch
        self.number = number
        self.prefix = f"/robot{number}"
        self.agent = None
        self.backend: Backend | None = None
        self._period = {"pose": _period(pose_hz), "scan": _period(scan_hz), "camera": _period(camera_hz),
                        "force": _period(force_camera_hz), "detections": _period(detections_hz)}
        self._next = dict.fromkeys(self._period, -1e+18)
        self._last_scan_stamp = None
        self._tree = None
        self._run = None
        self._prev: dict[int, Status] = {}
        self.pose_estimate: Pose2D | None = None

    def _due(self, what: str, now: float) -> bool:
        period = self._period[what]
        if period is None or now < self._next[what] - 1e-6:
            return False
        nxt = self._next[what] + period             # a fixed schedule: no drift with the step size
        self._next[what] = nxt if nxt > now else now + period
        return True

    def _now(self) -> float:
        return self.watch.clock.now() if self.watch.clock is not None else 0.0

    # -- the robot's backend -------------------------------------------------------------
    def tap(self, backend: Backend) -> TappedBackend:
        self.backend = backend
        return TappedBackend(backend, self)

    def saw_scan(self, scan) -> None:
        if scan.stamp == self._last_scan_stamp or not self._due("scan", self._now()):
            return
        self._last_scan_stamp = scan.stamp
        self.watch.scan(f"{self.prefix}/scan", scan, self.pose_estimate)

    def saw_image(self, img) -> None:
        if self._due("camera", self._now()):
            self.watch.image(f"{self.prefix}/camera", img)

    def saw_detections(self, d) -> None:
        if not (d.tags or d.lights) or not self._due("detections", self._now()):
            return
        self.watch.json(f"{self.prefix}/detections", {
            "tags": [{"id": t.tag_id, "tvec": list(t.tvec), "rvec": list(t.rvec), "camera": t.camera} for t in d.tags],
            "lights": [{"state": li.state, "box": list(li.box), "score": li.score, "tag_id": li.tag_id}
                       for li in d.lights]}, schema=DETECTIONS_SCHEMA)

    # -- agent observer ---------------------------------------------------------------------
    def attach(self, agent) -> None:
        """Observe ``agent`` (its pose and task trees)."""
        self.agent = agent
        agent.observers.append(self)

    def stepped(self, agent) -> None:
        now = self._now()
        if self._due("pose", now):
            pose, _conf = agent.pose.read()
            if pose is not None:
                self.pose_estimate = pose
                self.watch.pose(f"{self.prefix}/pose", pose)
        if self.backend is not None and self._due("force", now):
            try:
                img = self.backend.camera_image()
            except Exception:
                self._period["force"] = None
                return
            if img is not None:
                self.watch.image(f"{self.prefix}/camera", img)

    def task_started(self, agent, run) -> None:
        tree = run.tree
        self._run, self._tree = run, tree
        self._ids = {id(info.behaviour): info.id for info in tree.nodes}
        self._prev = {}
        self.watch.json(f"{self.prefix}/tree/structure", {
            "task_id": run.task_id, "kind": run.kind, "name": tree.name,
            "nodes": [{"id": i.id, "parent": i.parent, "depth": i.depth, "name": i.behaviour.name,
                       "type": i.spec.type if i.spec else type(i.behaviour).__name__} for i in tree.nodes]},
            schema=STRUCTURE_SCHEMA)
        tree.blackboard.drain_journal()
        tree.blackboard.start_journal()
        tree.add_observer(self._ticked)

    def _ticked(self, tree, visited) -> None:
        if tree is not self._tree:
            return
        ids = self._ids
        vis = [[ids[id(b)], b.status.name] for b in visited if id(b) in ids]
        running = [i.id for i in tree.nodes if i.behaviour.status is Status.RUNNING]
        changes = tree.blackboard.drain_journal()
        msg = {"task_id": self._run.task_id, "kind": self._run.kind, "tick": tree.count,
               "status": tree.root.status.name, "visited": vis, "running": running}
        bb = {k: jsonable(v) for k, v in changes.items() if v is not UNSET}
        if bb:
            msg["bb"] = bb
        unset = [k for k, v in changes.items() if v is UNSET]
        if unset:
            msg["unset"] = unset
        self.watch.json(f"{self.prefix}/tree", msg, schema=TREE_SCHEMA)

    def task_ended(self, agent, run, outcome) -> None:
        if run.tree is self._tree:
            try:
                run.tree.remove_observer(self._ticked)
            except ValueError:
                pass
            run.tree.blackboard.stop_journal()
            self._tree = None
        self.watch.json(f"{self.prefix}/tree", {
            "task_id": run.task_id, "kind": run.kind, "tick": run.tree.count, "status": run.tree.root.status.name,
            "visited": [], "running": [],
            "outcome": {"status": outcome.status, "code": str(outcome.code), "text": outcome.text}},
            schema=TREE_SCHEMA)


def _period(hz: float) -> float | None:
    return 1.0 / hz if hz and hz > 0 else None
