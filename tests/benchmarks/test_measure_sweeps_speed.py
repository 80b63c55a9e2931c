"""Benchmark: the sweep analysis's Gauss–Newton solve against scipy's least_squares.

Run (one core):
    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 \
    pytest tests/benchmarks/test_measure_sweeps_speed.py -n 0 -s

The same problem (residuals and sparse Jacobian of rapidfix.measure.sweeps) is
solved to convergence by the project's sparse Gauss–Newton and, as the baseline,
by scipy.optimize.least_squares (trf, lsmr, the textbook choice for a sparse
Jacobian) in the same process; prints both times, their ratio and how far apart
the two answers are.
"""

from __future__ import annotations

import time

import numpy as np
from scipy.optimize import least_squares

from rapidfix.measure import sweeps as S
from rapidfix.measure.registration import register
from rapidfix.sim import simulate_set


def _problem(step_deg: float):
    data = simulate_set(3, step_deg=step_deg, n_calibration=5, n_validation=5)
    robot, setup, table = data.robot.robot, data.setup, data.sweeps
    prob = S._index(table)
    initial = register(S._ball(robot, table.q, setup.smr_offset_mm), table.xyz)
    solver = S._Solver(
        table, robot, setup.smr_offset_mm, prob, initial.R, setup.tracker_sigma_mm, np.radians(5.0)
    )
    x0 = np.zeros(6 + solver.n_free)
    x0[3:6] = initial.t
    return solver, x0, np.arange(len(table))


def test_gauss_newton_against_least_squares():
    for step in (5.0, 2.0):
        for robust in (False, True):
            solver, x0, rows = _problem(step)
            R0 = solver.R0.copy()
            t0 = time.perf_counter()
            x_gn = solver.solve(x0, rows, robust=robust)
            t_gn = time.perf_counter() - t0
            cost_gn = solver.cost(solver.residuals(x_gn, rows), robust)
            solver.R0 = R0
            t0 = time.perf_counter()
            result = least_squares(
                solver.residuals,
                x0,
                jac=solver.jacobian,
                args=(rows,),
                method="trf",
                tr_solver="lsmr",
                x_scale="jac",
                loss="soft_l1" if robust else "linear",
                f_scale=S.ROBUST_SCALE,
                ftol=1e-12,
                xtol=1e-12,
                gtol=1e-12,
            )
            t_ls = time.perf_counter() - t0
            gap = np.degrees(np.max(np.abs(x_gn[6:] - result.x[6:])))
            print(
                f"\n{len(rows)} rows, {solver.n_free} joint unknowns, "
                f"{'soft-L1' if robust else 'linear'} loss: Gauss–Newton {t_gn:.3f} s "
                f"(cost {cost_gn:.3f}), least_squares {t_ls:.3f} s (cost {result.cost:.3f}, "
                f"{result.nfev} evaluations); speed-up ×{t_ls / t_gn:.1f}; "
                f"largest Δθ difference {gap:.2e}°"
            )
            assert cost_gn <= result.cost * (1 + 1e-6)
