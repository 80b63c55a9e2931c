"""Benchmark: all-branch analytic IK for 1,000,000 poses on one core.

Run (one core; numba optional, `pip install -e .[bench]` brings it and the baseline):
    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 MKL_NUM_THREADS=1 NUMBA_NUM_THREADS=1 \
    pytest tests/benchmarks/test_kinematics_ik_speed.py -n 0 -s

Poses come from random joints inside the IRB 1600 limits (forward kinematics is
not timed). Each chunk of poses goes through `solve_all`, the code behind
`RobotModel.ik`: rigidity check, the eight closed-form branches, every angle
wrapped into its axis's range, the whole-turn variants within the limits (a bit
mask per axis and branch) and a status per pose. That compact result is every
solution; `IKSolutions.q` / `.valid` expand it to all 96 slots on demand, which
is timed separately on one chunk. Both closed-form backends are timed: numpy
always, the numba kernel when numba is installed. Times are CPU seconds of this
process (`time.process_time`, one thread), so a busy machine slows but does not
inflate them; wall-clock rates are printed too.

The baseline is modern_robotics' IKinSpace (a general numeric Newton IK, one
solution per call from a seed 0.1 rad off) on a sample of the same poses, timed
the same way in the same process; the ratio compares poses per second.
"""

import time

import numpy as np

from rapidfix.kinematics import IKStatus, load_robot
from rapidfix.kinematics.ik import accelerated, solve_all

N_POSES = 1_000_000
CHUNK = 50_000
BASELINE_SAMPLE = 300


def _timed(fn):
    cpu, wall = time.process_time(), time.perf_counter()
    result = fn()
    return result, time.process_time() - cpu, time.perf_counter() - wall


def test_all_branch_ik_speed_against_modern_robotics():
    import modern_robotics as mr

    robot = load_robot("IRB1600-10/1.45")
    lo, hi = robot.limits[:, 0], robot.limits[:, 1]
    backends = ["numpy", "numba"] if accelerated() else ["numpy"]
    rng = np.random.default_rng(2024)
    warm = robot.fk(rng.uniform(lo, hi, (100, 6)))
    for backend in backends:  # compile / load the numba kernel before timing
        solve_all(robot, warm, backend=backend)

    cpu = dict.fromkeys(backends, 0.0)
    wall = dict.fromkeys(backends, 0.0)
    solved = dict.fromkeys(backends, 0)
    first_q = first_T = None
    for _ in range(N_POSES // CHUNK):
        q = rng.uniform(lo, hi, (CHUNK, 6))
        T = robot.fk(q)
        if first_T is None:
            first_q, first_T = q, T
        results = {}
        for backend in backends:
            sols, c, w = _timed(lambda b=backend, poses=T: solve_all(robot, poses, backend=b))
            assert sols.backend == backend
            cpu[backend] += c
            wall[backend] += w
            solved[backend] += int(
                np.isin(sols.status, [IKStatus.OK, IKStatus.WRIST_SINGULAR]).sum()
            )
            results[backend] = sols
        if len(results) == 2:  # the two closed forms agree (checked, not timed)
            a, b = results["numpy"], results["numba"]
            assert np.array_equal(a.status, b.status) and np.array_equal(a.reachable, b.reachable)
            # (to 1e-6 rad: near the fully stretched arm θ3 is fixed only to ~√ε)
            assert np.nanmax(np.abs(np.angle(np.exp(1j * (a.base_q - b.base_q))))) < 1e-6

    # Expanding the compact result into all 96 slots (what `.q` / `.valid` do on demand).
    sols = solve_all(robot, first_T, backend=backends[-1])
    _, expand_cpu, _ = _timed(lambda: (sols.q, sols.valid, sols.singular))
    slots = sols.q.shape[1]

    # Baseline on a sample of the same poses, same process, same timer.
    Slist = np.asarray(robot.screws).T  # columns (w, v)
    M = np.asarray(robot.home)
    seeds = first_q[:BASELINE_SAMPLE] + rng.uniform(-0.1, 0.1, (BASELINE_SAMPLE, 6))

    def baseline():
        return sum(
            bool(mr.IKinSpace(Slist, M, T, seed, 1e-9, 1e-6)[1])
            for T, seed in zip(first_T[:BASELINE_SAMPLE], seeds)
        )

    converged, base_cpu, base_wall = _timed(baseline)
    theirs = BASELINE_SAMPLE / base_cpu

    lines = [f"\nall-branch IK, IRB 1600, {N_POSES:,} poses in chunks of {CHUNK:,}, one thread:"]
    for backend in backends:
        rate = N_POSES / cpu[backend]
        lines.append(
            f"  {backend:5s}: {rate:>12,.0f} poses/s CPU ({N_POSES / wall[backend]:,.0f} wall), "
            f"{1e6 / rate:.2f} µs/pose, {rate / theirs:,.0f}x IKinSpace"
        )
    lines += [
        f"  expanding one chunk to all {slots} slots (.q, .valid, .singular): "
        f"{CHUNK / expand_cpu:,.0f} poses/s on top",
        f"  modern_robotics IKinSpace: {theirs:,.0f} poses/s CPU "
        f"({BASELINE_SAMPLE / base_wall:,.0f} wall; one solution per call, "
        f"{converged}/{BASELINE_SAMPLE} converged)",
    ]
    print("\n".join(lines))
    for backend in backends:
        assert solved[backend] == N_POSES  # every pose came from joints inside the limits
