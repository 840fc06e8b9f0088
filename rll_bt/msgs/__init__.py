"""Protobuf message sets: the refbox's ``llsf_msgs`` (2016 and today) and the team protocol.

Three sets, each compiled from ``.proto`` files in ``rll_bt/msgs/proto/<set>/``
and living in a descriptor pool of its own, so all of them can be used in
one process even though both refbox sets define ``llsf_msgs.GameState`` etc.:

- ``rcll2016``: the refbox at tag 2016-1 (20 files; zones Z1..Z24, DS by gate);
- ``rcll2025``: today's refbox (24 files; zones C_Zxy/M_Zxy, DS by order id,
  ``Order.competitive`` required, AgentTask ...);
- ``team``: rll-bt's own protocol between team server and robots
  (package ``rllbt``, COMP_ID 3000), what it adds to the league's AgentTask:
  TaskDetail/TaskOutcome,
  MachineObservation/ZoneExplored, RobotHello/Heartbeat/RobotStatus,
  MachineMap, GamePhase.

API::

    from rll_bt import msgs
    ms = msgs.message_set("rcll2016")   # "rcll2016", "rcll2025" or "team"; cached;
                                        # another name -> ValueError listing the known ones
    ms.name                             # "rcll2016"
    ms.GameState                        # class of a top-level message (attribute access;
                                        # top-level enums too, e.g. ms.Team)
    ms.get("GameState")                 # the same; KeyError with a clear message
    ms.classes                          # {name: class} of top-level messages with a CompType
    ms.all_classes                      # {name: class} of every top-level message
    ms.enum("Team")                     # enum wrapper (Name/Value/keys/values);
                                        # nested ones as ms.enum("GameState.Phase")
    ms.comp_type(cls_or_msg)            # (comp_id, msg_type) from the nested CompType, or None
    ms.by_comp_type                     # {(comp_id, msg_type): class}
    ms.decode(comp_id, msg_type, data)  # parse a payload by its message header
    msgs.PROFILES                       # ("rcll2016", "rcll2025"): the refbox sets
    msgs.SETS                           # ("rcll2016", "rcll2025", "team")
    msgs.to_dict(msg)                   # protobuf JSON mapping: original field names,
    msgs.from_dict(ms, "GameState", d)  # enums by name (from_dict: ValueError on bad input)

The generated modules ``_gen_<set>.py`` embed the compiled descriptors;
regenerate them after editing a ``.proto`` with ``python -m rll_bt.msgs.generate``
(``--check`` tells whether they are stale).
"""
from __future__ import annotations

from .jsonmap import from_dict, to_dict
from .messageset import MessageSet, comp_type_of, message_set
from .sources import SETS

#: The refbox message sets, one per rules profile.
PROFILES: tuple[str, ...] = ("rcll2016", "rcll2025")

__all__ = ["PROFILES", "SETS", "MessageSet", "comp_type_of", "from_dict", "message_set", "to_dict"]
