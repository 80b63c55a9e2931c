"""Robot model files: loading by name and path, clear errors, the CLI options."""

import argparse
from importlib import resources

import numpy as np
import pytest

from rapidfix.commands.robot_options import add_robot_arguments, robot_from_args
from rapidfix.exceptions import KinematicsError
from rapidfix.kinematics import available_robots, load_robot, read_robot_file

IRB1600 = resources.files("rapidfix.kinematics.robots").joinpath("irb1600-10_1.45.toml").read_text()


def test_names_are_found_loosely_and_unknown_names_list_the_known():
    assert load_robot("irb 1600-10/1.45") is load_robot("IRB1600-10/1.45")
    with pytest.raises(KinematicsError) as err:
        load_robot("IRB9999")
    for name in available_robots():
        assert name in str(err.value)


def test_shipped_files_cite_their_sources():
    for entry in resources.files("rapidfix.kinematics.robots").iterdir():
        if entry.name.endswith(".toml"):
            text = entry.read_text(encoding="utf-8")
            assert "Product specification" in text or "product specification" in text


def test_user_file_loads_and_matches_the_shipped_model(tmp_path):
    path = tmp_path / "my_robot.toml"
    path.write_text(IRB1600.replace('name = "IRB1600-10/1.45"', 'name = "my cell robot"'))
    robot = load_robot(path)
    assert robot.name == "my cell robot" and robot.source == str(path)
    q = np.random.default_rng(0).uniform(-1, 1, (20, 6))
    assert np.allclose(robot.fk(q), load_robot("IRB1600-10/1.45").fk(q))


@pytest.mark.parametrize(
    ("old", "new", "key"),
    [
        ('name = "IRB1600-10/1.45"', "", "'name'"),
        (
            "axis = [0.0, 1.0, 0.0]\npoint = [150.0, 0.0, 486.5]",
            "axis = [0.0, 1.0]\npoint = [150.0, 0.0, 486.5]",
            "joint[2].axis",
        ),
        ("limits_deg = [-90.0, 150.0]", "limits_deg = [150.0, -90.0]", "joint[2].limits_deg"),
        ("limits_deg = [-90.0, 150.0]", 'limits_deg = ["a", 150.0]', "joint[2].limits_deg"),
        (
            "quaternion = [0.70710678118654752, 0.0, 0.70710678118654752, 0.0]",
            "quaternion = [0.8, 0.0, 0.7, 0.0]",
            "tool0.quaternion",
        ),
        ("[tool0]", "[tool1]", "'tool0'"),
        (
            "point = [750.0, 0.0, 1186.5]\nlimits_deg = [-115.0, 115.0]",
            "point = [750.0, 0.0, 1216.5]\nlimits_deg = [-115.0, 115.0]",
            "joint[5].point",
        ),
        (
            "axis = [0.0, 1.0, 0.0]\npoint = [150.0, 0.0, 1186.5]",
            "axis = [0.0, 1.0, 0.1]\npoint = [150.0, 0.0, 1186.5]",
            "joint[3].axis",
        ),
    ],
)
def test_malformed_files_name_file_and_key(tmp_path, old, new, key):
    assert old in IRB1600
    path = tmp_path / "bad.toml"
    path.write_text(IRB1600.replace(old, new, 1))
    with pytest.raises(KinematicsError) as err:
        read_robot_file(path)
    assert str(path) in str(err.value) and key in str(err.value)


def test_toml_syntax_errors_carry_line_and_column(tmp_path):
    path = tmp_path / "broken.toml"
    path.write_text('name = "x"\naxis = = 2\n')
    with pytest.raises(KinematicsError) as err:
        read_robot_file(path)
    assert err.value.file == str(path) and (err.value.line, err.value.column) == (2, 8)


def test_missing_file_is_a_kinematics_error(tmp_path):
    with pytest.raises(KinematicsError, match="cannot read"):
        load_robot(tmp_path / "nothing.toml")


def test_cli_arguments(tmp_path):
    parser = argparse.ArgumentParser()
    add_robot_arguments(parser)
    assert robot_from_args(parser.parse_args([])).name == "IRB1600-10/1.45"
    assert robot_from_args(parser.parse_args(["--robot", "IRB120-3/0.58"])).name == "IRB120-3/0.58"
    assert (
        robot_from_args(parser.parse_args([]), fallback="IRB4600-60/2.05").name == "IRB4600-60/2.05"
    )
    path = tmp_path / "r.toml"
    path.write_text(IRB1600)
    assert robot_from_args(parser.parse_args(["--robot-file", str(path)])).source == str(path)
    with pytest.raises(SystemExit):
        parser.parse_args(["--robot", "IRB120-3/0.58", "--robot-file", str(path)])
