"""Today's rules (refbox HEAD 2025, rulebook 2025).  refbox-protocol.md §4-§6."""
from .profile import OrderShape, Phases, Profile, Scoring
from .zones import CYAN, MAGENTA, Rect, ZoneLayout2025

_INSERTION_C = frozenset({51, 61, 71})
# insertion zones, and the entrance (5,2) that must stay free, on both sides
_EXCLUDED = frozenset(_INSERTION_C | {52} | {z + 1000 for z in _INSERTION_C | {52}})

PROFILE = Profile(
    name="rcll2025",
    year=2025,
    zones=ZoneLayout2025(),
    machine_types=("BS", "DS", "SS", "RS1", "RS2", "CS1", "CS2"),
    fixed_zones={},
    # utils.clp tag-ids-from-machine-name: (input, output); input is even
    tags={
        "C-CS1": (102, 101), "C-CS2": (104, 103), "C-RS1": (112, 111), "C-RS2": (114, 113),
        "C-BS": (122, 121), "C-DS": (132, 131), "C-SS": (142, 141),
        "M-CS1": (202, 201), "M-CS2": (204, 203), "M-RS1": (212, 211), "M-RS2": (214, 213),
        "M-BS": (222, 221), "M-DS": (232, 231), "M-SS": (242, 241),
    },
    tag_family="aruco",
    tag_size=0.13,
    phases=Phases(setup=300.0, exploration=0.0, production=1200.0, overtime=300.0,
                  exploration_in_production=180.0),
    scoring=Scoring(
        explore_zone_ok=1, explore_zone_wrong=-1, explore_rotation_ok=1, explore_rotation_wrong=-1,
        type_feedback_wrong=-1,
        additional_base=2, ring_by_cost=(5, 10, 20), precap_by_complexity=(0, 0, 0, 0),
        cap_mounted=10, cap_retrieved=2, delivery_by_complexity=(20, 30, 50, 100),
        delivery_late_grace=10.0, delivery_too_late=5, delivery_wrong=0,
        competitive_first=10, competitive_second=-10,
        delivery_late_steps=4, delivery_late_share=0.75,
        ss_store=-5, ss_retrieve=-5, ss_relocate=0, break_revokes=True,
    ),
    # #1-2 standing (C0/C1 and C2/C3); #3-10 random; #11 C0 overtime, competitive;
    # one more random order is competitive (chosen per game)
    orders=(
        OrderShape((0, 1), standing=True), OrderShape((2, 3), standing=True),
        *[OrderShape((0, 1, 2, 3)) for _ in range(8)],
        OrderShape((0,), overtime=True, competitive=True),
    ),
    rs_colors={"RS1": ("RING_ORANGE", "RING_GREEN"), "RS2": ("RING_BLUE", "RING_YELLOW")},
    exploration_reports="zone+rotation",
    insertion={CYAN: Rect(4.0, 0.0, 7.0, 1.0), MAGENTA: Rect(-7.0, 0.0, -4.0, 1.0)},
    excluded_machine_zones=_EXCLUDED,
    down_period=(30.0, 60.0),
    prepare_requires_report=True,
    stuck_timeout=20.0,                 # PROCESSING-WAIT-TILL-RESET, auto-break-machines on
    rs_paid_at_prepare=True,
    wait_idle_after_delivery=True,
    down_start=180.0,                   # down periods start after the exploration time
    # facts.clp storage-slots (default-storage): one C0 of every base x cap pair, in the back
    prestored=((0, 1, "BASE_RED", "CAP_GREY"), (1, 1, "BASE_RED", "CAP_BLACK"),
               (2, 1, "BASE_SILVER", "CAP_GREY"), (3, 1, "BASE_SILVER", "CAP_BLACK"),
               (4, 1, "BASE_BLACK", "CAP_GREY"), (5, 1, "BASE_BLACK", "CAP_BLACK")),
    # rulebook 2025, scoring table: manual penalties a referee applies
    referee_penalties={"dropped-workpiece": -10, "obstruction": -20,
                       "prepare-without-workpiece": -1},
)
