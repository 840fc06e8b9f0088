"""Activity semantics and the error codes."""
from rll_bt.backend import BackendError
from skills.activity import Activity, Sequence, Status
from skills.errors import SkillError, SkillFailure
from tests.support.skills_scene import Scene


class Counter(Activity):
    name = "counter"

    def __init__(self, ctx, n, fail=None, timeout=None):
        super().__init__(ctx, timeout)
        self.n, self.fail, self.polls = n, fail, 0

    def _step(self, now):
        self.polls += 1
        if self.fail and self.polls == self.n:
            raise SkillFailure(self.fail, "planned failure")
        if self.polls == 3 and self.n < 0:
            raise BackendError("serial link lost")
        return Status.SUCCESS if self.polls >= abs(self.n) else Status.RUNNING


def test_poll_until_done_and_idempotent_afterwards():
    scene = Scene(localisation=None)
    a = Counter(scene.ctx, 3).start()
    assert [a.poll() for _ in range(4)] == [Status.RUNNING, Status.RUNNING, Status.SUCCESS, Status.SUCCESS]
    assert a.polls == 3 and a.error is SkillError.NONE


def test_failure_timeout_and_backend_errors_carry_codes():
    scene = Scene(localisation=None)
    assert scene.run(Counter(scene.ctx, 2, SkillError.ALIGN_FAILED)) is Status.FAILURE
    t = Counter(scene.ctx, 1000, timeout=1.0)
    assert scene.run(t) is Status.FAILURE and t.error is SkillError.TIMEOUT
    b = Counter(scene.ctx, -10)
    assert scene.run(b) is Status.FAILURE and b.error is SkillError.INTERNAL and "serial" in b.message


def test_sequence_runs_children_in_order_and_stops_at_the_first_failure():
    scene = Scene(localisation=None)
    made = []

    def child(n, fail=None):
        def make():
            c = Counter(scene.ctx, n, fail)
            made.append(c)
            return c
        return make

    seq = Sequence(scene.ctx, [child(2), child(2, SkillError.GRAB_FAILED), child(1)], name="s")
    assert scene.run(seq) is Status.FAILURE
    assert seq.error is SkillError.GRAB_FAILED and len(made) == 2
    ok = Sequence(scene.ctx, [child(1), child(3)])
    assert scene.run(ok) is Status.SUCCESS


def test_cancel_stops_the_robot_and_the_running_child():
    scene = Scene(localisation=None)
    inner = []
    seq = Sequence(scene.ctx, [lambda: inner.append(Counter(scene.ctx, 100)) or inner[-1]]).start()
    scene.robot.drive(0.3, 0.0, 0.0)
    seq.poll()
    seq.cancel()
    assert seq.status is Status.CANCELLED and inner[0].status is Status.CANCELLED
    assert tuple(scene.robot.cmd) == (0.0, 0.0, 0.0)


def test_error_names_are_team_protocol_error_codes():
    from rll_bt.msgs import message_set
    codes = message_set("team").enum("ErrorCode")
    for e in SkillError:
        assert codes.Value(e.value) >= 0            # raises for a name the protocol lacks
