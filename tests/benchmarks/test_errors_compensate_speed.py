"""Benchmark: compensating 100,000 poses with a fitted per-joint model.

Run (one core):
    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 \
    pytest tests/benchmarks/test_errors_compensate_speed.py -n 0 -s

The vectorised per-joint Newton solve and the general solve (damped Newton on
the full forward model) are timed against a baseline measured in the same
process: scipy.optimize.brentq solving θc + Δθ(θc) = θ_ideal one joint of one
pose at a time, on a sample. The printed ratios compare poses per second.
Correctness is asserted (all three agree); no time is asserted.
"""

import time

import numpy as np
from scipy.optimize import brentq

from rapidfix.error_model.compensate import solve_general, solve_per_joint
from rapidfix.error_model.joint_rbf import JointRBF, fit_network
from rapidfix.error_model.model import ErrorModel
from rapidfix.kinematics import load_robot

N = 100_000
N_BASELINE = 300
N_GENERAL = 20_000


def test_compensation_speed():
    robot = load_robot("IRB1600-10/1.45")
    rng = np.random.default_rng(0)
    nets = []
    for j in range(6):
        lo, hi = robot.limits[j]
        x = np.arange(lo, hi + 1e-12, np.radians(5.0))
        y = np.radians(0.02 * np.sin(3 * x + j) + 0.01 * np.cos(7 * x) + 0.005 * j)
        nets.append(fit_network(x, y)[0])
    model = ErrorModel(robot.name, [JointRBF(nets)])
    q = rng.uniform(robot.limits[:, 0] * 0.9, robot.limits[:, 1] * 0.9, (N, 6))
    q[:, 4] = np.where(np.abs(q[:, 4]) < 0.1, 0.5, q[:, 4])

    t0 = time.perf_counter()
    per_joint = solve_per_joint(model, q)
    t_vec = time.perf_counter() - t0
    assert per_joint.converged.all()

    t0 = time.perf_counter()
    general = solve_general(model, robot, q[:N_GENERAL])
    t_gen = time.perf_counter() - t0
    assert general.converged.all()
    assert np.degrees(np.abs(general.q_cmd - per_joint.q_cmd[:N_GENERAL])).max() < 1e-7

    def delta_j(j, value):
        row = np.zeros((1, 6))
        row[0, j] = value
        return model.delta(row)[0, j]

    sample = q[:N_BASELINE]
    t0 = time.perf_counter()
    base = np.empty_like(sample)
    for i in range(N_BASELINE):
        for j in range(6):
            target = sample[i, j]
            base[i, j] = brentq(lambda x, j=j, t=target: x + delta_j(j, x) - t,
                                target - 0.01, target + 0.01, xtol=1e-14)
    t_base = time.perf_counter() - t0
    assert np.degrees(np.abs(base - per_joint.q_cmd[:N_BASELINE])).max() < 1e-9

    rate_vec, rate_gen, rate_base = N / t_vec, N_GENERAL / t_gen, N_BASELINE / t_base
    print(f"\nper-joint Newton: {rate_vec:12.0f} poses/s ({per_joint.iterations} iterations)")
    print(f"general solve:    {rate_gen:12.0f} poses/s ({general.iterations} iterations)")
    print(f"baseline brentq:  {rate_base:12.0f} poses/s (one joint at a time)")
    print(f"ratio per-joint / baseline: {rate_vec / rate_base:.0f}x; "
          f"general / baseline: {rate_gen / rate_base:.0f}x")
