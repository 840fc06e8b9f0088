"""Seconds, metres and counts that steer the dispatcher."""
from __future__ import annotations

from dataclasses import dataclass


@dataclass
class DispatchConfig:
    """Seconds, metres and counts that steer the dispatcher (see :mod:`teamserver.dispatch`)."""

    heartbeat_timeout: float = 10.0
    prepare_distance: float = 1.5
    prepare_lead: float = 3.0
    retrieve_lead: float = 12.0     # ... a storage station's RETRIEVE this many seconds away
    prepare_retry: float = 6.0
    # the rules' limit on a PREPARED machine waiting for its workpiece (2025: 20 s; None:
    # none, 2016): a feed's station is then prepared only once its robot waits there,
    # docked (the robot's ``waiting_at``)
    stuck_timeout: float | None = None
    speed: float = 0.5
    max_attempts: int = 3
    deliver_early: float = 60.0     # at most this long before the window a delivery starts
    deliver_margin: float = 5.0     # ... and this long more than the drive to the DS takes
    window_margin: float = 1.0      # the DS is prepared this long after the window opened
    feed_confirm: float = 10.0      # a fed station reports the workpiece within this time
    pickup_time: float = 30.0       # a pickup's drive and grab, for "ready once held"
    urgency: float = 0.01           # metres of drive a second of an order's slack is worth
    unblock: float = 20.0           # metres of drive that freeing a stuck robot is worth
    cap_first: float = 10.0         # metres of drive a step of a product whose cap waits in a CS is worth
    cap_due: float = 5.0            # ... a product's due cap retrieval (its rings under way) is worth
    hold_cost: float = 5.0          # ... a pickup that leaves its robot holding (its next step not ready) costs
    fetch_early: bool = False       # fetch a new base even if its next step waits for work nobody can start
    divert_after: float = 10.0      # every robot stuck this long: a base for a full slide goes elsewhere
    idle_prefill: float = 15.0      # a robot without work this long: a cap is retrieved ahead
    park: bool = True
    park_retry: float = 15.0
    discard_backoff: float = 5.0
    # a robot this near (m) the station of a task that leaves its gripper empty gets its next
    # task before the current one ends, to start once it succeeded (None: never; :mod:`.fleet`)
    queue_near: float | None = 1.2
