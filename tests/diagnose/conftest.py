"""Shared virtual-cell scenarios for the diagnosis tests (cached per process).

A scenario: a virtual robot (rapidfix.sim, written independently of the error
model) with per-joint errors and some hidden effects, its measurement session,
the per-joint model fitted on its sweeps only, and the diagnosis on its
calibration and validation points.
"""

from __future__ import annotations

import os
import tempfile
import warnings
from functools import cache
from types import SimpleNamespace

import numpy as np
import pytest

from rapidfix.demo import measured_range, pick_and_place, run_on_robot
from rapidfix.diagnose.run import diagnose
from rapidfix.error_model.fit import fit_error_model
from rapidfix.error_model.joint_rbf import OutsideRangeWarning
from rapidfix.error_model.model_file import save_model
from rapidfix.measure.registration import rigid_fit
from rapidfix.measure.sweeps import analyse_sweeps
from rapidfix.postprocess.compensator import Compensator
from rapidfix.postprocess.rewrite import RewriteOptions, rewrite_source
from rapidfix.sim import VirtualRobot, simulate_set
from rapidfix.sim.virtual_robot import RunConditions


def scenario(effects: tuple[str, ...], seed: int, n_calibration: int = 60, balls: int = 2):
    """(simulated set, per-joint model, diagnosis) for hidden `effects` and `seed`; the
    points measured on `balls` nests of the flange (the simulator's default: 2)."""
    return _scenario(tuple(effects), int(seed), int(n_calibration), int(balls))


@cache
def _scenario(effects: tuple[str, ...], seed: int, n_calibration: int, balls: int):
    data = simulate_set(seed=seed, effects=effects, n_calibration=n_calibration, balls=balls)
    robot = data.robot.robot
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", OutsideRangeWarning)
        analysis = analyse_sweeps(data.setup, data.sweeps, robot)
        model = fit_error_model(
            robot.name,
            list(analysis.joints),
            extra_statistics={"sweep_analysis": analysis.report()},
        )
        result = diagnose(model, robot, data.setup, data.calibration, data.validation)
    return data, model, result


@cache
def hidden_size_mm(effects: tuple[str, ...], seed: int) -> float:
    """Mean displacement (mm) the hidden effects cause on the validation poses of a
    session, beyond what a rigid move of the tracker could absorb (noise-free truth)."""
    data = simulate_set(seed=seed, effects=effects, n_calibration=20, n_validation=40)
    table = data.validation
    ctx = RunConditions(
        payload_kg=table.payload_kg,
        time_s=table.time_s,
        temp_c=table.temp_c,
        q_prev=np.vstack([table.q[:1], table.q[:-1]]),
    )
    plain = VirtualRobot.create(seed=seed, effects=())
    with_it = data.robot.measure(table.q, ctx, noise=False, frame="tracker")
    without = plain.measure(table.q, ctx, noise=False, frame="tracker")
    R, t = rigid_fit(without, with_it)
    return float(np.linalg.norm(without @ R.T + t - with_it, axis=1).mean())


def detectable_seeds(
    effects: tuple[str, ...],
    count: int,
    *,
    floor_mm: float = 0.024,
    factor: float = 2.0,
    candidates: range = range(1, 40),
) -> list[int]:
    """The first `count` seeds whose hidden effect moves the ball by at least
    `factor` × the noise floor: an effect smaller than the noise cannot be named."""
    seeds: list[int] = []
    for seed in candidates:  # in order, and no further than needed (each costs a session)
        if len(seeds) == count:
            break
        if hidden_size_mm(effects, seed) >= factor * floor_mm:
            seeds.append(seed)
    return seeds


def loop(effects: tuple[str, ...], seed: int, n_calibration: int = 60, *,
         approach: bool = True):
    """The loop on the robot for a scenario: its diagnosed model saved and loaded, a
    pick-and-place program (within the measured joint ranges) rewritten with it and
    run, as written and as rewritten, on the scenario's virtual robot.

    Returns (diagnosis, rewrite result, run before, run after, noise floor mm); the
    runs are scored in the best joint-1 gauge of each (`align_axis1`).
    """
    data, _model, result = scenario(effects, seed, n_calibration)
    robot = data.robot.robot
    path = os.path.join(tempfile.mkdtemp(), "model.json")
    save_model(result.model, path)
    comp = Compensator.load(path)
    program = pick_and_place(robot, seed, smr_offset_mm=data.setup.smr_offset_mm,
                             ranges=measured_range(comp.model))
    temp = None if data.validation.temp_c is None else float(np.mean(data.validation.temp_c))
    rewritten = rewrite_source(program.text.encode(), "loop.mod", comp,
                               RewriteOptions(temperature_c=temp, approach=approach))
    vr = data.robot
    before = run_on_robot(vr, program, program.text, set(), temp)
    after = run_on_robot(vr, program, rewritten.data.decode(), rewritten.inserted, temp)
    floor = vr.noise_floor(program.q)["mean_tcp_error_mm"]
    return result, rewritten, before, after, floor


def check_on_robot(effects: tuple[str, ...], seed: int, n_calibration: int = 60, *,
                   limit: float = 1.5) -> float:
    """The diagnosed model compensates a real program: every move compensated, the
    robot lands within `limit` × the noise floor having started far off, and the
    error the model predicts for the program as written is the executed one.

    The prediction is in the model's base frame, registered with joint 1's error zero
    at 0° (the sweeps' gauge): it is compared with the program as written run on the
    robot and taken in that gauge (the truth states joint 1's error there), not in
    each run's best joint-1 gauge, which would absorb part of an error that grows with
    height (thermal growth).
    Returns the mean error after, in units of the noise floor."""
    _, rewritten, before, after, floor = loop(effects, seed, n_calibration)
    assert rewritten.moves_compensated == rewritten.moves_total, rewritten.report_lines()
    assert after.mean_mm <= limit * floor, (effects, seed, after.mean_mm, floor)
    assert before.mean_mm > 4 * floor, (effects, seed, before.mean_mm, floor)
    assert rewritten.worst_predicted_mm < 1e-3
    predicted = rewritten.predicted_before_mm[0]
    executed = _as_written_in_the_model_gauge(effects, seed, n_calibration)
    assert abs(predicted - executed) <= 0.25 * executed + 2 * floor, (
        effects, seed, predicted, executed)
    return after.mean_mm / floor


def _as_written_in_the_model_gauge(effects: tuple[str, ...], seed: int,
                                   n_calibration: int) -> float:
    """Mean TCP error (mm) of the program as written, run on the scenario's robot, in the
    gauge of its truth (joint 1's error zero at 0°)."""
    data, _model, result = scenario(effects, seed, n_calibration)
    vr = data.robot
    program = pick_and_place(vr.robot, seed, smr_offset_mm=data.setup.smr_offset_mm,
                             ranges=measured_range(result.model))
    temp = None if data.validation.temp_c is None else float(np.mean(data.validation.temp_c))
    zero = np.radians(data.truth["gauge"]["joint1_error_at_zero_deg"])
    return run_on_robot(vr, program, program.text, set(), temp,
                        joint1_zero_rad=zero).mean_mm


@pytest.fixture(scope="session")
def cell():
    """The scenario helpers: `cell.scenario(effects, seed)`, `cell.detectable_seeds(...)`,
    `cell.loop(...)` and `cell.check_on_robot(...)` (the loop on the robot)."""
    return SimpleNamespace(scenario=scenario, detectable_seeds=detectable_seeds, loop=loop,
                           check_on_robot=check_on_robot)
