"""The 2016 rules (refbox tag 2016-1, rulebook 2016).  refbox-protocol.md §4-§6."""
from .profile import OrderShape, Phases, Profile, Scoring
from .zones import CYAN, MAGENTA, Rect, ZoneLayout2016

PROFILE = Profile(
    name="rcll2016",
    year=2016,
    zones=ZoneLayout2016(),
    machine_types=("BS", "DS", "RS1", "RS2", "CS1", "CS2"),
    fixed_zones={"C-BS": 9, "C-DS": 4, "M-BS": 21, "M-DS": 16},
    # ALVAR ids of the 2016 rulebook: (input, output); input is odd
    tags={
        "C-CS1": (1, 2), "C-CS2": (17, 18), "C-RS1": (33, 34), "C-RS2": (177, 178),
        "C-BS": (65, 66), "C-DS": (81, 82),
        "M-CS1": (97, 98), "M-CS2": (113, 114), "M-RS1": (129, 130), "M-RS2": (145, 146),
        "M-BS": (161, 162), "M-DS": (49, 50),
    },
    tag_family="alvar",
    tag_size=0.135,
    phases=Phases(setup=300.0, exploration=240.0, production=900.0, overtime=300.0),
    scoring=Scoring(
        explore_type_ok=5, explore_type_wrong=-4, explore_zone_ok=3, explore_zone_wrong=-2,
        additional_base=2, ring_by_cost=(5, 10, 20), precap_by_complexity=(0, 10, 30, 80),
        cap_mounted=10, cap_retrieved=0, delivery_by_complexity=(20, 20, 20, 20),
        delivery_late_grace=10.0, delivery_too_late=5, delivery_wrong=1,
    ),
    # facts.clp: #1 C0 standing; #2-4 C0 (#3 quantity 2); #5 C1; #6 C2; #7 C3; #8 C0 overtime
    orders=(
        OrderShape((0,), standing=True),
        OrderShape((0,)), OrderShape((0,), quantity=2), OrderShape((0,)),
        OrderShape((1,)), OrderShape((2,)), OrderShape((3,)),
        OrderShape((0,), overtime=True),
    ),
    # machine-light-code: all steady; green 1, yellow 2, red 4 as in the paper's formula (1)
    light_codes={
        1: ("GREEN",), 2: ("YELLOW",), 3: ("GREEN", "YELLOW"), 4: ("RED",),
        5: ("RED", "GREEN"), 6: ("RED", "YELLOW"), 7: ("RED", "YELLOW", "GREEN"),
    },
    exploration_reports="type+zone",
    insertion={CYAN: Rect(3.0, -1.0, 6.0, 0.0), MAGENTA: Rect(-6.0, -1.0, -3.0, 0.0)},
    down_period=(30.0, 120.0),
    unprepared_input_breaks=True,       # production.clp prod-machine-input-not-prepared
    down_start=1.0,
    # rulebook 2016, scoring table: the obstruction penalty a referee applies
    referee_penalties={"obstruction": -20},
)
