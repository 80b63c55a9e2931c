"""Measurement processing: read and validate measurement files, register the tracker,
recover the actual joint angles from joint sweeps.

`files` (setup.toml and the CSV tables), `registration` (tracker frame → robot base,
p_tracker = R p_robot + t), `sweeps` (Δθ at every swept commanded angle).
"""

from typing import TYPE_CHECKING

from rapidfix import lazy_exports
from rapidfix.measure.files import (
    PointTable,
    Setup,
    SweepTable,
    read_points,
    read_setup,
    read_sweeps,
    write_points,
    write_setup,
    write_sweeps,
)
from rapidfix.measure.registration import Registration, register
from rapidfix.measure.sweeps import JointSweep, SweepAnalysis, analyse_sweeps

if TYPE_CHECKING:  # what type checkers and IDEs see of the lazy exports
    from rapidfix.measure.files import (
        ball_offsets,
        read_measurement_text,
        robot_reach_mm,
        round_joints_deg,
        toml_value,
    )
    from rapidfix.measure.registration import rigid_fit

# The other exports, name -> module of this package: each is imported from its module on
# first use (PEP 562), so exporting a name costs nothing until it is used.
# To add one: ARCHITECTURE.md, "Exports".
LAZY_EXPORTS = {
    "ball_offsets": "files",
    "read_measurement_text": "files",
    "rigid_fit": "registration",
    "robot_reach_mm": "files",
    "round_joints_deg": "files",
    "toml_value": "files",
}

__all__ = [
    "JointSweep",
    "PointTable",
    "Registration",
    "Setup",
    "SweepAnalysis",
    "SweepTable",
    "analyse_sweeps",
    "ball_offsets",
    "read_measurement_text",
    "read_points",
    "read_setup",
    "read_sweeps",
    "register",
    "rigid_fit",
    "robot_reach_mm",
    "round_joints_deg",
    "toml_value",
    "write_points",
    "write_setup",
    "write_sweeps",
]

__getattr__, __dir__ = lazy_exports(__name__, LAZY_EXPORTS)
