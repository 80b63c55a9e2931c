"""A model fitted for a robot rapidfix does not ship carries that robot: it rewrites a
program in a fresh process without the robot file, exactly as with it."""

from __future__ import annotations

import json
import subprocess
import sys
from importlib import resources
from pathlib import Path

import numpy as np

from rapidfix.cli import main
from rapidfix.error_model.model_file import load_model
from rapidfix.kinematics import is_shipped, load_robot, parse_robot, read_robot_file
from rapidfix.sim import simulate_cell

SAMPLES = Path(__file__).resolve().parents[2] / "samples"
IRB1600 = resources.files("rapidfix.kinematics.robots").joinpath("irb1600-10_1.45.toml")


def _custom_robot_file(path: Path) -> Path:
    """The IRB 1600 with another name and its upper arm 3 mm longer: a robot of one cell."""
    text = IRB1600.read_text(encoding="utf-8").replace(
        'name = "IRB1600-10/1.45"', 'name = "Cell7 arm"')
    text = text.replace("[750.0, 0.0, 1186.5]", "[753.0, 0.0, 1186.5]")
    text = text.replace("[815.0, 0.0, 1186.5]", "[818.0, 0.0, 1186.5]")
    path.write_text(text, encoding="utf-8")
    return path


def test_a_robot_file_model_reloads_without_the_file(tmp_path, capsys):
    robot_file = _custom_robot_file(tmp_path / "cell7.toml")
    robot = read_robot_file(robot_file)
    assert not is_shipped(robot) and is_shipped(load_robot("IRB1600-10/1.45"))
    q = np.radians([[10.0, 20.0, -10.0, 30.0, 40.0, 50.0]])
    assert np.abs(robot.fk(q) - load_robot("IRB1600-10/1.45").fk(q))[:, :3, 3].max() > 1.0

    cell = simulate_cell(tmp_path / "cell", seed=4, robot=robot)
    model_path = tmp_path / "model.json"
    assert main(["fit", str(cell / "setup.toml"), str(cell / "sweeps.csv"),
                 "--robot", str(robot_file), "-o", str(model_path)]) == 0
    # the file stores the robot, and the robot rebuilt from it is the file's
    stored = load_model(model_path).robot_definition
    assert stored is not None and stored["name"] == "Cell7 arm"
    again = parse_robot(json.loads(model_path.read_text())["robot_definition"], "model")
    qs = np.random.default_rng(1).uniform(robot.limits[:, 0], robot.limits[:, 1], (30, 6))
    assert np.array_equal(again.fk(qs), robot.fk(qs))
    assert np.array_equal(again.limits, robot.limits)

    with_file = tmp_path / "with_file.mod"
    status = main(["rewrite", str(SAMPLES / "ballbar.mod"), "--model", str(model_path),
                   "--robot-file", str(robot_file), "-o", str(with_file)])
    assert status in (0, 3)  # 3: a target whose confdata branch this arm cannot reach
    capsys.readouterr()
    robot_file.unlink()  # the robot file is gone: only the model file knows the robot
    alone = tmp_path / "alone.mod"
    done = subprocess.run(
        [sys.executable, "-c", "import sys; from rapidfix.cli import main; "
         "sys.exit(main(sys.argv[1:]))", "rewrite", str(SAMPLES / "ballbar.mod"),
         "--model", str(model_path), "-o", str(alone)],
        capture_output=True, text=True, check=False)
    assert done.returncode == status, done.stderr
    assert "Traceback" not in done.stderr
    assert alone.read_bytes() == with_file.read_bytes()
    assert b"MoveAbsJ" in alone.read_bytes()
