"""The loop on the robot: simulate → fit → diagnose → rewrite with the diagnosed model →
execute the rewritten program on the virtual robot, in its own move order.

The program (`closed_loop.pick_and_place`) has two tools with loads, a work object,
a part picked up and put down with GripLoad, MoveJ, MoveL and MoveC. The virtual
robot (rapidfix.sim, which shares no code with the error model) runs every move
with the load it really carries, each joint arriving from the side it really
moves in (intermediate points included) and at the cell's temperature. The
truth of those conditions comes from the program's generator, not from the
rewrite. Every candidate alone and three pairs are checked the same way in
test_acceptance.py; here the pair of two conditions-driven effects and the
approach points.
"""

import pytest


@pytest.mark.slow
@pytest.mark.parametrize("seed", [1, 2, 3])
def test_compliance_and_backlash_together_on_the_robot(cell, seed):
    _, _, result = cell.scenario(("joint_compliance", "backlash"), seed)
    assert {"joint_compliance", "backlash"} <= {e.type_name for e in result.model.effects}
    cell.check_on_robot(("joint_compliance", "backlash"), seed)


@pytest.mark.slow
@pytest.mark.parametrize("seed", [1, 2])
def test_approach_points_take_the_backlash_of_unknown_starts(cell, seed):
    # Without approach points the first move of the routine starts where the program
    # cannot say, and is taken midway between the directions: off by up to half the
    # play. With them every joint with play arrives moving up, as compensated.
    _, plain, _, without, floor = cell.loop(("backlash",), seed, approach=False)
    _, rewritten, _, with_approach, _ = cell.loop(("backlash",), seed, approach=True)
    assert with_approach.mean_mm <= 1.5 * floor, (with_approach.mean_mm, floor)
    assert with_approach.error_mm.max() < 0.5 * without.error_mm.max()
    assert with_approach.mean_mm < without.mean_mm
    text = rewritten.data.decode()
    assert "options: approach=fine_points" in text
    assert "direction_unknown_moves=0" in text
    # one approach point before each compensated MoveJ fine point, none for MoveL/MoveC
    movej = plain.data.decode().count("v500, fine")
    approach = {name for name in rewritten.inserted if name.endswith("_app")}
    assert len(approach) == movej > 0
    assert not any(name.endswith("_app") for name in plain.inserted)
