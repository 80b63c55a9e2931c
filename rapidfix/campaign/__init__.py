"""The measurement campaign: what the robot runs, and what the tracker saw.

- `plan` (with `poses`, `envelope`, `timing`, `program`, `pose_table`): the RAPID
  measurement program and its pose table (`rapidfix plan`);
- `tracker_export` and `matching`: a laser tracker's export merged with the pose
  table into the measurement files (`rapidfix import`);
- `iso9283`: pose and distance accuracy and repeatability in the terms of
  ISO 9283:1998 (`rapidfix iso9283`).
"""
