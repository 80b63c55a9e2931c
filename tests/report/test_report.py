"""Report: statistics against hand-computed values, HTML/JSON content, figures render."""

import base64
import json
import re

import numpy as np
import pytest

from rapidfix.report.accuracy import BallbarRun, BeforeAfter, accuracy_report
from rapidfix.report.document import write_report
from rapidfix.report.metrics import (
    PAPER_BALLBAR_MM,
    ballbar_deviation,
    ballbar_stats,
    position_error_stats,
)


def test_position_error_stats_by_hand():
    intended = np.zeros((2, 3))
    reached = np.array([[3.0, 4.0, 0.0], [0.0, 0.0, -1.0]])
    s = position_error_stats(intended, reached)
    assert s["mean_mm"] == pytest.approx(3.0)
    assert s["rms_mm"] == pytest.approx(np.sqrt((25 + 1) / 2))
    assert s["max_mm"] == pytest.approx(5.0)
    assert s["per_axis"]["z"] == pytest.approx({"mean_mm": -0.5, "rms_mm": np.sqrt(0.5),
                                                "max_abs_mm": 1.0})


def test_ballbar_deviation_on_a_known_circle():
    angles = np.radians(np.arange(0, 181, 10))
    centre = np.array([800.0, 100.0, 600.0])
    radius = 150.0
    r = radius + 0.1 * np.cos(angles)  # a circle squashed by ±0.1 mm
    pts = centre + np.column_stack([r * np.cos(angles), r * np.sin(angles), 0 * angles])
    dev = ballbar_deviation(pts, centre, radius)
    assert dev == pytest.approx(0.1 * np.cos(angles), abs=1e-9)
    s = ballbar_stats(dev)
    assert s["max_mm"] == pytest.approx(0.1)
    assert s["mean_mm"] == pytest.approx(np.mean(np.abs(0.1 * np.cos(angles))))


def _report():
    rng = np.random.default_rng(0)
    intended = rng.uniform(-1000, 1000, (40, 3))
    before = intended + rng.normal(0, 0.3, (40, 3))
    after = intended + rng.normal(0, 0.03, (40, 3))
    theta = np.arange(-90.0, 91.0, 5.0)
    curves = [None] * 6
    curves[1] = {"theta": theta, "delta": 0.02 * np.sin(np.radians(theta)),
                 "repeat_std": np.full(theta.shape, 0.001),
                 "curve_theta": np.linspace(-90, 90, 200),
                 "curve_delta": 0.02 * np.sin(np.radians(np.linspace(-90, 90, 200)))}
    angle = np.arange(0.0, 181.0, 15.0)
    ballbar = BallbarRun(angle, 0.3 * np.sin(np.radians(angle)), 0.03 * np.cos(angle))
    stats = [{"joint": j + 1, "points": 0} for j in range(6)]
    stats[1] = {"joint": 2, "points": 37, "range_deg": [-90.0, 90.0], "max_abs_error_deg": 0.02,
                "cv_rms_deg": 0.0004, "repeatability_deg": 0.001, "width_deg": 10.0}
    return accuracy_report("test <report>", joint_stats=stats, joint_curves=curves,
                           validation=BeforeAfter(intended, before, after), ballbar=ballbar)


def test_report_html_embeds_every_figure_and_json_carries_the_data(tmp_path):
    report = _report()
    html_path, json_path = write_report(report, tmp_path)
    page = html_path.read_text()
    assert "test &lt;report&gt;" in page  # escaped
    images = re.findall(r'src="data:image/png;base64,([^"]+)"', page)
    assert len(images) == 3
    assert all(base64.b64decode(img).startswith(b"\x89PNG\r\n\x1a\n") for img in images)
    doc = json.loads(json_path.read_text())
    assert set(doc["figures"]) == {"validation_errors", "ballbar", "joint_errors"}
    fig = doc["figures"]["joint_errors"]["data"]
    assert fig["joint_1"] is None and len(fig["joint_2"]["theta"]) == 37
    val = doc["summary"]["validation"]
    assert val["after"]["mean_mm"] < val["before"]["mean_mm"]
    assert doc["summary"]["ballbar"]["paper"] == PAPER_BALLBAR_MM
    assert len(doc["figures"]["validation_errors"]["data"]["before_xyz_mm"]) == 40
    rows = {t["title"].split(" ")[0]: t for t in doc["tables"]}
    assert rows["TCP"]["rows"][0][1] == pytest.approx(val["before"]["mean_mm"])


def test_figures_are_drawn_when_first_read_and_once(monkeypatch):
    """Building a report draws nothing (a diagnosis through the API never pays for it);
    reading a figure's PNG draws it once."""
    from rapidfix.report import figures

    drawn = []
    plain = figures.png_bytes
    monkeypatch.setattr(figures, "png_bytes", lambda fig: drawn.append(fig) or plain(fig))
    report = _report()
    assert drawn == []
    first = report.figures[0]
    assert first.png.startswith(b"\x89PNG\r\n\x1a\n")
    assert first.png is first.png
    assert drawn == [first.drawing]
