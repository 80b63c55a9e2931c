"""End to end on the virtual cell: rewrite with a fitted model, execute on the true robot.

The test executes programs itself: a jointtarget is commanded as written, a
robtarget through the nominal IK on its confdata; the commanded joints go
through the virtual robot's true errors. Intended TCP positions are computed
here from the original program's declarations with scipy (not with the
post-processor's frame code). A constant joint-1 error is invisible to any
measurement in the cell, so both runs are compared after the best rotation
about axis 1 (one parameter per run, fitted here).
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from rapidfix.postprocess.rewrite import RewriteOptions, rewrite_file
from rapidfix.rapid import load_program


def frame(trans, rot_wxyz) -> np.ndarray:
    T = np.eye(4)
    w, x, y, z = rot_wxyz
    T[:3, :3] = Rotation.from_quat([x, y, z, w]).as_matrix()
    T[:3, 3] = trans
    return T


def decls(program):
    return {d.name.lower(): d for d in program.declarations}


def ballbar_setup(program):
    d = decls(program)
    tool = d["tballbar"].data
    wobj = d["wobjballbar"].data
    tool_T = frame(tool.tframe.trans, tool.tframe.rot)
    wobj_T = frame(wobj.uframe.trans, wobj.uframe.rot) @ frame(wobj.oframe.trans, wobj.oframe.rot)
    names = [f"pbb{k:02d}" for k in range(19)]
    targets = np.array([wobj_T @ frame(d[n].data.trans, d[n].data.rot) for n in names])
    conf = np.array([d[n].data.robconf for n in names])
    return names, tool_T, wobj_T, targets, conf


def align_about_z(actual, intended):
    """Best rotation of `actual` about the base z axis onto `intended` (axis 1 of the IRB 1600)."""
    xa, ya = actual[:, 0], actual[:, 1]
    xi, yi = intended[:, 0], intended[:, 1]
    angle = np.arctan2(np.sum(xa * yi - ya * xi), np.sum(xa * xi + ya * yi))
    c, s = np.cos(angle), np.sin(angle)
    out = actual.copy()
    out[:, 0], out[:, 1] = c * xa - s * ya, s * xa + c * ya
    return out


def true_tcp(virtual, q_cmd, tool_T):
    flange = virtual.actual_model.fk(virtual.actual_joints(q_cmd))
    return (flange @ tool_T)[:, :3, 3]


def jointtargets(program):
    return {
        d.name.lower(): np.radians(np.asarray(d.data.robax, dtype=float))
        for d in program.declarations
        if d.type_key == "jointtarget"
    }


@pytest.fixture(scope="module")
def rewritten(cell, comp, samples, tmp_path_factory):
    out = tmp_path_factory.mktemp("e2e") / "ballbar.mod"
    result = rewrite_file(samples / "ballbar.mod", out, comp, RewriteOptions())
    return result, load_program(out)


def test_rewritten_ballbar_lands_on_its_targets(cell, samples, rewritten):
    virtual, robot = cell["virtual"], cell["robot"]
    original = load_program(samples / "ballbar.mod")
    names, tool_T, _, targets, conf = ballbar_setup(original)
    intended = targets[:, :3, 3]
    # before: the original program on the nominal controller
    flange = targets @ np.linalg.inv(tool_T)
    q_before, status = robot.ik_conf(flange, conf)
    assert np.all(status == 0)
    before = align_about_z(true_tcp(virtual, q_before, tool_T), intended)
    # after: the rewritten program's jointtargets, as written
    result, out = rewritten
    assert result.moves_compensated == result.moves_total == 21
    jts = jointtargets(out)
    q_after = np.array([jts[f"jt_{n}"] for n in names])
    after = align_about_z(true_tcp(virtual, q_after, tool_T), intended)
    err_before = np.linalg.norm(before - intended, axis=1).mean()
    err_after = np.linalg.norm(after - intended, axis=1).mean()
    assert err_before > 0.02  # the virtual robot does have errors to remove
    assert err_after <= 0.2 * err_before


def test_predicted_deviation_is_what_the_model_says(cell, samples, rewritten):
    """The stated worst case equals the model's TCP error of the written jointtargets."""
    model, robot = cell["model"], cell["robot"]
    original = load_program(samples / "ballbar.mod")
    names, tool_T, _, targets, _ = ballbar_setup(original)
    result, out = rewritten
    jts = jointtargets(out)
    q = np.array([jts[f"jt_{n}"] for n in names])
    tcp = (model.actual_flange(robot, q) @ tool_T)[:, :3, 3]
    err = np.linalg.norm(tcp - targets[:, :3, 3], axis=1)
    assert err.max() < 1e-3
    assert result.worst_predicted_mm < 1e-3


def distance_to_segment(points, a, b):
    ab = b - a
    t = np.clip((points - a) @ ab / (ab @ ab), 0.0, 1.0)
    return np.linalg.norm(points - (a + t[:, None] * ab), axis=1)


@pytest.mark.parametrize("tolerance", [0.1, 0.02])
def test_linear_paths_stay_within_tolerance(cell, comp, samples, tmp_path, tolerance):
    """Every MoveL, now a chain of MoveAbsJ, stays within the tolerance of its line
    (joint-linear interpolation sampled densely, TCP as the fitted model predicts it)."""
    model, robot = cell["model"], cell["robot"]
    out_path = tmp_path / "ballbar.mod"
    result = rewrite_file(
        samples / "ballbar.mod", out_path, comp, RewriteOptions(path_tolerance_mm=tolerance)
    )
    out = load_program(out_path)
    original = load_program(samples / "ballbar.mod")
    names, tool_T, _, targets, _ = ballbar_setup(original)
    jts = jointtargets(out)
    chain = [m.target.text.lower() for m in out.motions]
    destinations = [i for i, n in enumerate(chain) if n not in {s.lower() for s in result.inserted}]
    # output destinations 1..19 are the MoveL to pBB00..pBB18 (0 is the MoveJ approach)
    s = np.linspace(0.0, 1.0, 41)
    worst = 0.0
    for k in range(1, len(names)):
        a, b = targets[k - 1, :3, 3], targets[k, :3, 3]
        pieces = chain[destinations[k] : destinations[k + 1] + 1]
        assert pieces[-1] == f"jt_{names[k]}"
        for j0, j1 in itertools.pairwise(pieces):
            q = jts[j0] + s[:, None] * (jts[j1] - jts[j0])
            tcp = (model.actual_flange(robot, q) @ tool_T)[:, :3, 3]
            worst = max(worst, distance_to_segment(tcp, a, b).max())
    assert worst <= tolerance
    if tolerance < 0.1:
        assert result.points_added > 11  # a tighter tolerance needs more points


def test_filtered_robtargets_land_on_the_targets(cell, comp, samples, tmp_path):
    """--emit robtargets: the controller's nominal IK of each filtered robtarget, on its
    confdata, run on the true robot, lands closer than the original program."""
    virtual, robot = cell["virtual"], cell["robot"]
    out_path = tmp_path / "ballbar.mod"
    result = rewrite_file(
        samples / "ballbar.mod", out_path, comp, RewriteOptions(emit="robtargets")
    )
    assert result.points_added == 0 and not result.skipped
    out = load_program(out_path)
    assert [m.name for m in out.motions] == [
        m.name for m in load_program(samples / "ballbar.mod").motions
    ]
    original = load_program(samples / "ballbar.mod")
    _names, tool_T, _wobj_T, targets, conf = ballbar_setup(original)
    filtered = ballbar_setup(out)[3]
    f_conf = ballbar_setup(out)[4]
    q_before, _ = robot.ik_conf(targets @ np.linalg.inv(tool_T), conf)
    q_after, status = robot.ik_conf(filtered @ np.linalg.inv(tool_T), f_conf)
    assert np.all(status == 0)
    intended = targets[:, :3, 3]
    before = align_about_z(true_tcp(virtual, q_before, tool_T), intended)
    after = align_about_z(true_tcp(virtual, q_after, tool_T), intended)
    err_before = np.linalg.norm(before - intended, axis=1).mean()
    err_after = np.linalg.norm(after - intended, axis=1).mean()
    assert err_after <= 0.2 * err_before


#: instructions MoveAbsJ cannot stand for, each written as a program would (ToPoint pBBk)
KEPT_FORMS = (
    "ArcL {p}, v50, sm1, wd1, fine, tBallbar\\WObj:=wobjBallbar;",
    "TriggL {p}, v50, gun, fine, tBallbar\\WObj:=wobjBallbar;",
    "MoveLDO {p}, v50, fine, tBallbar\\WObj:=wobjBallbar, do1, 1;",
    "MoveL {p}, v50, fine, tBallbar\\WObj:=wobjBallbar\\Corr;",
    "SearchL \\Stop, di1, pHit, {p}, v50, tBallbar\\WObj:=wobjBallbar;",
    "MoveLSync {p}, v50, fine, tBallbar\\WObj:=wobjBallbar, \"Weld\";",
)


def test_instructions_without_a_joint_form_keep_it_and_land_on_their_targets(
        cell, comp, samples, tmp_path):
    """With joint targets emitted (the default), an instruction no MoveAbsJ can stand for
    (arc welding, triggers, set-output moves, \\Corr, searches, synchronised moves) keeps
    its instruction with a filtered robtarget: executed through the nominal IK on its
    confdata, it lands on the intended target as the MoveAbsJ moves do."""
    virtual, robot = cell["virtual"], cell["robot"]
    text = (samples / "ballbar.mod").read_text()
    names, tool_T, wobj_T, targets, conf = ballbar_setup(load_program(samples / "ballbar.mod"))
    for k in range(1, len(names)):
        line = f"MoveL pBB{k:02d}, v50, fine, tBallbar\\WObj:=wobjBallbar;"
        text = text.replace(line, KEPT_FORMS[k % len(KEPT_FORMS)].format(p=f"pBB{k:02d}"), 1)
    source = tmp_path / "kept.mod"
    source.write_text(text)
    result = rewrite_file(source, tmp_path / "kept.out.mod", comp, RewriteOptions())
    assert result.skipped == [] and result.moves_compensated == result.moves_total == 21
    kinds = {"ArcL", "TriggL", "MoveLDO", "SearchL", "MoveLSync"}
    expected = {f"{name} has no joint-target form": 3 for name in kinds}
    expected["optional argument \\Corr has no MoveAbsJ form"] = 3
    assert result.filtered_reasons == expected
    out = load_program(tmp_path / "kept.out.mod")
    kept = [m for m in out.motions if m.name.lower() != "moveabsj"]
    assert [m.name for m in kept] == [KEPT_FORMS[k % 6].split(" ")[0] for k in range(1, 19)]
    d = decls(out)
    written = [d[m.target.text.lower()].data for m in kept]
    flange = (wobj_T @ np.array([frame(w.trans, w.rot) for w in written])) @ np.linalg.inv(tool_T)
    q_after, status = robot.ik_conf(flange, np.array([w.robconf for w in written]))
    q_before, status_before = robot.ik_conf(targets[1:] @ np.linalg.inv(tool_T), conf[1:])
    assert np.all(status == 0) and np.all(status_before == 0)
    intended = targets[1:, :3, 3]
    before = align_about_z(true_tcp(virtual, q_before, tool_T), intended)
    after = align_about_z(true_tcp(virtual, q_after, tool_T), intended)
    err_before = np.linalg.norm(before - intended, axis=1).mean()
    err_after = np.linalg.norm(after - intended, axis=1).mean()
    assert err_before > 0.02
    assert err_after <= 0.2 * err_before
