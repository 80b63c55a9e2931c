"""Screw-theory kinematics for ABB robots.

Product-of-exponentials forward kinematics, analytic all-branch inverse
kinematics from Paden–Kahan subproblems, ABB confdata and frame conventions.
Robot models are TOML files (`robots/`); `load_robot` finds them by name or path.
Knows nothing of RAPID or of error models.
"""

from rapidfix.kinematics.ik_result import IKSolutions, IKStatus
from rapidfix.kinematics.robot_file import (
    available_robots,
    is_shipped,
    load_robot,
    parse_robot,
    read_robot_file,
)
from rapidfix.kinematics.robot_model import RobotModel

__all__ = [
    "IKSolutions",
    "IKStatus",
    "RobotModel",
    "available_robots",
    "is_shipped",
    "load_robot",
    "parse_robot",
    "read_robot_file",
]
