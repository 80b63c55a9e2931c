"""`rapidfix fit` and `rapidfix demo` end to end, through the command line."""

import json

import numpy as np

from rapidfix.cli import main
from rapidfix.commands.demo import claim_output
from rapidfix.digest import sha256_file
from rapidfix.error_model.model_file import load_model
from rapidfix.sim import VirtualRobot, simulate_cell


def test_fit_writes_a_model_of_the_sweeps_and_prints_the_summary(tmp_path, capsys):
    cell = simulate_cell(tmp_path / "cell", seed=5)
    out = tmp_path / "model.json"
    status = main(["fit", str(cell / "setup.toml"), str(cell / "sweeps.csv"), "-o", str(out),
                   "--validation", str(cell / "validation.csv"), "--report", str(tmp_path / "r")])
    printed = capsys.readouterr().out
    assert status == 0
    assert "CV RMS" in printed and f"wrote {out}" in printed
    # validation points the fit never saw: the model explains the measured error
    val = json.loads((tmp_path / "r" / "report.json").read_text())["summary"]["validation"]
    assert val["after"]["mean_mm"] < 0.15 * val["before"]["mean_mm"]
    assert "joint_errors" in (tmp_path / "r" / "report.json").read_text()
    model = load_model(out, "IRB1600-10/1.45")
    hashes = {d["name"]: d["sha256"] for d in model.data_files}
    assert hashes["sweeps.csv"] == sha256_file(cell / "sweeps.csv")
    assert [s["joint"] for s in model.statistics["joints"]] == [1, 2, 3, 4, 5, 6]
    # the fitted curve reproduces the truth of joint 3 (no gauge freedom there)
    robot = VirtualRobot.from_truth(json.loads((cell / "truth.json").read_text()))
    q = np.zeros((50, 6))
    q[:, 2] = np.radians(np.linspace(-60, 40, 50))
    true_d3 = np.degrees(robot.true_joint_error(q)[:, 2])
    assert np.abs(np.degrees(model.delta(q)[:, 2]) - true_d3).max() < 0.003


def test_fit_refuses_a_missing_file_with_one_line(tmp_path, capsys):
    status = main(["fit", str(tmp_path / "setup.toml"), str(tmp_path / "s.csv"), "-o",
                   str(tmp_path / "m.json")])
    err = capsys.readouterr().err
    assert status == 1 and err.count("\n") == 1 and "setup.toml" in err


def test_demo_runs_end_to_end_and_only_replaces_its_own_output(tmp_path, capsys):
    out = tmp_path / "demo"
    assert main(["demo", "--out", str(out), "--seed", "4"]) == 0
    printed = capsys.readouterr().out
    assert str(out / "report.html") in printed
    doc = json.loads((out / "report.json").read_text())
    val = doc["summary"]["validation"]
    assert val["after"]["mean_mm"] < 0.2 * val["before"]["mean_mm"]
    bb = doc["summary"]["ballbar"]
    assert bb["after"]["mean_mm"] * 3 < bb["before"]["mean_mm"]
    assert load_model(out / "model.json").robot == "IRB1600-10/1.45"
    # a later demo may replace its own previous output
    claim_output(out)
    # a folder someone else filled is refused
    other = tmp_path / "mine"
    other.mkdir()
    (other / "notes.txt").write_text("keep me")
    capsys.readouterr()
    assert main(["demo", "--out", str(other)]) == 1
    assert "not written by `rapidfix demo`" in capsys.readouterr().err
    assert (other / "notes.txt").read_text() == "keep me"


def test_fit_accepts_the_sweeps_split_over_several_files(tmp_path):
    from dataclasses import replace

    from rapidfix.measure.files import read_sweeps, write_sweeps

    cell = simulate_cell(tmp_path / "cell", seed=6)
    table = read_sweeps(cell / "sweeps.csv")
    parts = []
    for name, joints in (("arm.csv", (0, 1, 2)), ("wrist.csv", (3, 4, 5))):
        keep = np.isin(table.sweep_joint, joints)
        sub = replace(table, **{f: getattr(table, f)[keep]
                                for f in ("sweep_joint", "q", "repeat", "xyz", "rows")})
        parts.append(str(write_sweeps(tmp_path / name, sub)))
    one, two = tmp_path / "one.json", tmp_path / "two.json"
    setup = str(cell / "setup.toml")
    assert main(["fit", setup, str(cell / "sweeps.csv"), "-o", str(one)]) == 0
    assert main(["fit", setup, *parts, "-o", str(two)]) == 0
    q = np.radians(np.random.default_rng(1).uniform(-60, 60, (100, 6)))
    diff = load_model(one).delta(q) - load_model(two).delta(q)
    assert np.degrees(np.abs(diff)).max() < 1e-6
    assert [d["name"] for d in load_model(two).data_files] == ["setup.toml", "arm.csv",
                                                                "wrist.csv"]


def test_validation_points_outside_the_swept_range_are_warned_about(tmp_path, capsys):
    from dataclasses import replace

    from rapidfix.measure.files import read_sweeps, write_sweeps

    cell = simulate_cell(tmp_path / "cell", seed=7)
    table = read_sweeps(cell / "sweeps.csv")
    keep = (table.sweep_joint != 0) | (np.abs(table.q[:, 0]) <= np.radians(90.0))
    short = replace(table, **{f: getattr(table, f)[keep]
                              for f in ("sweep_joint", "q", "repeat", "xyz", "rows")})
    sweeps = write_sweeps(tmp_path / "short.csv", short)
    status = main(["fit", str(cell / "setup.toml"), str(sweeps), "-o", str(tmp_path / "m.json"),
                   "--validation", str(cell / "validation.csv")])
    captured = capsys.readouterr()
    assert status == 3
    assert captured.err.count("rapidfix: warning: joint 1 at") == 1
    assert "[-90.000°, 90.000°]" in captured.err
