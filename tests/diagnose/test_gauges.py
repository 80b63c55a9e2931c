"""One target ball does not show how the flange turns about it (rapidfix.diagnose.gauges).

Truth from the virtual robot: the flange's real orientation, which the measured
points never show, is compared with the diagnosed model's at poses the data never
had. Without the gauge a tool offset's tangential part sits in joint 6's zero and
the flange is off by up to ~0.3°.
"""

import copy

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from rapidfix.diagnose.gauges import resolve_flange_gauge
from rapidfix.errors.fit_effects import predict
from rapidfix.sim.plans import point_plan


def _turn_error_deg(model, vr, q):
    """Mean angle (deg) between the model's and the virtual robot's flange orientation."""
    truth = vr.tcp_poses(q, np.eye(4))[:, :3, :3]
    mine = model.actual_flange(vr.robot, q)[:, :3, :3]
    rel = np.swapaxes(mine, 1, 2) @ truth
    return float(np.degrees(np.linalg.norm(Rotation.from_matrix(rel).as_rotvec(), axis=1)).mean())


@pytest.mark.parametrize("effect", ["tool_offset", "link_geometry"])
def test_the_flange_turns_as_the_robot_does_and_the_points_stay(cell, effect):
    seed = cell.detectable_seeds((effect,), 1)[0]
    n_cal = 80 if effect == "link_geometry" else 60
    data, _, result = cell.scenario((effect,), seed, n_cal)
    vr = data.robot
    q = point_plan(vr.robot, np.zeros(3), 40, seed=seed + 100)
    assert "flange_gauge" in result.model.statistics["diagnosis"]
    # the fitted model before the gauge was set, as the selection left it
    raw = copy.deepcopy(result.selection.final.model)
    assert [e.type_name for e in raw.effects] == [e.type_name for e in result.model.effects]
    before = _turn_error_deg(raw, vr, q)
    after = _turn_error_deg(result.model, vr, q)
    assert after < 0.05, (before, after)
    assert after < 0.5 * before
    # the measured points are predicted as before (the change is invisible to them)
    moved = copy.deepcopy(raw)
    change = resolve_flange_gauge(moved, vr.robot, result.calibration)
    assert change is not None
    np.testing.assert_allclose(predict(moved, vr.robot, result.calibration),
                               predict(raw, vr.robot, result.calibration), atol=2e-3)


def test_nothing_moves_without_a_flange_translation(cell):
    data, _, result = cell.scenario(("joint_compliance",), 3)
    model = copy.deepcopy(result.model)
    assert resolve_flange_gauge(model, data.robot.robot, result.calibration) is None
    assert "flange_gauge" not in result.model.statistics["diagnosis"]
