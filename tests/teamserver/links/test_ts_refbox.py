"""The refbox client per profile: colour and crypto, exploration info, reports,
PrepareMachine, orders; and the CLI."""
import pytest

from rll_bt import msgs, rules
from rll_bt.cli import main
from rll_bt.clock import SimClock
from rll_bt.comm import MessageRegistry
from teamserver.knowledge import model as M
from teamserver.knowledge.kb import KnowledgeBase
from teamserver.links.refbox import RefboxClient
from tests.support.teamserver import TEAM, Lockstep


def client(profile="rcll2016", color="CYAN"):
    kb = KnowledgeBase(rules.profile(profile))
    if color:
        kb.set("team_color", color)
    return RefboxClient(kb, TEAM, clock=SimClock())


def test_our_name_in_game_state_switches_the_team_channel_to_encryption():
    ls = Lockstep()
    ls.refbox.game_state("EXPLORATION", "RUNNING", 0, team="Others")
    ls.step()
    assert ls.server.color is None
    ls.refbox.game_state("EXPLORATION", "RUNNING", 1, team=TEAM)
    ls.step()
    assert ls.server.color == "CYAN"
    assert ls.server.refbox_link.team.encrypted
    # an eavesdropper without the key on the cyan channel reads nothing we send
    reg = MessageRegistry.from_message_set(msgs.message_set("rcll2016"))
    spy = ls.bus.peer("cyan", registry=reg, name="spy")
    ls.agents[0].observe("C-BS", lights=1, lconf=0.99)
    ls.step(dt=1.0, n=2)
    assert spy.receive() == []
    reports = [m for m in ls.refbox.received if m.DESCRIPTOR.name == "MachineReport"]
    assert reports and reports[-1].team_color == 0


def test_exploration_info_maps_type_strings_to_light_codes_and_zones():
    c = client()
    ms = c.ms
    info = ms.ExplorationInfo()
    sig = info.signals.add(type="AbCdEfGh")
    sig.lights.add(color=ms.enum("LightColor").Value("RED"), state=1)
    sig.lights.add(color=ms.enum("LightColor").Value("GREEN"), state=1)
    sig.lights.add(color=ms.enum("LightColor").Value("YELLOW"), state=0)
    for z, team in ((3, 0), (19, 0), (15, 1)):
        info.zones.add(zone=z, team_color=team)
    c.handle(info)
    assert c.type_string(("GREEN", "RED")) == "AbCdEfGh"
    assert c.type_string(("RED",)) is None
    assert c.kb.get("exploration_zones") == [3, 19]


@pytest.mark.parametrize("profile", ["rcll2016", "rcll2025"])
def test_report_and_prepare_in_the_shape_of_the_profile(profile):
    c = client(profile)
    zone = 3 if profile == "rcll2016" else 33
    rep = c.machine_report([{"name": "C-RS1", "zone": zone, "type": "TTT", "rotation": 90}])
    e = rep.machines[0]
    assert rep.team_color == 0 and e.name == "C-RS1" and e.zone == zone
    if profile == "rcll2025":
        assert e.rotation == 90
    else:
        assert "rotation" not in e.DESCRIPTOR.fields_by_name and e.type == "TTT"
    pm = c.prepare_machine({"machine": "C-DS", "ds": {"gate": 2, "order_id": 7}})
    if profile == "rcll2016":
        assert pm.instruction_ds.gate == 2
    else:
        assert pm.instruction_ds.order_id == 7 and pm.sent_at > 0
    pm = c.prepare_machine({"machine": "C-CS1", "cs": {"operation": "MOUNT_CAP"}})
    assert pm.instruction_cs.operation == 2
    pm = c.prepare_machine({"machine": "C-BS", "bs": {"side": "OUTPUT", "color": "BASE_SILVER"}})
    assert (pm.instruction_bs.side, pm.instruction_bs.color) == (2, 3)
    pm.SerializeToString()                                   # every required field is set


def test_orders_rings_and_machine_info():
    c = client("rcll2025")
    ms = c.ms
    oi = ms.OrderInfo()
    oi.orders.add(id=3, complexity=2, base_color=2, ring_colors=[1, 4], cap_color=2,
                  quantity_requested=1, quantity_delivered_cyan=0, quantity_delivered_magenta=1,
                  delivery_period_begin=200, delivery_period_end=500, delivery_gate=1,
                  competitive=True)
    ev = c.handle(oi)
    assert ev[0].kind == "orders"
    o = c.kb.orders[3]
    assert (o.base, o.rings, o.cap, o.competitive) == ("BASE_BLACK", ("RING_BLUE",
                                                                      "RING_YELLOW"),
                                                        "CAP_GREY", True)
    assert c.handle(oi) == []                                # nothing new
    ri = ms.RingInfo()
    ri.rings.add(ring_color=3, raw_material=2)
    c.handle(ri)
    assert c.kb.get("ring_costs") == {"RING_ORANGE": 2}
    mi = ms.MachineInfo(team_color=0)
    mi.machines.add(name="C-RS1", state="IDLE", ring_colors=[3, 2], zone=45, rotation=90)
    mi.machines.add(name="M-RS1", state="DOWN")
    c.handle(mi)
    st = c.kb.stations["C-RS1"]
    assert st.ring_colors == ("RING_ORANGE", "RING_GREEN") and "M-RS1" not in c.kb.stations
    assert c.kb.estimate("C-RS1", M.ZONE).value == 45          # ground truth, fused
    mi.machines[0].state = "BROKEN"
    ev = c.handle(mi)
    assert ev[0].data == ("C-RS1", "IDLE", "BROKEN")


def test_cli_status_shows_the_state_database(tmp_path, capsys):
    state = str(tmp_path / "ts.sqlite")
    ls = Lockstep(state=state)
    ls.agents[0].hello()
    ls.refbox.game_state("EXPLORATION", "RUNNING", 0)
    ls.agents[0].observe("C-RS1", zone=2, zconf=0.95, lights=4, lconf=0.9)
    ls.step(n=3)
    assert main(["teamserver", "status", "--state", state]) == 0
    out = capsys.readouterr().out
    assert "explore_zone" in out and "robot1" in out and "C-RS1" in out and "Z2" in out
    ls.close()
    assert main(["teamserver", "status", "--state", str(tmp_path / "none.sqlite")]) == 2
    assert main(["teamserver", "--team", "X"]) == 2
    assert main(["teamserver", "--team", "X", "--key", "k", "--listen", "nowhere"]) == 2
