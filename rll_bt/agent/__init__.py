"""The robot agent: one robot's mid-level between the team server, the
refbox and its behaviour trees.

    from rll_bt.agent import AgentConfig, RobotAgent
    agent = RobotAgent(AgentConfig(robot_id=1, team_name="GRIPS", profile="rcll2016"),
                       clock=clock, backend=robot, link=link, public=public, team=team)
    agent.step()        # call often; ticks the task tree at config.hz on ``clock``

Lockstep simulation passes bus transports (``Bus.stream_client`` with the
team key, ``Bus.peer("public")``, and ``lambda color: bus.peer(color.lower(),
key=KEY)``) and a :class:`~rll_bt.clock.SimClock`; ``rll-bt agent`` passes
sockets from :mod:`rll_bt.agent.network` and the wall clock.  No threads.

Team server -> robot (``rllbt`` set): ``Task`` (runs ``<kind>.yaml`` with
the task's fields as ``$task.NAME``, see :mod:`.tasks`), ``CancelTask``
(halts the tree, stops the robot, answers CANCELLED), ``MachineMap``
(``services["machine_map"]`` and every service that takes it, see
:mod:`.machinemap`), ``GamePhase`` (game state and colour), ``Heartbeat``.

Robot -> team server: ``RobotHello`` on every connect (``restarted`` on the
first one after the agent started, unless created with
``restarted=False``), ``Heartbeat`` every ``heartbeat_period``,
``RobotStatus`` every ``status_period`` and on every change of state or
task, ``TaskResult`` (RUNNING on acceptance and again when the server
re-sends the task; SUCCEEDED / FAILED with an ``ErrorCode`` /
CANCELLED, with ``holding`` set while the gripper holds something; final
results wait for the link when it is down), ``MachineObservation`` and
``ZoneExplored`` as they change (:mod:`.observations`).

Refbox: listens to ``GameState`` on the public channel; sends
``BeaconSignal`` on its team channel every ``beacon_period`` (pose; with
rcll2025 the current task as ``AgentTask`` and finished tasks) and
``MachineReport`` for ``report_machines`` tasks.  The robot stands still
unless the game is RUNNING outside PRE_GAME/POST_GAME (:mod:`.gamestate`):
the tree is halted and the robot stopped, and the tree starts again from
its root when the game resumes.
"""
from .config import AgentConfig, check_team_key, normalise_color
from .core import RobotAgent
from .errorcodes import error_code
from .gamestate import GameGate
from .machinemap import KnownMachine, KnownMachines, changed_names, distribute
from .network import RefboxAddress, refbox_channels, team_server_link
from .observations import ObservationFeed
from .runner import Outcome, TaskRun, default_trees_dir, load_task_tree
from .tasks import (
    TASK_KINDS,
    TREE_KINDS,
    TREE_OUTPUTS,
    InvalidTask,
    agent_task,
    output_problems,
    task_kind,
    task_params,
)

__all__ = [
    "AgentConfig", "check_team_key", "normalise_color", "RobotAgent", "error_code", "GameGate", "KnownMachine",
    "KnownMachines", "changed_names", "distribute", "RefboxAddress", "refbox_channels", "team_server_link",
    "ObservationFeed",
    "Outcome", "TaskRun", "default_trees_dir", "load_task_tree", "TASK_KINDS", "TREE_KINDS", "TREE_OUTPUTS",
    "output_problems", "InvalidTask",
    "agent_task", "task_kind", "task_params",
]
