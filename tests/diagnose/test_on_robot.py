"""The loop on the robot: simulate → fit → diagnose → rewrite with the diagnosed model →
execute the rewritten program on the virtual robot, in its own move order.

The program (`closed_loop.pick_and_place`) has two tools with loads, a work object,
a part picked up and put down with GripLoad, MoveJ, MoveL and MoveC. The virtual
robot (rapidfix.sim, which shares no code with the error model) runs every move
with the load it really carries, each joint arriving from the side it really
moves in (intermediate points included) and at the cell's temperature. The
truth of those conditions comes from the program's generator, not from the
rewrite.
"""

import os
import tempfile
import warnings

import numpy as np
import pytest

from rapidfix.errors.joint_rbf import OutsideRangeWarning
from rapidfix.errors.model_file import save_model
from rapidfix.postprocess.closed_loop import pick_and_place, run_on_robot
from rapidfix.postprocess.compensator import Compensator
from rapidfix.postprocess.rewrite import RewriteOptions, rewrite_source

CASES = [
    (("joint_compliance",), 3),
    (("tool_offset",), 2),
    (("tool_offset",), 3),
    (("backlash",), 3),
    (("joint_coupling",), 7),
    (("registration_scale",), 3),
    (("thermal_drift",), 3),
    (("joint_compliance", "backlash"), 3),
]


def _loop(cell, effects, seed, n_calibration=60, approach=False):
    data, _model, result = cell.scenario(effects, seed, n_calibration)
    robot = data.robot.robot
    folder = tempfile.mkdtemp()
    path = os.path.join(folder, "model.json")
    save_model(result.model, path)
    comp = Compensator.load(path)
    program = pick_and_place(robot, seed, smr_offset_mm=data.setup.smr_offset_mm)
    temp = None if data.validation.temp_c is None else float(np.mean(data.validation.temp_c))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", OutsideRangeWarning)
        rewritten = rewrite_source(program.text.encode(), "loop.mod", comp,
                                   RewriteOptions(temperature_c=temp, approach=approach))
    vr = data.robot
    before = run_on_robot(vr, program, program.text, set(), temp)
    after = run_on_robot(vr, program, rewritten.data.decode(), rewritten.inserted, temp)
    floor = vr.noise_floor(program.q)["mean_tcp_error_mm"]
    return result, rewritten, before, after, floor


@pytest.mark.slow
@pytest.mark.parametrize(("effects", "seed"), CASES, ids=["+".join(c[0]) for c in CASES])
def test_the_diagnosed_model_compensates_a_real_program(cell, effects, seed):
    result, rewritten, before, after, floor = _loop(cell, effects, seed)
    named = {e.type_name for e in result.model.effects}
    expected = {"registration_scale": "registration"}
    assert {expected.get(e, e) for e in effects} <= named, named
    assert rewritten.moves_compensated == rewritten.moves_total
    # the robot lands within 1.5x the noise floor, having started ten times further off
    assert after.mean_mm <= 1.5 * floor, (after.mean_mm, floor)
    assert before.mean_mm > 8 * floor
    # what the rewrite predicted for the program as written is what the robot did
    predicted = rewritten.predicted_before_mm[0]
    assert abs(predicted - before.mean_mm) <= 0.25 * before.mean_mm + 2 * floor, (
        predicted, before.mean_mm)
    # and where it says the compensated moves land is where they land, to the floor
    assert rewritten.worst_predicted_mm < 1e-3


@pytest.mark.slow
@pytest.mark.parametrize("seed", [2, 3])
def test_approach_points_take_the_backlash_of_unknown_starts(cell, seed):
    # Without approach points the first move of the routine starts where the program
    # cannot say, and is taken midway between the directions: off by up to half the
    # play. With them every joint with play arrives moving up, as compensated.
    _, plain, _, without, floor = _loop(cell, ("backlash",), seed)
    _, rewritten, _, with_approach, _ = _loop(cell, ("backlash",), seed, approach=True)
    assert with_approach.mean_mm <= 1.5 * floor, (with_approach.mean_mm, floor)
    assert with_approach.error_mm.max() < 0.5 * without.error_mm.max()
    assert with_approach.mean_mm < without.mean_mm
    text = rewritten.data.decode()
    assert "options: approach=fine_points" in text
    # one approach point before each compensated MoveJ fine point, none for MoveL/MoveC
    movej = plain.data.decode().count("v500, fine")
    assert len(rewritten.inserted - plain.inserted) == movej > 0
