"""The non-parametric fallback (issue #14, section 2): a correction whose cause is unknown.

The simulator (rapidfix.sim, independent of rapidfix.error_model) hides a hose that pulls
on joint 5 by A · sin θ4 · sin θ6: smooth, over two joints together, and described by
no candidate and no single joint × driver. The diagnosis must accept the fallback
(no physical name), say which joint it acts on and which joints it depends on, end
at or below 1.5× the noise floor on validation points it never fitted, and its
model must compensate a real program on the virtual robot. The effect itself is
checked against an independent evaluation, its file round trip and its domain.
"""

import json
import warnings

import numpy as np
import pytest

from rapidfix.diagnose.fallback import cv_errors, farthest_points
from rapidfix.error_model.candidates.rbf_correction import RBFCorrection
from rapidfix.error_model.context import Context
from rapidfix.error_model.joint_rbf import OutsideRangeWarning
from rapidfix.error_model.model import ErrorModel
from rapidfix.error_model.model_file import save_model
from rapidfix.error_model.registry import effect_from_dict
from rapidfix.exceptions import ModelError
from rapidfix.kinematics import load_robot
from rapidfix.postprocess.compensator import Compensator
from rapidfix.postprocess.emission_forms import robtarget_literals
from rapidfix.postprocess.rewrite import RewriteOptions, rewrite_source
from rapidfix.sim import EFFECTS, VirtualRobot
from rapidfix.sim.plans import point_plan, sweep_plan

HIDDEN = ("hose_pull",)
SEEDS = 3


@pytest.mark.slow
def test_hidden_smooth_effect_is_taken_by_the_fallback(cell):
    seeds = cell.detectable_seeds(HIDDEN, SEEDS)
    assert len(seeds) == SEEDS
    for seed in seeds:
        data, _, result = cell.scenario(HIDDEN, seed)
        truth = data.truth["errors"]["hose_pull"]
        # the fallback, and no physical or structured name for what none of them is
        assert result.accepted == ["rbf_correction"], (seed, result.statement)
        effect = next(e for e in result.model.effects if e.type_name == "rbf_correction")
        assert effect.joint + 1 == truth["joint"], (seed, result.statement)
        depends = sorted(int(f[1]) for f in effect.features if f.startswith("q"))
        assert depends == truth["depends_on_joints"], (seed, result.statement)
        assert ("a correction whose cause is unknown, depending on joint 4 and joint 6, "
                "acting on joint 5") in result.statement
        floor = data.truth["noise_floor"]["mean_tcp_error_mm"]
        sel = result.selection
        assert sel.before.validation.mean_mm > 2 * floor
        assert sel.final.validation.mean_mm <= 1.5 * floor, (seed, sel.final.validation.mean_mm,
                                                             floor)
        # the correction follows the true error of joint 5 on the validation poses
        val = result.validation
        fitted = effect.joint_delta(val.q, val.ctx)[:, effect.joint]
        true = np.radians(truth["amplitude_deg"]) * np.sin(val.q[:, 3]) * np.sin(val.q[:, 5])
        assert np.corrcoef(fitted, true)[0, 1] > 0.8, seed
        # the search and what it found are in the report
        records = result.report.summary["fallback"]
        assert records["settings"][0]["joint"] == 5
        assert records["settings"][0]["depends_on"] == ["joint 4", "joint 6"]
        cell.check_on_robot(HIDDEN, seed)


def _effect(features=("q4", "q6"), lo=(-2.0, -2.5), hi=(2.0, 2.5), seed=0):
    rng = np.random.default_rng(seed)
    centres = rng.uniform(-1, 1, (7, len(features)))
    basis = np.linalg.qr(rng.normal(size=(7, 4)))[0]
    eff = RBFCorrection(4, features, lo, hi, centres, 0.6, basis,
                        centring=rng.uniform(0, 0.3, 7), reference=[0.0] * len(features))
    eff.set_fitted(rng.normal(0, 1e-4, 4))
    return eff


def test_correction_matches_an_independent_evaluation():
    eff = _effect()
    rng = np.random.default_rng(3)
    q = rng.uniform(-1.9, 1.9, (20, 6))
    got = eff.joint_delta(q, Context())
    weights = eff.basis @ eff.params()
    for i in range(len(q)):  # one pose at a time, written out
        u = np.array([q[i, 3] / 2.0, q[i, 5] / 2.5])
        value = 0.0
        for k, c in enumerate(eff.centres):
            value += weights[k] * (np.exp(-np.sum((u - c) ** 2) / (2 * 0.6**2))
                                   - eff.centring[k])
        assert got[i, 4] == pytest.approx(value, abs=1e-15)
    assert np.all(got[:, [0, 1, 2, 3, 5]] == 0.0)


def test_correction_round_trips_through_json():
    eff = _effect(features=("q2", "q3", "payload_kg"), lo=(-1, -2, 0.0), hi=(1, 1, 10.0))
    back = effect_from_dict(json.loads(json.dumps(eff.to_dict())))
    q = np.random.default_rng(1).uniform(-1, 1, (10, 6))
    ctx = Context(payload_kg=np.linspace(0, 10, 10))
    assert np.array_equal(back.joint_delta(q, ctx), eff.joint_delta(q, ctx))
    assert back.what() == eff.what() == ("a correction whose cause is unknown, depending on "
                                         "joint 2, joint 3 and payload, acting on joint 5")
    # without a payload it is taken at its reference
    assert back.context_fields() == {"payload_kg"}
    plain = back.joint_delta(q, Context())
    at_ref = back.joint_delta(q, Context(payload_kg=np.zeros(10)))
    assert np.array_equal(plain, at_ref)


def test_outside_its_domain_the_correction_fades_and_warns():
    eff = _effect()
    q = np.zeros((3, 6))
    q[:, 3] = [1.9, 2.0 + 0.6 * 2.0, 2.0 + 10 * 0.6 * 2.0]  # inside, one width, ten widths out
    with pytest.warns(OutsideRangeWarning, match="joint 4 at .* outside the domain"):
        d = eff.joint_delta(q, Context())[:, 4]
    edge = q.copy()
    edge[:, 3] = 2.0
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        at_edge = eff.joint_delta(edge, Context())[:, 4]
    assert d[1] == pytest.approx(at_edge[1] * np.exp(-0.5))
    assert abs(d[2]) < 1e-20


def test_cross_validation_finds_a_smooth_function_and_not_noise():
    rng = np.random.default_rng(5)
    n = 60
    u = rng.uniform(-1, 1, (n, 2))
    centres = farthest_points(u, 16)
    phi = np.exp(-0.5 * np.sum((u[:, None] - centres[None]) ** 2, axis=2) / 0.5**2)
    sensitivity = rng.normal(1.0, 0.3, 3 * n)  # how much each coordinate feels the joint
    design = np.repeat(phi, 3, axis=0) * sensitivity[:, None]
    smooth = np.repeat(np.sin(2 * u[:, 0]) * u[:, 1], 3) * sensitivity
    sse = cv_errors(np.stack([design, 0.5 * design]), smooth + rng.normal(0, 0.05, 3 * n),
                    n, 12)
    assert sse.shape == (2, 13)
    assert sse[0].min() < 0.1 * sse[0, 0]  # a smooth function is predicted out of fold
    assert sse[1] == pytest.approx(sse[0])  # and the scale of a design does not matter
    noise = rng.normal(0, 1.0, 3 * n)
    sse = cv_errors(design[None], noise, n, 12)[0]
    assert sse.min() > 0.9 * sse[0]  # noise is not


def test_rewrite_notes_targets_outside_the_domain(tmp_path):
    # the model file holds the correction; a target beyond its domain is compensated
    # (the correction faded) and the rewrite says so
    robot = load_robot("IRB1600-10/1.45")
    eff = _effect(lo=(-0.2, -0.3), hi=(0.2, 0.3))
    save_model(ErrorModel(robot.name, [eff]), tmp_path / "model.json")
    comp = Compensator.load(tmp_path / "model.json")
    q = np.radians([[10.0, 10.0, 10.0, 60.0, 40.0, 5.0]])
    T = robot.fk(q)[0]
    literal = robtarget_literals(T[None], robot.confdata(q), np.full((1, 6), 9e9))[0]
    text = ("MODULE M\n  CONST robtarget p1:=" + literal + ";\n  PROC main()\n"
            "    MoveJ p1, v100, fine, tool0;\n  ENDPROC\nENDMODULE\n")
    with pytest.warns(OutsideRangeWarning, match="outside the domain"):
        out = rewrite_source(text.encode(), "m.mod", comp, RewriteOptions())
    assert out.moves_compensated == 1


def test_the_hose_leaves_every_other_draw_and_the_sweeps_unchanged():
    # an effect added to the simulator must not change existing scenarios
    others = tuple(e for e in EFFECTS if e != "hose_pull")
    for seed in (1, 2, 3):
        plain = VirtualRobot.create(seed=seed, effects=others)
        hose = VirtualRobot.create(seed=seed, effects=(*others, "hose_pull"))
        truth = hose.truth()
        assert truth["errors"].pop("hose_pull")["joint"] == 5
        truth["errors"]["effects"].remove("hose_pull")
        assert json.dumps(truth, sort_keys=True) == json.dumps(plain.truth(), sort_keys=True)
    # no sweep sees it (joints 4 and 6 are held at 0), the points do
    plain, hose = VirtualRobot.create(seed=2), VirtualRobot.create(seed=2, effects=HIDDEN)
    robot = plain.robot
    sweeps = sweep_plan(robot, plain.smr_offset_mm)
    assert np.array_equal(hose.true_joint_error(sweeps.q), plain.true_joint_error(sweeps.q))
    q = point_plan(robot, plain.smr_offset_mm, 30, seed=2)
    extra = hose.true_joint_error(q) - plain.true_joint_error(q)
    assert np.all(extra[:, [0, 1, 2, 3, 5]] == 0.0)
    amp = np.radians(hose.truth()["errors"]["hose_pull"]["amplitude_deg"])
    assert np.allclose(extra[:, 4], amp * np.sin(q[:, 3]) * np.sin(q[:, 5]), atol=1e-15)


@pytest.mark.parametrize("key,value,column", [
    ("width_unit", -1.0, "width_unit"), ("basis", [[1.0]], "basis"),
    ("features", ["q9", "q2"], "features"), ("domain_low", [5.0, 5.0], "domain_low"),
    ("centring", [0.1], "centring"),
])
def test_a_corrupt_correction_in_a_model_file_is_one_line_naming_the_key(key, value, column):
    data = json.loads(json.dumps(_effect().to_dict()))
    data["state"][key] = value
    with pytest.raises(ModelError) as err:
        effect_from_dict(data)
    assert err.value.column == column and "\n" not in str(err.value)
