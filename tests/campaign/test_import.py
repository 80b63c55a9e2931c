"""`rapidfix import`: exports of every common shape, and every fault named by row and column."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from rapidfix.campaign.tracker_export import read_export
from rapidfix.cli import main
from rapidfix.measure.files import read_points, read_setup, read_sweeps


@pytest.fixture(scope="module")
def campaign(tmp_path_factory) -> Path:
    root = tmp_path_factory.mktemp("campaign")
    assert main(["plan", str(root / "plan"), "--joints", "2,3", "--step", "10", "--repeats",
                 "2", "--calibration-points", "8", "--validation-points", "6",
                 "--trigger", "tpwrite", "--payload", "0,4"]) == 0
    assert main(["simulate", str(root / "run"), "--program", str(root / "plan/measure.mod"),
                 "--poses", str(root / "plan/poses.csv"), "--export-format", "timed",
                 "--seed", "5"]) == 0
    return root


def lines(path: Path) -> list[str]:
    return path.read_text().splitlines()


def run_import(campaign: Path, export: Path, out: Path, *extra: str) -> int:
    return main(["import", str(export), "--poses", str(campaign / "plan/poses.csv"),
                 "-o", str(out), *extra])


def test_clean_export_gives_the_measurement_files_in_execution_order(campaign, tmp_path):
    assert run_import(campaign, campaign / "run/tracker_export.csv", tmp_path) == 0
    sweeps = read_sweeps(tmp_path / "sweeps.csv")
    cal = read_points(tmp_path / "calibration.csv")
    val = read_points(tmp_path / "validation.csv")
    setup = read_setup(tmp_path / "setup.toml")
    assert setup.robot == "IRB1600-10/1.45" and np.allclose(setup.smr_offset_mm, [60, 80, 90])
    export = read_export(campaign / "run/tracker_export.csv")
    n = len(sweeps)
    assert np.allclose(sweeps.xyz, export.xyz[:n], atol=1e-4)
    assert np.allclose(cal.xyz, export.xyz[n:n + len(cal)], atol=1e-4)
    assert list(val.point_id) == [f"V{i:03d}" for i in range(1, 7)]
    assert set(cal.payload_kg) == {0.0, 4.0}
    assert np.all(np.diff(sweeps.time_s) > 0)


@pytest.mark.parametrize("delimiter,unit,decimal_comma,header", [
    (";", "m", True, True), ("\t", "in", False, True), (" ", "mm", False, False)])
def test_delimiters_units_and_headers_are_detected(campaign, tmp_path, capsys, delimiter, unit,
                                                   decimal_comma, header):
    export = read_export(campaign / "run/tracker_export.csv")
    scale = {"mm": 1.0, "m": 1e-3, "in": 1 / 25.4}[unit]
    rows = [delimiter.join([pid, *(f"{v * scale:.7f}" for v in p)])
            for pid, p in zip(export.ids, export.xyz)]
    if decimal_comma:
        rows = [r.replace(".", ",") for r in rows]
    text = ([delimiter.join(["Name", "X", "Y", "Z"])] if header else []) + rows
    path = tmp_path / "export.txt"
    path.write_text("# exported by tracker software\n" + "\n".join(text) + "\n")
    assert run_import(campaign, path, tmp_path / "out") == 0
    said = capsys.readouterr().out
    assert f"units {unit} (detected" in said
    sweeps = read_sweeps(tmp_path / "out/sweeps.csv")
    assert np.allclose(sweeps.xyz, export.xyz[:len(sweeps)], atol=2e-3)


def test_matching_by_time_without_ids(campaign, tmp_path, capsys):
    src = lines(campaign / "run/tracker_export.csv")
    path = tmp_path / "noid.csv"
    path.write_text("\n".join(",".join(r.split(",")[1:]) for r in src) + "\n")
    assert run_import(campaign, path, tmp_path / "out") == 0
    assert "matched by time" in capsys.readouterr().out
    a = read_points(tmp_path / "out/validation.csv")
    assert main(["import", str(campaign / "run/tracker_export.csv"), "--poses",
                 str(campaign / "plan/poses.csv"), "-o", str(tmp_path / "ref")]) == 0
    b = read_points(tmp_path / "ref/validation.csv")
    assert np.allclose(a.xyz, b.xyz) and list(a.point_id) == list(b.point_id)


def one_line_error(capsys) -> str:
    err = capsys.readouterr().err.strip().splitlines()
    assert err and "Traceback" not in "\n".join(err)
    return err[-1]


def edited(campaign: Path, tmp_path: Path, edit) -> Path:
    rows = lines(campaign / "run/tracker_export.csv")
    edit(rows)
    path = tmp_path / "bad.csv"
    path.write_text("\n".join(rows) + "\n")
    return path


def test_corrupt_cell_names_file_row_and_column(campaign, tmp_path, capsys):
    def corrupt(rows):
        cells = rows[7].split(",")
        cells[3] = "12.3.4"
        rows[7] = ",".join(cells)
    path = edited(campaign, tmp_path, corrupt)
    assert run_import(campaign, path, tmp_path / "o") == 1
    assert one_line_error(capsys) == (f"rapidfix: error: {path}: row 8, column 'Y [mm]': "
                                      "'12.3.4' is not a number")


def test_unknown_and_duplicated_ids_and_wrong_order(campaign, tmp_path, capsys):
    def unknown(rows):
        rows[4] = "S9-9-999," + rows[4].split(",", 1)[1]
    path = edited(campaign, tmp_path, unknown)
    assert run_import(campaign, path, tmp_path / "o") == 1
    err = capsys.readouterr().err
    assert f"{path}: row 5, column 'Point': point id 'S9-9-999' is not in the pose table" in err

    def swap(rows):
        rows[10], rows[11] = rows[11], rows[10]
    path = edited(campaign, tmp_path, swap)
    assert run_import(campaign, path, tmp_path / "o", "--match", "id") == 1
    err = capsys.readouterr().err
    assert "row 12, column 'Point': points in the wrong order" in err

    def dup(rows):
        rows.insert(6, rows[5])
    path = edited(campaign, tmp_path, dup)
    assert run_import(campaign, path, tmp_path / "o") == 1
    assert "measured twice (first in row 6)" in capsys.readouterr().err


def test_missing_points_are_listed_and_only_written_when_allowed(campaign, tmp_path, capsys):
    def drop(rows):
        del rows[3]
    path = edited(campaign, tmp_path, drop)
    assert run_import(campaign, path, tmp_path / "o") == 1
    err = one_line_error(capsys)
    assert "1 poses of the pose table were not measured: S2-1-003" in err
    assert run_import(campaign, path, tmp_path / "o", "--allow-missing") == 3
    assert "S2-1-003" in capsys.readouterr().err


def test_point_measured_while_moving_is_named(campaign, tmp_path, capsys):
    table = lines(campaign / "plan/poses.csv")
    move_s = float(table[9].split(",")[-3]) - float(table[8].split(",")[-1])  # arrive − leave

    def early(rows):
        cells = rows[8].split(",")
        cells[1] = f"{float(cells[1]) - 1.0 - 0.8 * move_s:.3f}"  # early in the move
        rows[8] = ",".join(cells)
    path = edited(campaign, tmp_path, early)
    assert run_import(campaign, path, tmp_path / "o") == 1
    err = capsys.readouterr().err
    assert "row 9, column 'Time': measured while the robot was still moving" in err
    assert "S2-1-008" in err
    # the same by time alone (no ids)
    no_ids = tmp_path / "noid.csv"
    no_ids.write_text("\n".join(",".join(r.split(",")[1:]) for r in lines(path)) + "\n")
    assert run_import(campaign, no_ids, tmp_path / "o") == 1
    err = capsys.readouterr().err
    assert "row 9, column 'Time': measured while the robot was still moving" in err


def test_wrong_units_in_the_header_are_refused(campaign, tmp_path, capsys):
    def metres(rows):
        rows[0] = rows[0].replace("[mm]", "[m]")
    path = edited(campaign, tmp_path, metres)
    assert run_import(campaign, path, tmp_path / "o") == 1
    assert one_line_error(capsys).startswith(
        f"rapidfix: error: {path}: row 2, column 'X [m]': units are mm, not m")


def test_export_of_another_plan_is_refused_by_its_distances(campaign, tmp_path, capsys):
    def stretch(rows):
        for k in range(1, len(rows)):
            c = rows[k].split(",")
            rows[k] = ",".join(c[:2] + [f"{float(v) * 1.3:.4f}" for v in c[2:]])
    path = edited(campaign, tmp_path, stretch)
    assert run_import(campaign, path, tmp_path / "o") == 1
    assert "not mm, m or inch" in one_line_error(capsys)


def test_simulated_export_is_the_true_robot_seen_by_the_tracker_on_the_plans_clock(campaign):
    import json

    from rapidfix.campaign.pose_table import read_pose_table
    from rapidfix.sim import VirtualRobot

    table = read_pose_table(campaign / "plan/poses.csv")
    truth = json.loads((campaign / "run/truth.json").read_text())
    vr = VirtualRobot.from_truth(truth)
    export = read_export(campaign / "run/tracker_export.csv")
    assert list(export.ids) == list(table.point_id)
    # the export's clock: the plan's trigger times (same timing model) after the offset,
    # payload changes (Stop) taking the 60 s the plan allows for them
    assert np.allclose(export.time_s - 36000.0, table.times["t_trigger_s"], atol=2e-3)
    q_prev = np.vstack([np.zeros(6), table.q[:-1]])
    ctx = {"payload_kg": table.payload_kg, "q_prev": q_prev}
    p_robot = vr.ball_positions(table.q, ctx)
    expected = vr.tracker.to_tracker(p_robot)
    err = np.linalg.norm(export.xyz - expected, axis=1)
    assert np.mean(err) < 0.05 and np.max(err) < 0.15  # noise and repeatability only
    nominal = vr.tracker.to_tracker(vr.ideal_positions(table.q))
    assert np.mean(np.linalg.norm(export.xyz - nominal, axis=1)) > 3 * np.mean(err)


def test_pose_table_faults_are_named(campaign, tmp_path, capsys):
    rows = lines(campaign / "plan/poses.csv")
    cells = rows[3].split(",")
    cells[9] = "7"  # sweep_joint of a sweep row
    rows[3] = ",".join(cells)
    bad = tmp_path / "poses.csv"
    bad.write_text("\n".join(rows) + "\n")
    assert main(["import", str(campaign / "run/tracker_export.csv"), "--poses", str(bad),
                 "-o", str(tmp_path / "o"), "--robot", "IRB1600-10/1.45",
                 "--smr-offset", "60,80,90"]) == 1
    assert one_line_error(capsys) == (f"rapidfix: error: {bad}: row 4, column 'sweep_joint': "
                                      "sweep rows need sweep_joint 1..6")


def test_time_matching_survives_a_longer_stop_and_a_slower_robot(campaign, tmp_path, capsys):
    """The operator takes 5 min instead of the planned 60 s to change the payload, and the
    robot runs 6 % slower than the plan's estimate: re-anchoring at every point and at
    every Stop keeps each point on its pose."""
    run = tmp_path / "slow"
    assert main(["simulate", str(run), "--program", str(campaign / "plan/measure.mod"),
                 "--poses", str(campaign / "plan/poses.csv"), "--export-format", "timed",
                 "--seed", "5", "--pause", "300", "--no-ids", "--delimiter", "tab"]) == 0
    rows = lines(run / "tracker_export.csv")
    t0 = float(rows[1].split("\t")[0])
    stretched = [rows[0]] + ["\t".join([f"{t0 + 1.06 * (float(r.split(chr(9))[0]) - t0):.3f}",
                                        *r.split("\t")[1:]]) for r in rows[1:]]
    path = tmp_path / "slow.txt"
    path.write_text("\n".join(stretched) + "\n")
    assert run_import(campaign, path, tmp_path / "o") == 0
    assert "matched by time" in capsys.readouterr().out
    assert run_import(campaign, campaign / "run/tracker_export.csv", tmp_path / "ref") == 0
    a = read_points(tmp_path / "o/calibration.csv")
    b = read_points(tmp_path / "ref/calibration.csv")
    assert list(a.point_id) == list(b.point_id)
    assert np.allclose(a.q, b.q)
    assert np.all(np.linalg.norm(a.xyz - b.xyz, axis=1) < 0.2)  # same poses, new noise


def test_clock_times_and_temperature_reach_the_measurement_files(tmp_path, capsys):
    assert main(["plan", str(tmp_path / "plan"), "--joints", "3", "--step", "10",
                 "--repeats", "1", "--calibration-points", "6", "--validation-points", "4"]) == 0
    assert main(["simulate", str(tmp_path / "run"), "--program",
                 str(tmp_path / "plan/measure.mod"), "--poses", str(tmp_path / "plan/poses.csv"),
                 "--export-format", "timed", "--effect", "thermal_drift", "--seed", "2"]) == 0
    rows = lines(tmp_path / "run/tracker_export.csv")
    assert rows[0].endswith("Temperature")

    def clock(r: str) -> str:
        c = r.split(",")
        t = float(c[1])
        c[1] = f"{int(t // 3600):02d}:{int(t % 3600 // 60):02d}:{t % 60:06.3f}"
        return ",".join(c)
    path = tmp_path / "clock.csv"
    path.write_text("\n".join([rows[0]] + [clock(r) for r in rows[1:]]) + "\n")
    capsys.readouterr()
    assert main(["import", str(path), "--poses", str(tmp_path / "plan/poses.csv"), "-o",
                 str(tmp_path / "set")]) == 0
    cal = read_points(tmp_path / "set/calibration.csv")
    sweeps = read_sweeps(tmp_path / "set/sweeps.csv")
    export = read_export(tmp_path / "run/tracker_export.csv")
    assert np.allclose(cal.temp_c, export.temp_c[len(sweeps):len(sweeps) + len(cal)], atol=1e-3)
    assert np.allclose(sweeps.time_s, export.time_s[:len(sweeps)] - export.time_s[0], atol=2e-3)


def test_headerless_columns_named_on_the_command_line(campaign, tmp_path):
    rows = lines(campaign / "run/tracker_export.csv")[1:]
    # time first, then the id, a column to skip, X Y Z
    swapped = [";".join([r.split(",")[1], r.split(",")[0], "x", *r.split(",")[2:]])
               for r in rows]
    path = tmp_path / "raw.txt"
    path.write_text("\n".join(swapped) + "\n")
    assert run_import(campaign, path, tmp_path / "o", "--columns", "time,id,-,x,y,z") == 0
    assert run_import(campaign, campaign / "run/tracker_export.csv", tmp_path / "ref") == 0
    a, b = read_sweeps(tmp_path / "o/sweeps.csv"), read_sweeps(tmp_path / "ref/sweeps.csv")
    assert np.allclose(a.xyz, b.xyz) and np.allclose(a.time_s, b.time_s)
