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

Team server -> robot: the league's ``AgentTask`` (:mod:`rll_bt.agenttask`):
a task runs the tree ``<kind>.yaml`` of the kind it reads as, with its
parameters as ``$task.NAME`` (:func:`rll_bt.agenttask.read_task`); one that
arrives while another runs waits for it; ``cancel_task`` halts the tree,
stops the robot and answers ``canceled``; ``pause_task`` holds the task
(true) or lets it go on (false).  A task id runs at most once
(:mod:`.taskbook`): sent again it is ignored while it runs or waits and
answered with its result once it ended (unless the server cancelled it and
gives it out again later).  From an rll-bt team server also
``TaskDetail`` (the rll-bt task behind an AgentTask), ``MachineMap``
(``services["machine_map"]`` and every service that takes it, see
:mod:`.machinemap`), ``GamePhase`` (game state and colour), ``Heartbeat``.

Robot -> team server (:mod:`.serverlink`): ``BeaconSignal`` every
``heartbeat_period`` (the current task in field 9, the last finished ones
in field 10), each result as the ``AgentTask`` echoed with ``successful``
/ ``canceled`` / ``error_code`` (the league's codes; results wait for the
link when it is down).  To an rll-bt team server also ``LinkAck`` for each
task and cancel, and its final results are repeated until acknowledged
(:mod:`.delivery`); also ``RobotHello`` on
every connect (``restarted`` on the first one after the agent started,
unless created with ``restarted=False``), ``RobotStatus`` every
``status_period`` and on every change of state or task, ``TaskOutcome``
before each result (rll-bt's code, text, ``holding``), and
``MachineObservation`` / ``ZoneExplored`` as they change
(:mod:`.observations`).  With ``league_only`` the robot says nothing but
the league's messages and finds the stations itself (:mod:`.localmap`).

Refbox: listens to ``GameState`` on the public channel; sends
``BeaconSignal`` on its team channel every ``beacon_period`` (pose; with
rcll2025 the current task and the finished ones, as to the team server);
with ``league_only`` it also reads ``MachineInfo`` on its team channel.  The robot stands still
unless the game is RUNNING outside PRE_GAME/POST_GAME (:mod:`.gamestate`):
the tree is halted and the robot stopped, and the tree starts again from
its root when the game resumes.
"""
from .config import AgentConfig, check_team_key, normalise_color
from .core import RobotAgent
from .errorcodes import error_code
from .gamestate import GameGate
from .localmap import LocalMachines
from .machinemap import KnownMachine, KnownMachines, changed_names, distribute
from .network import RefboxAddress, refbox_channels, team_server_link
from .observations import ObservationFeed
from .results import make_result
from .runner import InvalidTask, Outcome, TaskRun, default_trees_dir, load_task_tree
from .serverlink import ServerLink
from .taskbook import Entry, Result, TaskBook
from .tasks import TREE_KINDS, TREE_OUTPUTS, output_problems

__all__ = [
    "AgentConfig", "check_team_key", "normalise_color", "RobotAgent", "error_code", "GameGate", "KnownMachine",
    "KnownMachines", "changed_names", "distribute", "RefboxAddress", "refbox_channels", "team_server_link",
    "ObservationFeed",
    "LocalMachines", "make_result", "InvalidTask", "Outcome", "TaskRun", "default_trees_dir", "load_task_tree",
    "ServerLink", "Entry", "Result", "TaskBook", "TREE_KINDS", "TREE_OUTPUTS", "output_problems",
]
