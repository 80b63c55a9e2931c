"""The measurement campaign: what the robot runs, and what the tracker saw.

- `plan` (with `poses`, `envelope`, `timing`, `program`, `pose_table`): the RAPID
  measurement program and its pose table (`rapidfix plan`);
- `tracker_export` and `matching`: a laser tracker's export merged with the pose
  table into the measurement files (`rapidfix import`);
- `iso9283`: pose and distance accuracy and repeatability in the terms of
  ISO 9283:1998 (`rapidfix iso9283`).
"""

from typing import TYPE_CHECKING

from rapidfix import lazy_exports

if TYPE_CHECKING:  # what type checkers and IDEs see of the lazy exports
    from rapidfix.campaign.envelope import Box, Envelope
    from rapidfix.campaign.importing import import_export
    from rapidfix.campaign.iso9283 import cube_runs, evaluate, registered, to_robot
    from rapidfix.campaign.matching import MODES
    from rapidfix.campaign.plan import APPROACH_MODES, PlanSettings, make_plan, write_plan
    from rapidfix.campaign.pose_table import read_plan_meta, read_pose_table
    from rapidfix.campaign.poses import ball_positions
    from rapidfix.campaign.program import TRIGGERS, ProgramOptions
    from rapidfix.campaign.sight import TrackerView
    from rapidfix.campaign.timing import MotionSettings, move_durations
    from rapidfix.campaign.tracker_export import write_export

# The other exports, name -> module of this package: each is imported from its module on
# first use (PEP 562), so exporting a name costs nothing until it is used.
# To add one: ARCHITECTURE.md, "Exports".
LAZY_EXPORTS = {
    "APPROACH_MODES": "plan",
    "MODES": "matching",
    "TRIGGERS": "program",
    "Box": "envelope",
    "Envelope": "envelope",
    "MotionSettings": "timing",
    "PlanSettings": "plan",
    "ProgramOptions": "program",
    "TrackerView": "sight",
    "ball_positions": "poses",
    "cube_runs": "iso9283",
    "evaluate": "iso9283",
    "import_export": "importing",
    "make_plan": "plan",
    "move_durations": "timing",
    "read_plan_meta": "pose_table",
    "read_pose_table": "pose_table",
    "registered": "iso9283",
    "to_robot": "iso9283",
    "write_export": "tracker_export",
    "write_plan": "plan",
}

__all__ = [
    "APPROACH_MODES",
    "MODES",
    "TRIGGERS",
    "Box",
    "Envelope",
    "MotionSettings",
    "PlanSettings",
    "ProgramOptions",
    "TrackerView",
    "ball_positions",
    "cube_runs",
    "evaluate",
    "import_export",
    "make_plan",
    "move_durations",
    "read_plan_meta",
    "read_pose_table",
    "registered",
    "to_robot",
    "write_export",
    "write_plan",
]

__getattr__, __dir__ = lazy_exports(__name__, LAZY_EXPORTS)
