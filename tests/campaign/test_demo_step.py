"""The campaign step of `rapidfix demo`: the cube, compensated with the demo's model."""

from __future__ import annotations

from rapidfix import pipeline
from rapidfix.demo import demo_campaign, format_campaign
from rapidfix.error_model.model_file import save_model
from rapidfix.sim import simulate_cell


def test_demo_cube_is_compensated_to_the_noise_floor(tmp_path):
    simulate_cell(tmp_path / "cell", seed=2, n_calibration=4, n_validation=4)
    outcome = pipeline.fit_from_files(tmp_path / "cell/setup.toml", [tmp_path / "cell/sweeps.csv"])
    model = save_model(outcome.model, tmp_path / "model.json")
    result = demo_campaign(tmp_path / "campaign", model, seed=2)
    floor = result["noise_floor_mm"]
    assert max(p["AP_mm"] for p in result["after"]["poses"]) <= 2 * floor
    assert min(p["AP_mm"] for p in result["before"]["poses"]) > 2 * floor
    assert "AP P1..P5 after" in format_campaign(result)
    assert (tmp_path / "campaign/set_after/iso9283.csv").exists()
