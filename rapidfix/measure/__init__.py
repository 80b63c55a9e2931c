"""Measurement processing: read and validate measurement files, register the tracker,
recover the actual joint angles from joint sweeps.

`files` (setup.toml and the CSV tables), `registration` (tracker frame → robot base,
p_tracker = R p_robot + t), `sweeps` (Δθ at every swept commanded angle).
"""

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

__all__ = [
    "JointSweep",
    "PointTable",
    "Registration",
    "Setup",
    "SweepAnalysis",
    "SweepTable",
    "analyse_sweeps",
    "read_points",
    "read_setup",
    "read_sweeps",
    "register",
    "write_points",
    "write_setup",
    "write_sweeps",
]
