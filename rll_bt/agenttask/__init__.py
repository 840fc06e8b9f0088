"""The task protocol between the team server and its robots: the league's AgentTask.

The paper's layers talked through its ``PrsTask`` (Listing 1); the league's
``llsf_msgs.AgentTask`` grew out of it, and today's refbox, the league's
simulator and the strongest teams' agents speak it.  rll-bt's team server
and robots speak it too, so any robot that speaks AgentTask can be driven by
rll-bt's team server and any AgentTask team server can drive rll-bt's
robots (``reference/league-interfaces.md``, ``docs/league.md``).

On the link (:mod:`.link`; TCP or the in-process bus, protobuf_comm frames):

- server -> robot: ``AgentTask`` (a task; ``cancel_task``; ``pause_task``);
- robot -> server: ``AgentTask`` echoed with ``successful`` / ``canceled`` /
  ``error_code`` when the task ends, and ``BeaconSignal`` (rcll2025:
  current task in field 9, finished tasks in field 10) every second;
- between rll-bt peers only, rll-bt's additions (package ``rllbt``):
  ``TaskDetail`` before a task, ``TaskOutcome`` before a result,
  ``RobotHello``, ``RobotStatus``, ``MachineObservation``, ``ZoneExplored``,
  ``MachineMap``, ``GamePhase``, ``Heartbeat``.

Modules: :mod:`.render` (an rll-bt task as AgentTask + TaskDetail, the
server's side), :mod:`.read` (back to a tree and its parameters, the
robot's side), :mod:`.codes` (rll-bt's error codes and the league's),
:mod:`.link` (the link's messages and transports, and its encryption).

Task ids: a team server never gives two tasks the same id (rll-bt's keeps
its counter in its database, so not across a restart either); a robot
runs a task id at most once: a task sent again while it runs, waits or
after it ended is not run again (after it ended, its result is sent again).
"""
from .codes import from_league, holding_after, league_name, league_value, to_league
from .read import BODIES, TaskRejected, body_of, read_task
from .render import KINDS, nearest_zone, render_cancel, render_pause, render_task

__all__ = ["from_league", "holding_after", "league_name", "league_value", "to_league", "BODIES",
           "TaskRejected", "body_of", "read_task", "KINDS", "nearest_zone", "render_cancel", "render_pause",
           "render_task"]
