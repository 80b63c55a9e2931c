"""What a rewrite needs besides the program: robot, error model, outside declarations.

Loaded once per process and shared by every file of a batch. The model file's
sha256 goes into the header of every output, so a batch can tell whether an
output is still up to date.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from rapidfix.digest import sha256_bytes, sha256_file
from rapidfix.error_model import ErrorModel, load_model
from rapidfix.exceptions import KinematicsError, ModelError, RapidSemanticError
from rapidfix.kinematics import RobotModel, load_robot, parse_robot
from rapidfix.postprocess.header import read_header


@dataclass
class Compensator:
    """Robot model, error model (with its file and hash) and outside RAPID declarations."""

    robot: RobotModel
    model: ErrorModel
    model_path: str
    model_sha256: str
    decls: list[Any] = field(default_factory=list)
    decl_paths: list[str] = field(default_factory=list)

    @property
    def decls_sha256(self) -> str:
        """One sha256 over the declaration files' bytes, in the order given."""
        return sha256_bytes(b"".join(p.original for p in self.decls))

    @classmethod
    def load(
        cls,
        model_path: str | Path,
        robot: str | None = None,
        robot_file: str | Path | None = None,
        decl_files: list[str | Path] | None = None,
    ) -> Compensator:
        """Load the model, the robot (named, from a file, or the one the model names)
        and the declaration files; refuse a model made for another robot."""
        model = load_model(model_path)
        if robot is not None and robot_file is not None:
            raise KinematicsError("give either robot or robot_file, not both")
        if robot is None and robot_file is None and model.robot_definition is not None:
            robot_model = parse_robot(model.robot_definition, f"{model_path} (robot_definition)")
        else:
            robot_model = load_robot(robot_file if robot_file is not None
                                     else (robot or model.robot))
        if robot_model.name != model.robot:
            raise ModelError(
                f"the model was made for robot {model.robot!r}, not {robot_model.name!r}",
                file=model_path,
                hint="fit a model on measurements of this robot",
            )
        from rapidfix.rapid import load_program

        paths = [str(p) for p in (decl_files or [])]
        decls = [load_program(p) for p in paths]
        for path, program in zip(paths, decls):
            if read_header(program.source.text) is not None:
                raise RapidSemanticError(
                    "is a compensated program: the targets it declares may be compensated "
                    "already, and a second compensation through them would be wrong",
                    file=path, hint="pass the original file with Compensator.load(decl_files)")
        return cls(robot_model, model, str(model_path), sha256_file(model_path), decls, paths)
