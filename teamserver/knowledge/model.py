"""The team server's records: robots, orders, stations, workpieces, tasks.

Plain dataclasses that round-trip through JSON (``to_dict`` / ``from_dict``)
so the knowledge base can persist them one row each.  Times are seconds of
the server's clock (``Clock.now()``) unless a field says *game time*, which
is the refbox's game time of the current phase.  Poses are field frame
metres and radians (x, y, ori).
"""
from __future__ import annotations

from dataclasses import asdict, dataclass, field, fields
from typing import Any

# -- machine properties an observation can carry --------------------------
ZONE, POSE, ORIENTATION, LIGHT, TYPE = "zone", "pose", "orientation", "light", "type"
PROPERTIES = (ZONE, POSE, ORIENTATION, LIGHT, TYPE)

# -- robot status -----------------------------------------------------------
ACTIVE, LOST = "ACTIVE", "LOST"

# -- task kinds (the team protocol's Task variants) --------------------------
EXPLORE_ZONE = "explore_zone"
GET_WORKPIECE = "get_workpiece"
PUT_WORKPIECE = "put_workpiece"
RETRIEVE_CAP = "retrieve_cap"
MOUNT_RING = "mount_ring"
MOUNT_CAP = "mount_cap"
DELIVER = "deliver"
DISCARD = "discard"
REPORT_MACHINES = "report_machines"
GO_TO = "go_to"            # params x, y, theta (field frame): park an idle robot there
TASK_KINDS = (EXPLORE_ZONE, GET_WORKPIECE, PUT_WORKPIECE, RETRIEVE_CAP, MOUNT_RING, MOUNT_CAP,
              DELIVER, DISCARD, REPORT_MACHINES, GO_TO)

# -- task states --------------------------------------------------------------
PENDING = "PENDING"        # planned, waiting for predecessors / a robot / a station
ASSIGNED = "ASSIGNED"      # sent to a robot, no result yet
DONE = "DONE"
FAILED = "FAILED"
CANCELLED = "CANCELLED"
OPEN_STATES = (PENDING, ASSIGNED)
CLOSED_STATES = (DONE, FAILED, CANCELLED)

# -- machine sides -------------------------------------------------------------
INPUT, OUTPUT, SLIDE, SHELF = "INPUT", "OUTPUT", "SLIDE", "SHELF"


class Record:
    """JSON round trip for the dataclasses below."""

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)

    @classmethod
    def from_dict(cls, data: dict[str, Any]):
        names = {f.name for f in fields(cls)}
        kw = {k: v for k, v in data.items() if k in names}
        for k, v in kw.items():
            if isinstance(v, list) and k in cls._tuples:
                kw[k] = tuple(v)
        return cls(**kw)

    _tuples: tuple[str, ...] = ()


@dataclass
class Observation(Record):
    """One robot's statement about one property of one machine.

    ``value``: zone number; pose ``(x, y, ori)``; orientation in degrees
    (the profile's rotation step); light as the sorted tuple of lights that
    are on (e.g. ``("GREEN", "RED")``); type as "BS"/"CS"/"RS"/"DS"/"SS".
    ``confidence`` in [0, 1]; ``time`` server seconds.
    """

    machine: str
    prop: str
    value: Any
    confidence: float
    robot: str
    time: float = 0.0

    def __post_init__(self) -> None:
        if self.prop not in PROPERTIES:
            raise ValueError(f"unknown machine property {self.prop!r} (one of {PROPERTIES})")
        if isinstance(self.value, list):
            self.value = tuple(self.value)
        if not 0.0 <= float(self.confidence) <= 1.0:
            raise ValueError(f"confidence {self.confidence} outside [0, 1]")
        self.confidence = float(self.confidence)


#: joins a robot and its view of a signal tower in an observation's source ("R1#v2")
VIEW_MARK = "#v"


def view_source(robot: str, view: int) -> str:
    """The source name of a light read by ``robot`` from its ``view`` of the
    tower: each view of a tower votes once, its latest reading (see
    :class:`~.kb.KnowledgeBase`), and views are the independent readings the
    exploration's light gate counts (:mod:`teamserver.exploration.lights`)."""
    return f"{robot}{VIEW_MARK}{int(view)}"


def is_view_source(source: str) -> bool:
    return VIEW_MARK in source



@dataclass
class Robot(Record):
    """A connected (or once connected) robot agent, keyed by its jersey ``number``."""

    number: int
    name: str = ""
    status: str = ACTIVE
    pose: tuple[float, float, float] | None = None
    task_id: int | None = None
    last_heartbeat: float = 0.0
    holding: str | None = None          # workpiece id in the gripper ("?" if unknown)
    gripper: bool = False               # the robot's own word: its gripper holds something
    waiting_at: str | None = None       # ... docked at this station, waiting for its prepare
    peer: Any = None                    # transport address (not meaningful after a restart)
    state: str = "IDLE"                 # the agent's own RobotStatus.State
    _tuples = ("pose",)

    @property
    def key(self) -> str:
        """The robot's name in observations and plans (``"R<number>"``)."""
        return f"R{self.number}"


@dataclass
class Order(Record):
    """An order from OrderInfo; window in production game seconds."""

    id: int
    complexity: int
    base: str
    rings: tuple[str, ...]
    cap: str
    quantity: int = 1
    delivered: int = 0                  # by our team
    begin: float = 0.0
    end: float = 0.0
    gate: int = 0
    competitive: bool = False
    _tuples = ("rings",)

    @property
    def open(self) -> int:
        return max(self.quantity - self.delivered, 0)


@dataclass
class Station(Record):
    """A machine's production state from MachineInfo (plus what we track)."""

    name: str
    state: str = "IDLE"
    loaded_with: int = 0
    ring_colors: tuple[str, ...] = ()
    correctly_reported: bool = False
    zone: int | None = None             # ground truth, once the refbox releases it
    rotation: int | None = None
    cap_buffered: bool = False          # a CS holds a retrieved cap (our bookkeeping)
    since: float = 0.0                  # server time of the last state change
    fed_at: float = 0.0                 # server time it last took a workpiece (left PREPARED)
    shelf: tuple[str, ...] = ()         # a storage station's filled places ("shelf,slot")
    stored: tuple[str, ...] = ()        # ... with their descriptions ("shelf,slot=BASE_RED CAP_GREY")
    _tuples = ("ring_colors", "shelf", "stored")


@dataclass
class Workpiece(Record):
    """A physical workpiece: what it is and where it is.

    ``location``: ``"robot:<name>"``, ``"<machine>:<side>"`` or ``"gone"``.
    """

    id: str
    base: str | None = None
    rings: tuple[str, ...] = ()
    cap: str | None = None
    location: str = "gone"
    product: str | None = None
    _tuples = ("rings",)


@dataclass
class Task(Record):
    """A unit of work for one robot: the team protocol's Task, plus plan bookkeeping.

    ``params``: the kind's arguments (machine, side, colour, zone, ...).
    ``deps``: ids of tasks that must be DONE first.  ``product``: the product
    (plan) this task belongs to, None for exploration.  ``prepare``: the
    PrepareMachine this task needs, as a dict (machine, instruction fields),
    and ``prepared_at`` when it was last sent.  ``locks``: machines this task
    holds while assigned; ``keep_locks``: machines it leaves locked for a
    later task of the same product (``releases`` names the ones it frees).
    ``after``: the robot's current task this one was sent to run after
    (:meth:`teamserver.dispatch.fleet.Fleet.queue`), until that one's result.
    """

    id: int
    kind: str
    params: dict = field(default_factory=dict)
    state: str = PENDING
    robot: int | None = None
    product: str | None = None
    deps: tuple[int, ...] = ()
    prepare: dict | None = None
    prepared_at: float | None = None
    locks: tuple[str, ...] = ()
    releases: tuple[str, ...] = ()
    carry: bool = False                 # the robot must hold the workpiece already
    holder: int | None = None           # robot bound to a carry task
    attempts: int = 0
    created: float = 0.0
    assigned_at: float | None = None
    finished_at: float | None = None
    error: str | None = None
    after: int | None = None            # queued on its robot behind this task (id): sent before it ended
    _tuples = ("deps", "locks", "releases")

    @property
    def machine(self) -> str | None:
        return self.params.get("machine")


@dataclass
class Product(Record):
    """One product being made for an order: its plan's task ids and progress."""

    id: str
    order_id: int
    state: str = "ACTIVE"               # ACTIVE, DELIVERED, ABANDONED
    tasks: tuple[int, ...] = ()
    workpiece: str | None = None        # id of the product's own workpiece
    created: float = 0.0
    repair: str | None = None           # why it must be re-planned (None: it need not)
    repairs: int = 0
    delivered_at: float | None = None   # game time of our delivery (the refbox confirms it)
    _tuples = ("tasks",)
