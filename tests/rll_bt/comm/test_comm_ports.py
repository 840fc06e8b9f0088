"""The refbox's port layouts: a robot's view and a layout moved by an offset."""
from rll_bt.comm import SIM, PeerPorts


def test_the_sim_layout_moved_by_an_offset_moves_every_port_and_keeps_the_roles():
    moved = SIM.moved(700)
    assert moved.name == "sim+700" and moved.stream == 4444 + 700
    assert (moved.public, moved.cyan, moved.magenta) == (PeerPorts(5144, 5145), PeerPorts(5141, 5146),
                                                         PeerPorts(5142, 5147))
    assert moved.robot("cyan") == PeerPorts(send=5146, recv=5141)      # a team server listens where it sends
    assert SIM.moved(0) is SIM
