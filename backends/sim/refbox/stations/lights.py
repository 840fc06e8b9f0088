"""Station states and the signal-tower lights each shows (2016: production.clp; 2019+:
machine-lights.clp).

States and signal-tower lights (refbox code; where the 2016 rulebook's
wording differs, e.g. "yellow busy", the code wins):

================  =============================  =================================
state             lights 2016 (2017+ if other)   leaves when
================  =============================  =================================
IDLE              green                          a valid PrepareMachine arrives
PREPARED          green blinking for 3 s, green  its workpiece is on the input
                  (green blinking)               (2025: and carried to the middle)
PROCESSING        green + yellow                 the operation is done
PROCESSED         (as PROCESSING)                the product reached the output
READY-AT-OUTPUT   yellow (yellow + green blink)  a robot takes the product
WAIT-IDLE         yellow blinking (yellow and    5 s later -> IDLE
                  green blinking)
BROKEN            red + yellow blinking          30 s later -> IDLE (slots cleared)
DOWN              red                            the down period ends
================  =============================  =================================

Which table a station shows is the rule set's choice (``host.station_lights``):
2017+ stations show their state only once correctly reported.
"""
from __future__ import annotations

from ..world import BLINK, ON, lights

IDLE, PREPARED, PROCESSING, PROCESSED = "IDLE", "PREPARED", "PROCESSING", "PROCESSED"
READY_AT_OUTPUT, WAIT_IDLE, BROKEN, DOWN = "READY-AT-OUTPUT", "WAIT-IDLE", "BROKEN", "DOWN"
STATES = (IDLE, PREPARED, PROCESSING, PROCESSED, READY_AT_OUTPUT, WAIT_IDLE, BROKEN, DOWN)

STATE_LIGHTS = {
    IDLE: lights(green=ON),
    PREPARED: lights(green=ON),
    PROCESSING: lights(yellow=ON, green=ON),
    PROCESSED: lights(yellow=ON, green=ON),
    READY_AT_OUTPUT: lights(yellow=ON),
    WAIT_IDLE: lights(yellow=BLINK),
    BROKEN: lights(red=BLINK, yellow=BLINK),
    DOWN: lights(red=ON),
}
PREPARED_BLINK = lights(green=BLINK)
#: machine-lights.clp (2019+); PROCESSED sends no change, so PROCESSING's stay
STATE_LIGHTS_2025 = {
    IDLE: lights(green=ON),
    PREPARED: lights(green=BLINK),
    PROCESSING: lights(yellow=ON, green=ON),
    PROCESSED: lights(yellow=ON, green=ON),
    READY_AT_OUTPUT: lights(yellow=ON, green=BLINK),
    WAIT_IDLE: lights(yellow=BLINK, green=BLINK),
    BROKEN: lights(red=BLINK, yellow=BLINK),
    DOWN: lights(red=ON),
}


def light_text(lights: dict) -> str:
    on = [f"{c}-{s}" for c, s in lights.items() if s != "OFF"]
    return " ".join(on) or "off"
