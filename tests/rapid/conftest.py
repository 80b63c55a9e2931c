"""Fixtures shared by the RAPID layer tests."""

from __future__ import annotations

from pathlib import Path

import pytest

SAMPLES = Path(__file__).resolve().parents[2] / "samples"


@pytest.fixture
def rapid_samples() -> list[Path]:
    """Every RAPID program in samples/."""
    return sorted(p for p in SAMPLES.iterdir() if p.suffix.lower() in (".mod", ".prg", ".sys"))
