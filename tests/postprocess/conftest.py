"""Shared fixtures: a virtual cell, a model fitted on its sweeps, the sample programs."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from rapidfix import pipeline
from rapidfix.error_model.model_file import save_model
from rapidfix.postprocess.compensator import Compensator
from rapidfix.sim import VirtualRobot, simulate_cell

SAMPLES = Path(__file__).resolve().parents[2] / "samples"
SEED = 11


@pytest.fixture(scope="session")
def cell(tmp_path_factory):
    """A simulated cell with per-joint errors, and the model fitted on its sweeps only."""
    root = tmp_path_factory.mktemp("cell")
    folder = simulate_cell(root / "measurements", seed=SEED)
    truth = json.loads((folder / "truth.json").read_text(encoding="utf-8"))
    outcome = pipeline.fit_from_files(folder / "setup.toml", [folder / "sweeps.csv"])
    model_path = save_model(outcome.model, root / "model.json")
    return {
        "virtual": VirtualRobot.from_truth(truth),
        "model_path": model_path,
        "model": outcome.model,
        "robot": outcome.robot,
    }


@pytest.fixture(scope="session")
def comp(cell):
    """The post-processor's robot + model, loaded once."""
    return Compensator.load(cell["model_path"])


@pytest.fixture(scope="session")
def samples():
    """The folder of sample programs."""
    return SAMPLES
