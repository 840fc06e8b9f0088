"""Error codes between rll-bt's words and the league's, and the link's messages."""
from __future__ import annotations

from rll_bt import msgs
from rll_bt.agenttask import codes, link
from rll_bt.agenttask.codes import from_league, holding_after, league_value, to_league

LEAGUE = msgs.message_set("rcll2025").enum("AgentTask.ErrorCode")
RLLBT = msgs.message_set("team").enum("ErrorCode")


def test_every_rllbt_code_has_a_league_code_and_every_league_code_an_rllbt_one():
    assert set(codes.TO_LEAGUE) == set(RLLBT.keys())
    assert set(codes.TO_LEAGUE.values()) <= set(LEAGUE.keys())
    assert set(codes.FROM_LEAGUE) == set(LEAGUE.keys())
    assert set(codes.FROM_LEAGUE.values()) <= set(RLLBT.keys())


def test_a_failure_reads_the_same_to_a_league_team_server_and_back():
    # the codes a team server acts on differently come back as what they were
    for ours in ("NAVIGATION_FAILED", "MACHINE_NOT_FOUND", "ALIGN_FAILED", "GRAB_FAILED", "PUT_FAILED",
                 "INVALID_TASK", "INTERNAL"):
        assert from_league(league_value(to_league(ours))) == ours
    assert league_value(to_league("NAVIGATION_FAILED", "no path to the goal")) == 300
    assert to_league("PUT_FAILED", holding=False) == "NO_WORKPIECE_IN_GRIPPER"
    assert to_league("PUT_FAILED", holding=True) == "MACHINE_POINT_OCCUPIED"
    assert to_league("SOMETHING_ELSE") == "INTERNAL_ERROR"


def test_a_league_robots_failure_without_a_code_is_simply_tried_again():
    assert from_league(None) == "NONE"
    assert from_league(0) == from_league(1) == "NONE"
    assert from_league(999) == "INTERNAL"
    assert holding_after(208) is False and holding_after(207) is True and holding_after(201) is None


def test_the_link_carries_the_leagues_messages_and_rllbts_additions():
    reg = link.registry()
    assert reg.lookup(8000, 502).DESCRIPTOR.full_name == "llsf_msgs.AgentTask"
    assert reg.lookup(8000, 510).DESCRIPTOR.full_name == "llsf_msgs.WorkpieceDescription"
    beacon = reg.lookup(2000, 1)
    assert beacon.DESCRIPTOR.full_name == "llsf_msgs.BeaconSignal"
    assert {"task", "finished_tasks"} <= set(beacon.DESCRIPTOR.fields_by_name)
    for name in link.EXTRAS:
        cls = reg.by_name(name)
        assert cls is not None and cls.DESCRIPTOR.full_name == f"rllbt.{name}"
    league_only = link.league_registry()
    assert len(league_only) == 3 and league_only.lookup(3000, 13) is None
