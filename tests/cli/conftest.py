"""A small measurement set and the model fitted on it, plus helpers to run the CLI.

The set is deliberately small (15° steps, two repeats, few points) so that every
command finishes in seconds; the numbers it gives are not what these tests check.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from rapidfix import pipeline
from rapidfix.error_model.model_file import save_model
from rapidfix.sim import simulate_cell

ROOT = Path(__file__).resolve().parents[2]
SAMPLES = ROOT / "samples"


@pytest.fixture(scope="session")
def small_set(tmp_path_factory):
    """Folder of a small simulated set (setup.toml, sweeps.csv, calibration.csv, …)."""
    return simulate_cell(tmp_path_factory.mktemp("small") / "set", seed=3, repeats=2,
                         step_deg=15.0, n_calibration=20, n_validation=12)


@pytest.fixture(scope="session")
def small_model(small_set, tmp_path_factory):
    """Path of the model fitted on the small set's sweeps."""
    outcome = pipeline.fit_from_files(small_set / "setup.toml", [small_set / "sweeps.csv"])
    return save_model(outcome.model, tmp_path_factory.mktemp("model") / "model.json")


def run_cli(args: list[str], *, memory_bytes: int | None = None, timeout: float = 300.0,
            cwd: Path | None = None) -> subprocess.CompletedProcess:
    """`rapidfix ARGS` in a fresh interpreter (optionally under an address-space limit)."""

    def limit() -> None:
        if memory_bytes is not None:
            import resource

            resource.setrlimit(resource.RLIMIT_AS, (memory_bytes, memory_bytes))

    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1", MKL_NUM_THREADS="1",
               NUMBA_NUM_THREADS="1")
    return subprocess.run(
        [sys.executable, "-c", "import sys; from rapidfix.cli import main; sys.exit(main())",
         *args],
        capture_output=True, text=True, timeout=timeout, preexec_fn=limit, env=env, cwd=cwd)


def one_line_error(stderr: str) -> bool:
    """True when stderr ends with exactly one `rapidfix: error: …` line and no traceback."""
    lines = [line for line in stderr.splitlines() if line.strip()]
    errors = [line for line in lines if line.startswith("rapidfix: error: ")]
    return len(errors) == 1 and "Traceback" not in stderr and lines[-1] == errors[0]
