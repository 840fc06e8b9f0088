"""Zone layouts of the two rule sets, as pure functions of a pose or a number.

Zone numbers are the refbox's ``llsf_msgs.Zone`` enum values of the profile:
2016 ``Z1..Z24`` = 1..24; 2017+ ``C_Zxy`` = 10x+y and ``M_Zxy`` = 1000+10x+y.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

CYAN, MAGENTA = "CYAN", "MAGENTA"


@dataclass(frozen=True)
class Rect:
    x_min: float
    y_min: float
    x_max: float
    y_max: float

    @property
    def centre(self) -> tuple[float, float]:
        return ((self.x_min + self.x_max) / 2.0, (self.y_min + self.y_max) / 2.0)

    def contains(self, x: float, y: float) -> bool:
        return self.x_min <= x <= self.x_max and self.y_min <= y <= self.y_max


class ZoneLayout2016:
    """12 x 6 m, x in [-6, 6], y in [0, 6]; 24 zones of 2 x 1.5 m.

    Cyan Zn (n = 1..12): column c = (n-1)//4 covers x in [2c, 2c+2], row
    r = (n-1)%4 covers y in [1.5r, 1.5r+1.5].  Magenta Z(n+12) mirrors Zn
    across the y axis.
    """

    field = Rect(-6.0, 0.0, 6.0, 6.0)
    zone_w, zone_h = 2.0, 1.5
    all_zones = tuple(range(1, 25))

    def team(self, zone: int) -> str:
        self._check(zone)
        return CYAN if zone <= 12 else MAGENTA

    def name(self, zone: int) -> str:
        self._check(zone)
        return f"Z{zone}"

    def number(self, name: str) -> int:
        if not name.startswith("Z") or not name[1:].isdigit():
            raise ValueError(f"not a 2016 zone name: {name!r} (expected Z1..Z24)")
        zone = int(name[1:])
        self._check(zone)
        return zone

    def bounds(self, zone: int) -> Rect:
        self._check(zone)
        n = zone if zone <= 12 else zone - 12
        c, r = (n - 1) // 4, (n - 1) % 4
        x0, x1 = 2.0 * c, 2.0 * c + 2.0
        y0, y1 = 1.5 * r, 1.5 * r + 1.5
        if zone > 12:
            x0, x1 = -x1, -x0
        return Rect(x0, y0, x1, y1)

    def centre(self, zone: int) -> tuple[float, float]:
        return self.bounds(zone).centre

    def zone_at(self, x: float, y: float) -> int | None:
        if not self.field.contains(x, y):
            return None
        c = min(int(abs(x) // 2.0), 2)
        r = min(int(y // 1.5), 3)
        n = 4 * c + r + 1
        return n if x >= 0 else n + 12

    def mirror(self, zone: int) -> int:
        self._check(zone)
        return zone + 12 if zone <= 12 else zone - 12

    def _check(self, zone: int) -> None:
        if zone not in self.all_zones:
            raise ValueError(f"zone {zone} is not a 2016 zone (1..24)")


class ZoneLayout2025:
    """14 x 8 m, x in [-7, 7], y in [0, 8]; 1 x 1 m zones C_Zxy / M_Zxy.

    For x >= 0 the zone is C_Z(floor(x)+1)(floor(y)+1), for x < 0
    M_Z(floor(-x)+1)(floor(y)+1).  C_Zxy is 10x+y, M_Zxy 1000+10x+y.
    """

    field = Rect(-7.0, 0.0, 7.0, 8.0)
    zone_w, zone_h = 1.0, 1.0
    all_zones = tuple([10 * x + y for x in range(1, 8) for y in range(1, 9)]
                      + [1000 + 10 * x + y for x in range(1, 8) for y in range(1, 9)])

    def team(self, zone: int) -> str:
        self._check(zone)
        return MAGENTA if zone >= 1000 else CYAN

    def digits(self, zone: int) -> tuple[int, int]:
        self._check(zone)
        z = zone % 1000
        return z // 10, z % 10

    def name(self, zone: int) -> str:
        x, y = self.digits(zone)
        return f"{'M' if zone >= 1000 else 'C'}_Z{x}{y}"

    def number(self, name: str) -> int:
        n = name.replace("-", "_")
        if len(n) != 5 or n[1:3] != "_Z" or n[0] not in "CM" or not n[3:].isdigit():
            raise ValueError(f"not a zone name: {name!r} (expected C_Zxy or M_Zxy)")
        zone = (1000 if n[0] == "M" else 0) + int(n[3:])
        self._check(zone)
        return zone

    def bounds(self, zone: int) -> Rect:
        x, y = self.digits(zone)
        x0, x1 = float(x - 1), float(x)
        if zone >= 1000:
            x0, x1 = -x1, -x0
        return Rect(x0, float(y - 1), x1, float(y))

    def centre(self, zone: int) -> tuple[float, float]:
        return self.bounds(zone).centre

    def zone_at(self, x: float, y: float) -> int | None:
        if not self.field.contains(x, y):
            return None
        zx = min(int(math.floor(abs(x))) + 1, 7)
        zy = min(int(math.floor(y)) + 1, 8)
        return (1000 if x < 0 else 0) + 10 * zx + zy

    def mirror(self, zone: int) -> int:
        self._check(zone)
        return zone - 1000 if zone >= 1000 else zone + 1000

    def _check(self, zone: int) -> None:
        if zone not in self.all_zones:
            raise ValueError(f"zone {zone} is not a 2025 zone (C_Z11..C_Z78, M_Z11..M_Z78)")
