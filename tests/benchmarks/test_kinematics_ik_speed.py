"""Benchmark: all-branch analytic IK for 1,000,000 poses on one core.

Run (one core):
    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 \
    pytest tests/benchmarks/test_kinematics_ik_speed.py -n 0 -s

Poses come from random joints inside the IRB 1600 limits (forward kinematics is
not timed). The batch is solved in chunks to bound memory: every chunk returns
all slots (8 branches × whole-turn variants) with limits checked and statuses.
The baseline is modern_robotics' IKinSpace (a general numeric Newton IK, one
solution per call from a seed 0.1 rad off) on a sample of the same poses, timed
in the same process; the printed ratio compares poses per second. The closed-form
core alone (eight branches, no whole-turn variants, limits or statuses) is timed
on the first chunks too, to show where the time goes.
"""

import time

import numpy as np

from rapidfix.kinematics import IKStatus, load_robot
from rapidfix.kinematics.ik_analytic import analytic_solver

N_POSES = 1_000_000
CHUNK = 20_000
BASELINE_SAMPLE = 300


def test_all_branch_ik_speed_against_modern_robotics():
    import modern_robotics as mr

    robot = load_robot("IRB1600-10/1.45")
    lo, hi = robot.limits[:, 0], robot.limits[:, 1]
    rng = np.random.default_rng(2024)
    seconds, core_seconds, core_poses, solved, slots = 0.0, 0.0, 0, 0, 0
    first_q = first_T = None
    core = analytic_solver(robot)
    for i in range(N_POSES // CHUNK):
        q = rng.uniform(lo, hi, (CHUNK, 6))
        T = robot.fk(q)
        if first_T is None:
            first_q, first_T = q, T
        start = time.perf_counter()
        sols = robot.ik(T)
        seconds += time.perf_counter() - start
        if i < 5:
            start = time.perf_counter()
            core.base_branches(T, np.zeros((CHUNK, 6)), 1e-7)
            core_seconds += time.perf_counter() - start
            core_poses += CHUNK
        solved += int(np.isin(sols.status, [IKStatus.OK, IKStatus.WRIST_SINGULAR]).sum())
        slots = sols.q.shape[1]
    ours = N_POSES / seconds

    # Baseline on a sample of the same poses, same process.
    Slist = np.asarray(robot.screws).T  # columns (w, v)
    M = np.asarray(robot.home)
    seeds = first_q[:BASELINE_SAMPLE] + rng.uniform(-0.1, 0.1, (BASELINE_SAMPLE, 6))
    start = time.perf_counter()
    converged = 0
    for T, seed in zip(first_T[:BASELINE_SAMPLE], seeds):
        _, ok = mr.IKinSpace(Slist, M, T, seed, 1e-9, 1e-6)
        converged += bool(ok)
    theirs = BASELINE_SAMPLE / (time.perf_counter() - start)

    print(
        f"\nrapidfix all-branch IK: {N_POSES} poses in {seconds:.2f} s = {ours:,.0f} poses/s "
        f"({slots} slots per pose, chunks of {CHUNK})"
        f"\nclosed-form core alone (8 branches): {core_poses / core_seconds:,.0f} poses/s"
        f"\nmodern_robotics IKinSpace: {theirs:,.0f} poses/s (one solution per call, "
        f"{converged}/{BASELINE_SAMPLE} converged)"
        f"\nratio: {ours / theirs:,.0f}x"
    )
    assert solved == N_POSES  # every pose came from joints inside the limits
