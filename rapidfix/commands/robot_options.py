"""The one definition of the command-line options that choose a robot: --robot and --robot-file."""

from __future__ import annotations

import argparse

from rapidfix.kinematics import RobotModel, available_robots, load_robot, read_robot_file

DEFAULT_ROBOT = "IRB1600-10/1.45"


def add_robot_arguments(
    parser: argparse.ArgumentParser, default: str | None = DEFAULT_ROBOT,
    default_text: str | None = None,
) -> None:
    """Add mutually exclusive --robot NAME and --robot-file PATH options to `parser`.

    `default_text` says what is used without either (default: the `default` robot).
    """
    if default_text is None and default:
        default_text = default
    group = parser.add_mutually_exclusive_group()
    group.add_argument(
        "--robot",
        metavar="NAME",
        default=None,
        help=f"robot model shipped with rapidfix ({', '.join(available_robots())}); "
        f"default {default_text}"
        if default_text
        else "robot model shipped with rapidfix",
    )
    group.add_argument(
        "--robot-file",
        metavar="PATH",
        default=None,
        help="your own robot model file (TOML: six screws, tool0 home pose, joint limits)",
    )
    parser.set_defaults(_robot_default=default)


def robot_from_args(args: argparse.Namespace, fallback: str | None = None) -> RobotModel | None:
    """The model named by --robot / --robot-file; else `fallback` or the parser default.

    `fallback` lets a command prefer the robot named in a data file (setup.toml)
    over the built-in default. Returns None only when nothing names a robot.
    """
    if getattr(args, "robot_file", None):
        return read_robot_file(args.robot_file)
    if getattr(args, "robot", None):
        return load_robot(args.robot)
    name = fallback or getattr(args, "_robot_default", None)
    return None if name is None else load_robot(name)
