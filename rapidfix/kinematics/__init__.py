"""Screw-theory kinematics for ABB robots.

Product-of-exponentials forward kinematics, analytic all-branch inverse
kinematics from Paden–Kahan subproblems, ABB confdata and frame conventions.
Robot models are TOML files (`robots/`); `load_robot` finds them by name or path.
Knows nothing of RAPID or of error models.
"""

from typing import TYPE_CHECKING

from rapidfix import lazy_exports
from rapidfix.kinematics.ik_result import IKSolutions, IKStatus
from rapidfix.kinematics.robot_file import (
    available_robots,
    is_shipped,
    load_robot,
    parse_robot,
    read_robot_file,
)
from rapidfix.kinematics.robot_model import RobotModel

if TYPE_CHECKING:  # what type checkers and IDEs see of the lazy exports
    from rapidfix.kinematics.frames import (
        matrix_to_quat,
        matrix_to_rotvec,
        pose,
        pose_to_pos_quat,
        rotvec_to_matrix,
    )
    from rapidfix.kinematics.ik import numpy_closed_form, prepare
    from rapidfix.kinematics.screws import compiled_forward, invert_transform, revolute_exp

# The other exports, name -> module of this package: each is imported from its module on
# first use (PEP 562), so exporting a name costs nothing until it is used.
# To add one: ARCHITECTURE.md, "Exports".
LAZY_EXPORTS = {
    "compiled_forward": "screws",
    "invert_transform": "screws",
    "matrix_to_quat": "frames",
    "matrix_to_rotvec": "frames",
    "numpy_closed_form": "ik",
    "pose": "frames",
    "pose_to_pos_quat": "frames",
    "prepare": "ik",
    "revolute_exp": "screws",
    "rotvec_to_matrix": "frames",
}

__all__ = [
    "IKSolutions",
    "IKStatus",
    "RobotModel",
    "available_robots",
    "compiled_forward",
    "invert_transform",
    "is_shipped",
    "load_robot",
    "matrix_to_quat",
    "matrix_to_rotvec",
    "numpy_closed_form",
    "parse_robot",
    "pose",
    "pose_to_pos_quat",
    "prepare",
    "read_robot_file",
    "revolute_exp",
    "rotvec_to_matrix",
]

__getattr__, __dir__ = lazy_exports(__name__, LAZY_EXPORTS)
