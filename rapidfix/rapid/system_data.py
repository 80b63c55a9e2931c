"""Predefined data of the controller's BASE module (tool0, wobj0, load0, vN, zN, fine).

Programs use these without declaring them; the model resolves them here when
the file does not declare a name of its own.
"""

from __future__ import annotations

from rapidfix.rapid.values import Value

_IDENTITY = ((0.0, 0.0, 0.0), (1.0, 0.0, 0.0, 0.0))
_LOAD0 = (0.001, (0.0, 0.0, 0.001), (1.0, 0.0, 0.0, 0.0), 0.0, 0.0, 0.0)

_SPEEDS = (5, 10, 20, 30, 40, 50, 60, 80, 100, 150, 200, 300, 400, 500, 600, 800, 1000,
           1500, 2000, 2500, 3000, 4000, 5000, 6000, 7000)

# zN: pzone_tcp, pzone_ori, pzone_eax, zone_ori, zone_leax, zone_reax
_ZONES = {
    0: (0.3, 0.3, 0.3, 0.03, 0.3, 0.03),
    1: (1, 1, 1, 0.1, 1, 0.1),
    5: (5, 8, 8, 0.8, 8, 0.8),
    10: (10, 15, 15, 1.5, 15, 1.5),
    15: (15, 23, 23, 2.3, 23, 2.3),
    20: (20, 30, 30, 3.0, 30, 3.0),
    30: (30, 45, 45, 4.5, 45, 4.5),
    40: (40, 60, 60, 6.0, 60, 6.0),
    50: (50, 75, 75, 7.5, 75, 7.5),
    60: (60, 90, 90, 9.0, 90, 9.0),
    80: (80, 120, 120, 12, 120, 12),
    100: (100, 150, 150, 15, 150, 15),
    150: (150, 225, 225, 23, 225, 23),
    200: (200, 300, 300, 30, 300, 30),
}


def _build() -> dict[str, tuple[Value, str]]:
    data: dict[str, tuple[Value, str]] = {
        "tool0": ((True, _IDENTITY, _LOAD0), "tooldata"),
        "wobj0": ((False, True, "", _IDENTITY, _IDENTITY), "wobjdata"),
        "load0": (_LOAD0, "loaddata"),
        "fine": ((True, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0), "zonedata"),
    }
    for v in _SPEEDS:
        data[f"v{v}"] = ((float(v), 500.0, 5000.0, 1000.0), "speeddata")
    for z, values in _ZONES.items():
        data[f"z{z}"] = ((False, *(float(x) for x in values)), "zonedata")
    return data


SYSTEM_DATA: dict[str, tuple[Value, str]] = _build()
