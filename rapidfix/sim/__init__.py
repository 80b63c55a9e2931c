"""A virtual robot cell: a robot with chosen true errors, a hidden tracker, a session.

`VirtualRobot` executes commanded joints on the true robot and measures them;
`simulate_set` / `simulate_cell` run a whole calibration session (sweeps,
calibration and validation points, a ballbar run) and write it in the shared
measurement format, with the truth in a separate file.
"""

from rapidfix.sim.cell import SimulatedSet, simulate_cell, simulate_set, write_set
from rapidfix.sim.true_errors import EFFECTS
from rapidfix.sim.virtual_robot import RunConditions, VirtualRobot

__all__ = [
    "EFFECTS",
    "RunConditions",
    "SimulatedSet",
    "VirtualRobot",
    "simulate_cell",
    "simulate_set",
    "write_set",
]
