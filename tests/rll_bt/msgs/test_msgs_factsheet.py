"""The message sets against the fact sheet (shared/reference/refbox-protocol.md §1, §3).

Field tables are written the way the fact sheet lists them:
``number label type name`` (``req``/``opt``/``rep``).  Every table lists all
fields of the message, so an extra field fails as well as a wrong one.
"""
from __future__ import annotations

import pytest
from google.protobuf import descriptor_pb2

from rll_bt import msgs

FDP = descriptor_pb2.FieldDescriptorProto
LABELS = {"req": FDP.LABEL_REQUIRED, "opt": FDP.LABEL_OPTIONAL, "rep": FDP.LABEL_REPEATED}
SCALARS = {"int64": FDP.TYPE_INT64, "uint64": FDP.TYPE_UINT64, "uint32": FDP.TYPE_UINT32,
           "float": FDP.TYPE_FLOAT, "double": FDP.TYPE_DOUBLE, "bool": FDP.TYPE_BOOL,
           "string": FDP.TYPE_STRING}

BOTH = ("rcll2016", "rcll2025")
R16, R25 = ("rcll2016",), ("rcll2025",)

FIELDS = [
    (BOTH, "Time", "1 req int64 sec; 2 req int64 nsec"),
    (BOTH, "Pose2D", "1 req Time timestamp; 2 req float x; 3 req float y; 4 req float ori"),
    (R16, "BeaconSignal", "1 req Time time; 2 req uint64 seq; 8 req uint32 number; "
                          "4 req string team_name; 5 req string peer_name; 6 opt Team team_color; "
                          "7 opt Pose2D pose"),
    (R25, "BeaconSignal", "1 req Time time; 2 req uint64 seq; 8 req uint32 number; "
                          "4 req string team_name; 5 req string peer_name; 6 opt Team team_color; "
                          "7 opt Pose2D pose; 9 opt AgentTask task; "
                          "10 rep FinishedTask finished_tasks"),
    (R25, "FinishedTask", "1 req uint32 TaskId; 2 req bool successful"),
    (R16, "GameState", "1 req Time game_time; 3 req State state; 4 req Phase phase; "
                       "5 opt uint32 points_cyan; 6 opt string team_cyan; "
                       "8 opt uint32 points_magenta; 9 opt string team_magenta"),
    (R25, "GameState", "1 req Time game_time; 3 req State state; 4 req Phase phase; "
                       "5 opt uint32 points_cyan; 6 opt string team_cyan; "
                       "8 opt uint32 points_magenta; 9 opt string team_magenta; "
                       "10 opt uint32 field_height; 11 opt uint32 field_width; "
                       "12 opt bool field_mirrored"),
    (BOTH, "SetGameState", "1 req State state"),
    (BOTH, "SetGamePhase", "1 req Phase phase"),
    (R25, "RandomizeField", ""),
    (BOTH, "MachineInfo", "1 rep Machine machines; 2 opt Team team_color"),
    (R16, "Machine", "1 req string name; 2 opt string type; 3 opt string state; "
                     "10 opt Team team_color; 7 rep LightSpec lights; 8 opt Pose2D pose; "
                     "11 opt Zone zone; 9 opt bool correctly_reported; 13 opt uint32 loaded_with; "
                     "14 rep RingColor ring_colors; 16 opt PrepareInstructionBS instruction_bs; "
                     "17 opt PrepareInstructionDS instruction_ds; "
                     "18 opt PrepareInstructionRS instruction_rs; "
                     "19 opt PrepareInstructionCS instruction_cs; "
                     "21 opt ExplorationState exploration_type_state; "
                     "22 opt ExplorationState exploration_zone_state"),
    (R25, "Machine", "1 req string name; 2 opt string type; 3 opt string state; "
                     "10 opt Team team_color; 5 opt uint32 input_tag; 6 opt uint32 output_tag; "
                     "7 rep LightSpec lights; 8 opt Pose2D pose; 11 opt Zone zone; "
                     "12 opt uint32 rotation; 9 opt bool correctly_reported; "
                     "13 opt uint32 loaded_with; 14 rep RingColor ring_colors; "
                     "16 opt PrepareInstructionBS instruction_bs; "
                     "17 opt PrepareInstructionDS instruction_ds; "
                     "18 opt PrepareInstructionRS instruction_rs; "
                     "19 opt PrepareInstructionCS instruction_cs; "
                     "20 opt PrepareInstructionSS instruction_ss; "
                     "21 opt ExplorationState exploration_rotation_state; "
                     "22 opt ExplorationState exploration_zone_state; "
                     "25 rep ShelfSlotInfo status_ss"),
    (R25, "ShelfSlotInfo", "1 req uint32 shelf; 2 req uint32 slot; 3 req bool is_filled; "
                           "5 opt string description"),
    (BOTH, "LightSpec", "1 req LightColor color; 2 req LightState state"),
    (BOTH, "MachineReport", "2 req Team team_color; 1 rep MachineReportEntry machines"),
    (R16, "MachineReportEntry", "1 req string name; 2 opt string type; 3 opt Zone zone"),
    (R25, "MachineReportEntry", "1 opt string name; 2 opt string type; 3 opt Zone zone; "
                                "4 opt uint32 rotation"),
    (R16, "MachineReportInfo", "1 rep string reported_machines; 2 req Team team_color"),
    (R25, "MachineReportInfo", "1 rep string reported_machines; 2 req Team team_color; "
                               "3 rep MachineTypeFeedback reported_types"),
    (R25, "MachineTypeFeedback", "1 req string type; 2 req Zone zone; 3 opt string name; "
                                 "4 opt Team team_color"),
    (BOTH, "ExplorationInfo", "1 rep ExplorationSignal signals; 2 rep ExplorationZone zones"),
    (BOTH, "ExplorationSignal", "1 req string type; 2 rep LightSpec lights"),
    (BOTH, "ExplorationZone", "2 req Zone zone; 3 req Team team_color"),
    (BOTH, "OrderInfo", "1 rep Order orders"),
    (R16, "Order", "1 req uint32 id; 2 req Complexity complexity; 3 req BaseColor base_color; "
                   "4 rep RingColor ring_colors; 5 req CapColor cap_color; "
                   "6 req uint32 quantity_requested; 7 req uint32 quantity_delivered_cyan; "
                   "8 req uint32 quantity_delivered_magenta; 9 req uint32 delivery_period_begin; "
                   "10 req uint32 delivery_period_end; 11 req uint32 delivery_gate"),
    (R25, "Order", "1 req uint32 id; 2 req Complexity complexity; 3 req BaseColor base_color; "
                   "4 rep RingColor ring_colors; 5 req CapColor cap_color; "
                   "6 req uint32 quantity_requested; 7 req uint32 quantity_delivered_cyan; "
                   "8 req uint32 quantity_delivered_magenta; 9 req uint32 delivery_period_begin; "
                   "10 req uint32 delivery_period_end; 11 req uint32 delivery_gate; "
                   "12 rep UnconfirmedDelivery unconfirmed_deliveries; 13 req bool competitive"),
    (R25, "UnconfirmedDelivery", "1 req uint32 id; 2 req Team team; 3 req Time delivery_time"),
    (R16, "PrepareMachine", "1 req Team team_color; 2 req string machine; "
                            "4 opt PrepareInstructionBS instruction_bs; "
                            "5 opt PrepareInstructionDS instruction_ds; "
                            "6 opt PrepareInstructionRS instruction_rs; "
                            "7 opt PrepareInstructionCS instruction_cs"),
    (R25, "PrepareMachine", "1 req Team team_color; 2 req string machine; "
                            "4 opt PrepareInstructionBS instruction_bs; "
                            "5 opt PrepareInstructionDS instruction_ds; "
                            "6 opt PrepareInstructionRS instruction_rs; "
                            "7 opt PrepareInstructionCS instruction_cs; "
                            "8 opt PrepareInstructionSS instruction_ss; 15 opt uint64 sent_at"),
    (BOTH, "PrepareInstructionBS", "1 req MachineSide side; 2 req BaseColor color"),
    (R16, "PrepareInstructionDS", "1 req uint32 gate"),
    (R25, "PrepareInstructionDS", "2 req uint32 order_id"),
    (BOTH, "PrepareInstructionRS", "1 req RingColor ring_color"),
    (R16, "PrepareInstructionCS", "1 req CsOp operation"),
    (R25, "PrepareInstructionCS", "1 req CSOp operation"),
    (R25, "PrepareInstructionSS", "1 req SSOp operation; 2 req uint32 shelf; 3 req uint32 slot; "
                                  "10 opt string wp_description"),
    (R25, "ResetMachine", "1 req Team team_color; 2 req string machine"),
    (BOTH, "RingInfo", "1 rep Ring rings"),
    (BOTH, "Ring", "1 req RingColor ring_color; 2 req uint32 raw_material"),
    (BOTH, "RobotInfo", "1 rep Robot robots"),
    (BOTH, "Robot", "1 req string name; 2 req string team; 12 req Team team_color; "
                    "7 req uint32 number; 3 req string host; 4 req Time last_seen; "
                    "6 opt Pose2D pose; 11 opt Pose2D vision_pose; 8 opt RobotState state; "
                    "9 opt float maintenance_time_remaining; 10 opt uint32 maintenance_cycles"),
    (R16, "VersionInfo", "1 req uint32 version_major; 2 req uint32 version_minor; "
                         "3 req uint32 version_micro; 4 req string version_string"),
    (R25, "VersionInfo", "1 req uint32 version_major; 2 req uint32 version_minor; "
                         "3 req uint32 version_micro; 4 req string version_string; "
                         "10 rep ConfigValue configuration"),
    (R25, "ConfigValue", "1 req string name; 2 req ValueType type; 5 opt string string_value; "
                         "6 opt bool boolean_value; 7 opt uint32 integer_value; "
                         "8 opt float float_value"),
]


def _messages(set_name):
    """{name: DescriptorProto} of the top-level messages of a set, from its descriptors."""
    fds = msgs.message_set(set_name).file_descriptor_set()
    return {m.name: m for f in fds.file for m in f.message_type}


def _enums(set_name):
    fds = msgs.message_set(set_name).file_descriptor_set()
    out = {e.name: e for f in fds.file for e in f.enum_type}
    for f in fds.file:
        for m in f.message_type:
            for e in m.enum_type:
                out[f"{m.name}.{e.name}"] = e
    return out


CASES = [(s, name, spec) for sets, name, spec in FIELDS for s in sets]


@pytest.mark.parametrize("set_name,name,spec", CASES, ids=[f"{s}.{n}" for s, n, _ in CASES])
def test_fields_match_fact_sheet(set_name, name, spec):
    desc = _messages(set_name)[name]
    want = {}
    for item in filter(None, (i.strip() for i in spec.split(";"))):
        number, label, typ, fname = item.split()
        want[fname] = (int(number), LABELS[label], typ)
    have = {}
    for f in desc.field:
        typ = f.type_name.rsplit(".", 1)[-1] if f.type_name else \
            next(k for k, v in SCALARS.items() if v == f.type)
        have[f.name] = (f.number, f.label, typ)
    assert have == want


def test_ds_field_1_reserved_in_2025():
    ds = _messages("rcll2025")["PrepareInstructionDS"]
    assert [(r.start, r.end) for r in ds.reserved_range] == [(1, 2)]
    assert list(ds.reserved_name) == ["gate"]


def test_defaults():
    for s in BOTH:
        m = _messages(s)
        loaded = next(f for f in m["Machine"].field if f.name == "loaded_with")
        assert loaded.default_value == "0"
        assert msgs.message_set(s).Machine().loaded_with == 0


ENUMS = [
    (BOTH, "Team", {"CYAN": 0, "MAGENTA": 1}),
    (BOTH, "RingColor", {"RING_BLUE": 1, "RING_GREEN": 2, "RING_ORANGE": 3, "RING_YELLOW": 4}),
    (R16, "BaseColor", {"BASE_RED": 1, "BASE_BLACK": 2, "BASE_SILVER": 3}),
    (R25, "BaseColor", {"BASE_RED": 1, "BASE_BLACK": 2, "BASE_SILVER": 3, "BASE_CLEAR": 4}),
    (BOTH, "CapColor", {"CAP_BLACK": 1, "CAP_GREY": 2}),
    (BOTH, "LightColor", {"RED": 0, "YELLOW": 1, "GREEN": 2}),
    (BOTH, "LightState", {"OFF": 0, "ON": 1, "BLINK": 2}),
    (R16, "CsOp", {"RETRIEVE_CAP": 1, "MOUNT_CAP": 2}),
    (R25, "CSOp", {"RETRIEVE_CAP": 1, "MOUNT_CAP": 2}),
    (R25, "SSOp", {"STORE": 1, "RETRIEVE": 2, "CHANGE_INFO": 3}),
    (BOTH, "MachineSide", {"INPUT": 1, "OUTPUT": 2}),
    (BOTH, "ExplorationState", {"NO_REPORT": 0, "CORRECT_REPORT": 1, "WRONG_REPORT": 2}),
    (BOTH, "GameState.State", {"INIT": 0, "WAIT_START": 1, "RUNNING": 2, "PAUSED": 3}),
    (BOTH, "GameState.Phase", {"PRE_GAME": 0, "SETUP": 10, "EXPLORATION": 20,
                               "PRODUCTION": 30, "POST_GAME": 40}),
    (BOTH, "Order.Complexity", {"C0": 0, "C1": 1, "C2": 2, "C3": 3}),
    (BOTH, "RobotState", {"ACTIVE": 1, "MAINTENANCE": 2, "DISQUALIFIED": 3}),
    (R25, "ConfigValue.ValueType", {"STRING": 0, "BOOLEAN": 1, "FLOAT": 2, "INTEGER": 3}),
    (R16, "Zone", {f"Z{n}": n for n in range(1, 25)}),
    (R25, "Zone", {f"{p}_Z{x}{y}": base + 10 * x + y
                   for p, base in (("C", 0), ("M", 1000)) for x in range(1, 8) for y in range(1, 9)}),
]
ENUM_CASES = [(s, name, values) for sets, name, values in ENUMS for s in sets]


@pytest.mark.parametrize("set_name,name,values", ENUM_CASES,
                         ids=[f"{s}.{n}" for s, n, _ in ENUM_CASES])
def test_enums_match_fact_sheet(set_name, name, values):
    have = {v.name: v.number for v in _enums(set_name)[name].value}
    assert have == values
    wrapper = msgs.message_set(set_name).enum(name)
    assert {k: wrapper.Value(k) for k in wrapper.keys()} == values


def test_2025_zone_includes_insertion_zones():
    zone = msgs.message_set("rcll2025").enum("Zone")
    for n in ("C_Z51", "C_Z61", "C_Z71", "M_Z51", "M_Z61", "M_Z71"):
        assert n in zone.keys()
    assert len(zone.keys()) == 2 * 7 * 8


# -- CompType of every message (fact sheet §3 "Notation ... (COMP_ID/MSG_TYPE)") --
COMMON_IDS = {
    "BeaconSignal": 1, "AttentionMessage": 2, "VersionInfo": 3, "LightSpec": 10, "Machine": 12,
    "MachineInfo": 13, "SetMachineState": 17, "MachineAddBase": 18, "SetMachineLights": 19,
    "GameState": 20, "SetGameState": 21, "SetGamePhase": 22, "RobotInfo": 30, "Robot": 31,
    "OrderInfo": 41, "Order": 42, "SetOrderDelivered": 43, "MachineReportEntry": 60,
    "MachineReport": 61, "MachineReportInfo": 62, "ExplorationSignal": 70,
    "ExplorationZone": 71, "ExplorationInfo": 72, "GameInfo": 81, "SetTeamName": 82,
    "SetRobotMaintenance": 91, "PrepareMachine": 101, "RingInfo": 110, "SimTimeSync": 327,
}
COMP_TYPES = {
    "rcll2016": {**{k: (2000, v) for k, v in COMMON_IDS.items()},
                 "SetOrderDeliveredByColor": (2000, 44)},
    "rcll2025": {**{k: (2000, v) for k, v in COMMON_IDS.items()},
                 "ConfigValue": (2000, 6), "RandomizeField": (2000, 23),
                 "UnconfirmedDelivery": (2000, 45), "ConfirmDelivery": (2000, 46),
                 "Workpiece": (2000, 55), "WorkpieceInfo": (2000, 56),
                 "WorkpieceAddRing": (2000, 57), "MachineTypeFeedback": (2000, 63),
                 "ResetMachine": (2000, 104), "ShelfSlotInfo": (2000, 121),
                 "NavigationRoutes": (2000, 250), "AgentTask": (8000, 502),
                 "WorkpieceDescription": (8000, 510)},
    "team": {"RobotHello": (3000, 1), "Heartbeat": (3000, 2), "RobotStatus": (3000, 3), "LinkAck": (3000, 4),
             "TaskDetail": (3000, 13), "TaskOutcome": (3000, 14),
             "MachineObservation": (3000, 20), "ZoneExplored": (3000, 21),
             "MachineMap": (3000, 30), "GamePhase": (3000, 40)},
}
WITHOUT_COMP_TYPE = {
    "rcll2016": {"Time", "Pose2D", "Ring", "PrepareInstructionBS", "PrepareInstructionDS",
                 "PrepareInstructionRS", "PrepareInstructionCS"},
    "rcll2025": {"Time", "Pose2D", "Ring", "PrepareInstructionBS", "PrepareInstructionDS",
                 "PrepareInstructionRS", "PrepareInstructionCS", "PrepareInstructionSS",
                 "FinishedTask", "Move", "Retrieve", "Deliver", "BufferStation",
                 "ExploreWaypoint", "Route"},
}


@pytest.mark.parametrize("set_name", msgs.SETS)
def test_every_comp_type(set_name):
    ms = msgs.message_set(set_name)
    table = COMP_TYPES[set_name]
    assert {n: ms.comp_type(c) for n, c in ms.classes.items()} == table
    assert {ct: c.DESCRIPTOR.name for ct, c in ms.by_comp_type.items()} == \
        {ct: n for n, ct in table.items()}
    for name, ct in table.items():
        assert ms.comp_type(ms.get(name)()) == ct       # instances too
    if set_name in WITHOUT_COMP_TYPE:
        assert set(ms.all_classes) - set(ms.classes) == WITHOUT_COMP_TYPE[set_name]
        for name in WITHOUT_COMP_TYPE[set_name]:
            assert ms.comp_type(ms.get(name)) is None


def test_file_lists():
    f16 = {"AttentionMessage", "BeaconSignal", "ExplorationInfo", "GameInfo", "GameState",
           "MachineCommands", "MachineInfo", "MachineInstructions", "MachineReport",
           "OrderInfo", "Pose2D", "ProductColor", "RingInfo", "RobotCommands", "RobotInfo",
           "SimTimeSync", "Team", "Time", "VersionInfo", "Zone"}
    f25 = f16 | {"AgentTask", "MachineDescription", "NavigationChallenge", "WorkpieceInfo"}
    assert {f.removesuffix(".proto") for f in msgs.message_set("rcll2016").files} == f16
    assert {f.removesuffix(".proto") for f in msgs.message_set("rcll2025").files} == f25
    for s in BOTH:
        fds = msgs.message_set(s).file_descriptor_set()
        assert {f.package for f in fds.file} == {"llsf_msgs"}
    assert {f.package for f in msgs.message_set("team").file_descriptor_set().file} == {"rllbt"}


def test_agent_task_error_codes_of_msgs_head():
    codes = msgs.message_set("rcll2025").enum("AgentTask.ErrorCode")
    assert codes.Value("NO_ERROR") == 0
    assert codes.Value("NO_WORKPIECE_IN_GRIPPER") == 208
    assert codes.Value("INTERNAL_ERROR") == 220
    assert codes.Value("NO_PATH_FOUND") == 300
