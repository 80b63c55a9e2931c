"""Shared virtual-cell scenarios for the diagnosis tests (cached per process).

A scenario: a virtual robot (rapidfix.sim, written independently of the error
model) with per-joint errors and some hidden effects, its measurement session,
the per-joint model fitted on its sweeps only, and the diagnosis on its
calibration and validation points.
"""

from __future__ import annotations

import warnings
from functools import cache
from types import SimpleNamespace

import numpy as np
import pytest

from rapidfix.diagnose.run import diagnose
from rapidfix.errors.fit import fit_error_model
from rapidfix.errors.joint_rbf import OutsideRangeWarning
from rapidfix.measure.registration import rigid_fit
from rapidfix.measure.sweeps import analyse_sweeps
from rapidfix.sim import VirtualRobot, simulate_set
from rapidfix.sim.virtual_robot import RunConditions


def scenario(effects: tuple[str, ...], seed: int, n_calibration: int = 60):
    """(simulated set, per-joint model, diagnosis) for hidden `effects` and `seed`."""
    return _scenario(tuple(effects), int(seed), int(n_calibration))


@cache
def _scenario(effects: tuple[str, ...], seed: int, n_calibration: int):
    data = simulate_set(seed=seed, effects=effects, n_calibration=n_calibration)
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


@pytest.fixture(scope="session")
def cell():
    """The scenario helpers: `cell.scenario(effects, seed)`, `cell.detectable_seeds(...)`."""
    return SimpleNamespace(scenario=scenario, detectable_seeds=detectable_seeds)
