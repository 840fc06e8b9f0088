"""The agent's parts: error codes, the game gate, the observation stream and
the machine map (task parameters: tests/rll_bt/agenttask)."""
from __future__ import annotations

import math

import pytest

from rll_bt import msgs, rules
from rll_bt.agent import (
    AgentConfig,
    GameGate,
    KnownMachines,
    ObservationFeed,
    changed_names,
    check_team_key,
    distribute,
    error_code,
)
from rll_bt.backend import Pose2D
from rll_bt.clock import SimClock
from tests.support.agents import TM

P16 = rules.profile("rcll2016")
P25 = rules.profile("rcll2025")


# -- error codes --------------------------------------------------------------------------------

@pytest.mark.parametrize("code, name", [
    ("GRAB_FAILED", "GRAB_FAILED"), ("grasp_failed", "GRAB_FAILED"), ("NAVIGATION_FAILED", "NAVIGATION_FAILED"),
    ("MACHINE_UNKNOWN", "MACHINE_NOT_FOUND"), ("BAD_GOAL", "NAVIGATION_FAILED"), ("TIMEOUT", "TIMEOUT"),
    ("HARDWARE", "INTERNAL"), ("something odd", "INTERNAL"), (None, "INTERNAL"), ("", "INTERNAL"),
])
def test_error_codes(code, name):
    value, got = error_code(code)
    assert got == name and value == TM.ErrorCode.Value(name)


def test_every_protocol_code_passes_unchanged():
    for name in TM.ErrorCode.keys():
        assert error_code(name)[1] == name


# -- configuration ------------------------------------------------------------------------------

@pytest.mark.parametrize("key", ["", "has space", "tab\there", "ünïcode", "x" * 257])
def test_bad_team_keys(key):
    with pytest.raises(ValueError):
        check_team_key(key)


def test_config_checks():
    assert AgentConfig(robot_id=2, team_name="T", color="magenta").peer_name == "R2"
    assert AgentConfig(robot_id=2, team_name="T", color="magenta").color == "MAGENTA"
    for bad in ({"robot_id": 0, "team_name": "T"}, {"robot_id": 1, "team_name": ""},
                {"robot_id": 1, "team_name": "T", "profile": "rcll1999"}, {"robot_id": 1, "team_name": "T", "hz": 0},
                {"robot_id": 1, "team_name": "T", "color": "green"}):
        with pytest.raises(ValueError):
            AgentConfig(**bad)


# -- the game gate ------------------------------------------------------------------------------

def _game_state(ms, state, phase, cyan="", magenta=""):
    gs = ms.GameState(state=ms.GameState.State.Value(state), phase=ms.GameState.Phase.Value(phase),
                      team_cyan=cyan, team_magenta=magenta)
    gs.game_time.sec, gs.game_time.nsec = 5, 0
    return gs


def test_gate_stands_still_until_running_outside_pre_and_post_game():
    clock = SimClock()
    gate = GameGate("Us", clock)
    ms = msgs.message_set("rcll2016")
    assert not gate.moving_allowed                       # nothing heard yet
    gate.on_game_state(_game_state(ms, "RUNNING", "PRE_GAME"))
    assert not gate.moving_allowed
    gate.on_game_state(_game_state(ms, "RUNNING", "EXPLORATION"))
    assert gate.moving_allowed
    gate.on_game_state(_game_state(ms, "PAUSED", "EXPLORATION"))
    assert not gate.moving_allowed
    gate.on_game_state(_game_state(ms, "RUNNING", "POST_GAME"))
    assert not gate.moving_allowed
    assert not GameGate("Us", clock, require=True).moving_allowed
    assert GameGate("Us", clock, require=False).moving_allowed


def test_gate_learns_the_colour_from_the_team_names():
    gate = GameGate("Us", SimClock())
    ms = msgs.message_set("rcll2025")
    assert gate.on_game_state(_game_state(ms, "RUNNING", "SETUP", cyan="Them", magenta="Us")) == "MAGENTA"


def test_fresh_refbox_state_outranks_the_team_server():
    clock = SimClock()
    gate = GameGate("Us", clock, fresh=3.0)
    ms = msgs.message_set("rcll2016")
    gate.on_game_state(_game_state(ms, "PAUSED", "PRODUCTION"))
    clock.advance(1.0)
    gate.on_game_phase(TM.GamePhase(state=2, phase=30, game_time=1.0))
    assert not gate.moving_allowed and gate.view.source == "refbox"
    clock.advance(3.0)                                   # the refbox went quiet: the server counts now
    assert gate.moving_allowed and gate.view.source == "teamserver"
    gate.on_game_phase(TM.GamePhase(state=2, phase=30, game_time=1.0, team_color=1))
    assert gate.color == "MAGENTA"                       # the server's word while the refbox said nothing
    gate.on_game_state(_game_state(ms, "RUNNING", "PRODUCTION", cyan="Us"))
    gate.on_game_phase(TM.GamePhase(state=2, phase=30, game_time=1.0, team_color=1))
    assert gate.color == "CYAN"                          # the refbox's word wins


# -- observations -------------------------------------------------------------------------------

def _feed():
    return ObservationFeed(P16, SimClock(), robot_id=4)


def test_only_changes_are_streamed():
    feed = _feed()
    assert feed.machine("C-CS1", pose=Pose2D(3.0, 2.3, math.pi), confidence=0.6)
    assert not feed.machine("C-CS1", pose=Pose2D(3.05, 2.3, math.pi), confidence=0.62)   # noise
    assert feed.machine("C-CS1", pose=Pose2D(3.3, 2.3, math.pi), confidence=0.62)        # moved 0.3 m
    assert feed.machine("C-CS1", lights=5, confidence=0.5)                                 # light first read
    assert not feed.machine("C-CS1", lights=5, confidence=0.5)
    assert feed.machine("C-CS1", lights=5, confidence=0.7)                                 # more certain
    assert feed.machine("C-CS1", pose=Pose2D(3.3, 2.3, math.pi / 2), confidence=0.7)      # turned 90 deg
    sent = feed.drain()
    assert len(sent) == 5 and not feed.drain()
    first = sent[0]
    assert first.robot_id == 4 and first.name.value == "C-CS1" and first.zone.value == 6
    assert first.orientation.value == 180 and abs(first.pose.confidence - 0.6) < 1e-6
    assert sent[2].lights.pattern == 5


def test_sightings_by_tag_and_from_a_subscribed_map():
    feed = _feed()
    assert feed.machine(None, tag_id=P16.tag_ids("C-RS1")[1], pose=Pose2D(5.0, 2.6, 0.0))
    assert not feed.machine(None, tag_id=9999)           # nobody's tag: dropped

    class Map:                                           # the skills' machine map, as the agent sees it
        def __init__(self):
            self.sinks = []

        def subscribe(self, fn):
            self.sinks.append(fn)

    m = Map()
    assert feed.attach(m) and not feed.attach(object())
    obs = type("Obs", (), {"machine": "C-BS", "pose": Pose2D(4.5, 1.0, 0.0), "stamp": 2.0, "tag_id": None, "zone": None,
                               "light_state": None, "confidence": 0.9})()
    m.sinks[0](obs)
    names = [x.name.value for x in feed.drain()]
    assert names == ["C-RS1", "C-BS"]


def test_zone_search_results():
    feed = _feed()
    feed.machine("C-CS1", pose=Pose2D(3.0, 2.3, 0.0))
    feed.drain()
    feed.zone_searched(6)
    feed.zone_searched(7)
    out = feed.drain()
    assert [m.DESCRIPTOR.name for m in out] == ["ZoneExplored", "MachineObservation", "ZoneExplored"]
    assert list(out[0].machines) == ["C-CS1"] and out[0].zone == 6
    assert out[1].searched_zone == 7 and out[1].seen_in_zone is False and not out[1].HasField("name")
    assert list(out[2].machines) == [] and feed.searched == {6, 7}


# -- machine map ---------------------------------------------------------------------------------

def _map_msg():
    mm = TM.MachineMap(profile="rcll2016", stamp=3.0)
    k = mm.machines.add(name="C-CS1", type="CS", team_color=0, zone=6, rotation=180, confidence=0.9)
    k.pose.x, k.pose.y, k.pose.theta = 3.0, 2.3, math.pi
    mm.machines.add(name="C-DS", zone=4)                 # zone known, pose not
    return mm


def test_known_machines_from_the_message():
    km = KnownMachines.from_message(_map_msg(), received=7.0)
    assert set(km) == {"C-CS1", "C-DS"} and km.profile == "rcll2016" and km.received == 7.0
    cs1 = km["C-CS1"]
    assert cs1.team_color == "CYAN" and cs1.zone == 6 and cs1.rotation == 180 and cs1.pose.x == 3.0
    assert km["C-DS"].pose is None and km.pose("C-DS") is None and km["C-DS"].type is None


def test_the_map_reaches_every_service_that_takes_it():
    km = KnownMachines.from_message(_map_msg())
    got = {}

    class Whole:
        def apply_machine_map(self, known):
            got["whole"] = known

    class MachineStore:                                  # the skills' machine map
        def set(self, name, pose):
            got.setdefault("store", {})[name] = pose

        def subscribe(self, fn):
            pass

    class Skills:                                        # the skills' context holds one
        def __init__(self):
            self.machines = MachineStore()

    services = {"a": Whole(), "b": Skills(), "c": MachineStore(), "profile": P16, "start_pose": Pose2D()}
    assert distribute(services, km) == 3
    assert services["machine_map"] is km and got["whole"] is km
    assert set(got["store"]) == {"C-CS1"}                # only stations with a pose


def test_only_moved_stations_are_passed_on_again():
    old = KnownMachines.from_message(_map_msg())
    msg = _map_msg()
    k = msg.machines.add(name="C-BS", zone=9)
    k.pose.x, k.pose.y, k.pose.theta = 4.5, 1.0, 0.0
    assert changed_names(old, KnownMachines.from_message(msg)) == {"C-BS"}
    msg.machines[0].pose.x += 0.005                      # C-CS1 within a centimetre: not moved
    assert changed_names(old, KnownMachines.from_message(msg)) == {"C-BS"}
    msg.machines[0].pose.theta += 0.1
    assert changed_names(old, KnownMachines.from_message(msg)) == {"C-BS", "C-CS1"}
    assert changed_names(None, old) == {"C-CS1"}
