"""Gripper use as a non-blocking activity: a list of steps, each sent once
and waited for until the gripper reports IDLE again.

A step is done when the gripper reports IDLE after having reported MOVING,
or after ``min_wait`` seconds (a real gripper reports its state late).

Steps: ``("open",)``, ``("close",)``, ``("move", x, y, z)``, ``("sense",)``,
``("expect_holding", True|False, code)``.  An ``expect_holding`` step
checks ``backend.holding()`` and fails with ``code`` (GRAB_FAILED after a
grab, PUT_FAILED after a put) when it disagrees: the paper's first error
detection.  A ``sense`` step (with the open fingers at the place) reads the
gripper's workpiece sensor (``GripperStatus.sensed``): a grab that finds
the gripper empty after the sensor saw nothing there fails with a message
beginning :data:`NOTHING_FOUND` (nothing to take: the league's
NO_WORKPIECE_FOUND), else with "no workpiece in the gripper" (the grasp
failed: GRASPING_FAILED).  A gripper in state ERROR fails with GRIPPER_ERROR; a step
taking longer than ``step_time`` too.  However the sequence ends, the
gripper is sent back home (x = 0, y = 0) unless told otherwise.
"""
from __future__ import annotations

from rll_bt.agenttask.codes import NOTHING_FOUND
from rll_bt.backend import BackendError, CapabilityError, GripperState

from ..activity import Activity, Status
from ..errors import SkillError, SkillFailure


class GripperSequence(Activity):
    name = "gripper"

    def __init__(self, ctx, steps, home_z: float | None = None, step_time: float | None = None,
                 name: str | None = None):
        super().__init__(ctx, None)
        self.steps = list(steps)
        self.home_z = home_z
        self.step_time = step_time or ctx.settings.manipulation.gripper_step_time
        self.holding: bool | None = None
        self.sensed: bool | None = None     # the workpiece sensor at the last ``sense`` step
        self.min_wait = 0.2       # s; a gripper may report MOVING only after a while
        if name:
            self.name = name

    def _on_start(self) -> None:
        self._index = 0
        self._sent_at: float | None = None
        self._seen_moving = False
        self.sensed = None

    def _status(self):
        try:
            return self.ctx.backend.gripper_status()
        except CapabilityError as exc:
            raise SkillFailure(SkillError.GRIPPER_ERROR, str(exc)) from None

    def _step(self, now: float) -> Status:
        while self._index < len(self.steps):
            step = self.steps[self._index]
            if step[0] == "expect_holding":
                want, code = step[1], step[2]
                held = self.ctx.backend.holding()
                self.holding = held
                if held is not None and bool(held) != want:
                    if want and self.sensed is False:
                        raise SkillFailure(code, f"{NOTHING_FOUND} ({self.name}: nothing between the open fingers)")
                    what = "no workpiece in the gripper" if want else "the workpiece is still in the gripper"
                    raise SkillFailure(code, f"{what} ({self.name})")
                self._index += 1
                continue
            if step[0] == "sense":
                self.sensed = self._status().sensed
                self._index += 1
                continue
            if self._sent_at is None:
                self._send(step)
                self._sent_at = now
                self._seen_moving = False
                return Status.RUNNING
            st = self._status()
            if st.state is GripperState.ERROR:
                raise SkillFailure(SkillError.GRIPPER_ERROR, f"gripper error during {step[0]}: {st.message}")
            if st.state is GripperState.MOVING:
                self._seen_moving = True
            elif st.state is GripperState.IDLE and (self._seen_moving or now - self._sent_at >= self.min_wait):
                self._index += 1
                self._sent_at = None
                continue
            if now - self._sent_at > self.step_time:
                raise SkillFailure(SkillError.GRIPPER_ERROR,
                                   f"gripper {step[0]} did not finish in {self.step_time:.0f} s")
            return Status.RUNNING
        return Status.SUCCESS

    def _send(self, step) -> None:
        b = self.ctx.backend
        try:
            if step[0] == "open":
                b.gripper_open()
            elif step[0] == "close":
                b.gripper_close()
            elif step[0] == "move":
                b.gripper_move(*step[1:4])
            else:
                raise ValueError(f"unknown gripper step {step!r}")
        except CapabilityError as exc:
            raise SkillFailure(SkillError.GRIPPER_ERROR, str(exc)) from None
        except BackendError as exc:
            raise SkillFailure(SkillError.GRIPPER_ERROR, f"gripper {step[0]}: {exc}") from None

    def _on_stop(self, status: Status) -> None:
        self.ctx.stop_base()
        if self.home_z is not None and status is not Status.SUCCESS:
            try:
                self.ctx.backend.gripper_move(0.0, 0.0, self.home_z)
            except BackendError:
                pass
