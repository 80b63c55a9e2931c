"""A virtual robot cell: a robot with chosen true errors, a hidden tracker, a session.

`VirtualRobot` executes commanded joints on the true robot and measures them;
`simulate_set` / `simulate_cell` run a whole calibration session (sweeps,
calibration and validation points, a ballbar run) and write it in the shared
measurement format, with the truth in a separate file.
"""

from typing import TYPE_CHECKING

from rapidfix import lazy_exports
from rapidfix.sim.cell import SimulatedSet, simulate_cell, simulate_set, write_set
from rapidfix.sim.true_errors import EFFECTS
from rapidfix.sim.virtual_robot import RunConditions, VirtualRobot

if TYPE_CHECKING:  # what type checkers and IDEs see of the lazy exports
    from rapidfix.sim.cell import joint1_gauge
    from rapidfix.sim.plans import longest_run, plausible_poses, point_plan
    from rapidfix.sim.virtual_robot import DEFAULT_ROBOT, DEFAULT_SMR_OFFSET_MM

# The other exports, name -> module of this package: each is imported from its module on
# first use (PEP 562), so exporting a name costs nothing until it is used.
# To add one: ARCHITECTURE.md, "Exports".
LAZY_EXPORTS = {
    "DEFAULT_ROBOT": "virtual_robot",
    "DEFAULT_SMR_OFFSET_MM": "virtual_robot",
    "joint1_gauge": "cell",
    "longest_run": "plans",
    "plausible_poses": "plans",
    "point_plan": "plans",
}

__all__ = [
    "DEFAULT_ROBOT",
    "DEFAULT_SMR_OFFSET_MM",
    "EFFECTS",
    "RunConditions",
    "SimulatedSet",
    "VirtualRobot",
    "joint1_gauge",
    "longest_run",
    "plausible_poses",
    "point_plan",
    "simulate_cell",
    "simulate_set",
    "write_set",
]

__getattr__, __dir__ = lazy_exports(__name__, LAZY_EXPORTS)
