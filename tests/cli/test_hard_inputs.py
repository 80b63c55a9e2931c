"""Hard inputs through the command line (issue #15): one line and the right exit status,
no traceback, no runaway, nothing half-written."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest

from rapidfix.cli import main
from rapidfix.error_model.joint_rbf import JointRBF, fit_network
from rapidfix.error_model.model import ErrorModel
from rapidfix.error_model.model_file import save_model
from rapidfix.kinematics import load_robot

from .conftest import SAMPLES, one_line_error, run_cli

GB = 1 << 30


def set_cell(path, row: int, column: str, value: str, out):
    """A copy of CSV `path` with one cell replaced (row = line number, header = 1)."""
    lines = path.read_text().splitlines()
    header = lines[0].split(",")
    cells = lines[row - 1].split(",")
    cells[header.index(column)] = value
    lines[row - 1] = ",".join(cells)
    out.write_text("\n".join(lines) + "\n")
    return out


# ---- 1, 2: absurd cells are bad cells; no runaway, no LinAlgError ----------------------


@pytest.mark.parametrize("value", ["1e200", "1e20"])
def test_absurd_sweep_cell_is_a_bad_cell(small_set, tmp_path, value):
    bad = set_cell(small_set / "sweeps.csv", 11, "x", value, tmp_path / "sweeps.csv")
    done = run_cli(["fit", str(small_set / "setup.toml"), str(bad), "-o",
                    str(tmp_path / "m.json")], memory_bytes=2 * GB)
    assert done.returncode == 1, done.stderr
    assert one_line_error(done.stderr)
    assert "sweeps.csv: row 11, column 'x'" in done.stderr and value in done.stderr
    assert not (tmp_path / "m.json").exists()


def test_absurd_validation_cell_is_a_bad_cell(small_set, tmp_path):
    bad = set_cell(small_set / "validation.csv", 4, "y", "1e308", tmp_path / "val.csv")
    done = run_cli(["fit", str(small_set / "setup.toml"), str(small_set / "sweeps.csv"),
                    "--validation", str(bad), "-o", str(tmp_path / "m.json")],
                   memory_bytes=2 * GB)
    assert done.returncode == 1 and one_line_error(done.stderr), done.stderr
    assert "val.csv: row 4, column 'y'" in done.stderr
    assert not (tmp_path / "m.json").exists()


def test_absurd_angle_in_calibration_is_refused_by_diagnose(small_set, small_model, tmp_path):
    bad = set_cell(small_set / "calibration.csv", 3, "j2", "1e308", tmp_path / "cal.csv")
    done = run_cli(["diagnose", "--model", str(small_model), "--setup",
                    str(small_set / "setup.toml"), str(bad), str(small_set / "validation.csv"),
                    "-o", str(tmp_path / "out")], memory_bytes=2 * GB)
    assert done.returncode == 1 and one_line_error(done.stderr), done.stderr
    assert "cal.csv: row 3, column 'j2'" in done.stderr


def test_a_warning_inside_model_warnings_is_passed_on_once(tmp_path):
    # It used to be recorded into the very list being read: an endless loop eating memory.
    code = ("import warnings\nfrom rapidfix.pipeline import model_warnings\n"
            "with model_warnings() as messages:\n"
            "    warnings.warn('overflow', RuntimeWarning)\n"
            "print('done', messages)\n")
    import subprocess
    import sys

    def limit():
        import resource

        resource.setrlimit(resource.RLIMIT_AS, (2 * GB, 2 * GB))

    done = subprocess.run([sys.executable, "-W", "always", "-c", code], capture_output=True,
                          text=True, timeout=120, preexec_fn=limit)
    assert done.returncode == 0 and "done []" in done.stdout, done.stderr
    assert done.stderr.count("RuntimeWarning: overflow") == 1


def test_simulate_more_outliers_than_rows_is_a_user_error(tmp_path, capsys):
    status = main(["simulate", str(tmp_path / "s"), "--outliers", "1045", "--step", "15",
                   "--repeats", "1", "--calibration-points", "1", "--validation-points", "1"])
    err = capsys.readouterr().err
    assert status == 1 and one_line_error(err) and "1045 outliers" in err
    assert not (tmp_path / "s").exists()


# ---- 3: data of another robot -----------------------------------------------------------


def test_setup_naming_another_robot_is_refused(small_set, tmp_path, capsys):
    setup = tmp_path / "setup.toml"
    setup.write_text((small_set / "setup.toml").read_text().replace(
        "IRB1600-10/1.45", "IRB120-3/0.58"))
    out = tmp_path / "m.json"
    status = main(["fit", str(setup), str(small_set / "sweeps.csv"), "-o", str(out)])
    err = capsys.readouterr().err
    assert status == 1 and one_line_error(err)
    assert "mm RMS from what the robot model 'IRB120-3/0.58' predicts" in err
    assert not out.exists()


# ---- 4: a failed fit writes nothing ------------------------------------------------------


@pytest.fixture
def existing_model(tmp_path):
    path = tmp_path / "model.json"
    path.write_text('{"keep": "me"}\n')
    return path


def _fit_args(small_set, model, *extra):
    return ["fit", str(small_set / "setup.toml"), str(small_set / "sweeps.csv"), "-o",
            str(model), *extra]


def test_fit_with_missing_validation_leaves_the_model_alone(small_set, existing_model,
                                                           tmp_path, capsys):
    status = main(_fit_args(small_set, existing_model, "--validation",
                            str(tmp_path / "nope.csv")))
    err = capsys.readouterr()
    assert status == 1 and one_line_error(err.err) and "nope.csv" in err.err
    assert err.out == ""  # refused before any work
    assert existing_model.read_text() == '{"keep": "me"}\n'


def test_fit_with_bad_validation_leaves_the_model_alone(small_set, existing_model,
                                                       tmp_path, capsys):
    bad = tmp_path / "val.csv"
    bad.write_text("point_id,j1,j2,j3,j4,j5,j6,x,y,z\nV1,0,0,0,0,0,0,1,2\n")
    status = main(_fit_args(small_set, existing_model, "--validation", str(bad)))
    err = capsys.readouterr().err
    assert status == 1 and one_line_error(err) and "val.csv: row 2" in err
    assert existing_model.read_text() == '{"keep": "me"}\n'


def test_fit_report_on_a_file_is_refused_before_any_work(small_set, existing_model,
                                                        tmp_path, capsys):
    report = tmp_path / "report"
    report.write_text("a file")
    status = main(_fit_args(small_set, existing_model, "--report", str(report)))
    out, err = capsys.readouterr()
    assert status == 1 and one_line_error(err)
    assert "not a folder" in err and "File exists" not in err and out == ""
    assert existing_model.read_text() == '{"keep": "me"}\n'


# ---- 5: malformed models; no header where nothing was compensated ----------------------


def _model_doc(small_model):
    return json.loads(small_model.read_text())


def test_model_with_a_nan_weight_is_refused(small_model, tmp_path, capsys):
    doc = _model_doc(small_model)
    doc["effects"][0]["params"]["j1_w003_rad"] = float("nan")
    bad = tmp_path / "nan.json"
    bad.write_text(json.dumps(doc))
    out = tmp_path / "o.mod"
    status = main(["rewrite", str(SAMPLES / "ballbar.mod"), "--model", str(bad), "-o", str(out)])
    err = capsys.readouterr().err
    assert status == 1 and one_line_error(err) and "j1_w003_rad" in err and "finite" in err
    assert not out.exists()


def test_model_with_a_cut_centres_array_is_refused(small_model, tmp_path, capsys):
    doc = _model_doc(small_model)
    net = doc["effects"][0]["state"]["networks"][0]
    net["centres_rad"] = net["centres_rad"][:-1]
    bad = tmp_path / "cut.json"
    bad.write_text(json.dumps(doc))
    status = main(["rewrite", str(SAMPLES / "ballbar.mod"), "--model", str(bad), "-o",
                   str(tmp_path / "o.mod")])
    err = capsys.readouterr().err
    assert status == 1 and one_line_error(err) and "centres_rad" in err


RUNTIME_ONLY = """MODULE Runtime
  VAR robtarget pHere;
  PROC main()
    pHere := CRobT(\\Tool:=tool0);
    MoveL Offs(pHere, 0, 0, 50), v100, fine, tool0;
  ENDPROC
ENDMODULE
"""


def test_no_compensated_header_when_nothing_was_compensated(small_model, tmp_path, capsys):
    src = tmp_path / "rt.mod"
    src.write_text(RUNTIME_ONLY)
    out = tmp_path / "out.mod"
    status = main(["rewrite", str(src), "--model", str(small_model), "-o", str(out)])
    assert status == 3
    assert "rapidfix-compensated" not in out.read_text()
    # so the next run does not take it for a compensated program
    assert main(["rewrite", str(out), "--model", str(small_model), "-o",
                 str(tmp_path / "again.mod")]) == 3
    capsys.readouterr()


# ---- 6: warnings follow the convention ---------------------------------------------------


@pytest.fixture(scope="module")
def narrow_model(tmp_path_factory):
    """A model valid only for joint 1 in [-1°, 1°]: the ballbar program (J1 ≈ 5°) is
    clamped."""
    x = np.radians(np.linspace(-1.0, 1.0, 9))
    net, _ = fit_network(x, 1e-4 * np.sin(40 * x))
    model = ErrorModel("IRB1600-10/1.45", [JointRBF([net, None, None, None, None, None])])
    return save_model(model, tmp_path_factory.mktemp("narrow") / "narrow.json")


def test_clamping_warns_in_the_cli_convention_and_exits_3(narrow_model, tmp_path):
    done = run_cli(["rewrite", str(SAMPLES / "ballbar.mod"), "--model", str(narrow_model),
                    "-o", str(tmp_path / "o.mod")])
    assert done.returncode == 3, done.stderr
    assert "rapidfix: warning: joint 1 at" in done.stderr
    assert "OutsideRangeWarning" not in done.stderr and "model.py" not in done.stderr


def test_clamping_is_a_warnings_row_in_batch(narrow_model, tmp_path, capsys):
    src = tmp_path / "in"
    src.mkdir()
    shutil.copy(SAMPLES / "ballbar.mod", src / "a.mod")
    shutil.copy(SAMPLES / "ballbar.mod", src / "b.mod")
    status = main(["batch", str(src), str(tmp_path / "out"), "--model", str(narrow_model),
                   "-j", "1", "--no-progress"])
    assert status == 3
    summary = json.loads((tmp_path / "out" / "rapidfix-batch.json").read_text())
    rows = {r["path"]: r for r in summary["results"]}
    # each file warns for itself, not only the first one a worker sees
    assert rows["a.mod"]["status"] == rows["b.mod"]["status"] == "warnings"
    assert "joint 1 at" in rows["b.mod"]["message"]
    capsys.readouterr()


# ---- 7: usage errors exit 2 --------------------------------------------------------------


@pytest.mark.parametrize("extra", [[], ["-o", "X", "--in-place"]])
def test_rewrite_usage_errors_exit_2(small_model, tmp_path, capsys, extra):
    extra = [str(tmp_path / "o.mod") if a == "X" else a for a in extra]
    status = main(["rewrite", str(SAMPLES / "ballbar.mod"), "--model", str(small_model),
                   *extra])
    err = capsys.readouterr().err
    assert status == 2 and one_line_error(err)


def test_batch_without_out_dir_exits_2(small_model, tmp_path, capsys):
    (tmp_path / "in").mkdir()
    status = main(["batch", str(tmp_path / "in"), "--model", str(small_model)])
    err = capsys.readouterr().err
    assert status == 2 and one_line_error(err) and "OUT_DIR" in err


# ---- 8: clear messages -------------------------------------------------------------------


@pytest.mark.parametrize("codec", ["utf-16-le", "utf-16-be"])
def test_utf16_without_bom_is_read_and_written_back_so(small_model, tmp_path, capsys, codec):
    src = tmp_path / "u16.mod"
    src.write_bytes((SAMPLES / "ballbar.mod").read_text().encode(codec))
    out = tmp_path / "out.mod"
    assert main(["rewrite", str(src), "--model", str(small_model), "-o", str(out)]) == 0
    data = out.read_bytes()
    assert not data.startswith((b"\xff\xfe", b"\xfe\xff"))
    text = data.decode(codec)
    assert text.startswith("MODULE Ballbar") and "MoveAbsJ" in text
    capsys.readouterr()


def test_broken_utf16_without_bom_is_named_as_such(tmp_path, capsys):
    src = tmp_path / "u16.mod"
    src.write_bytes("MODULE A\nENDMODULE\n".encode("utf-16-le") + b"\x00\xd8\x41\x00")
    assert main(["check", str(src)]) == 1
    err = capsys.readouterr().err
    assert "UTF-16 without a byte-order mark" in err


def test_output_that_is_a_folder_is_named(small_model, tmp_path, capsys):
    folder = tmp_path / "folder"
    folder.mkdir()
    status = main(["rewrite", str(SAMPLES / "ballbar.mod"), "--model", str(small_model),
                   "-o", str(folder)])
    err = capsys.readouterr().err
    assert status == 1 and one_line_error(err)
    assert f"{folder}: is a folder" in err and ".tmp" not in err


def test_diagnose_output_on_a_file_is_refused_before_any_work(small_set, small_model,
                                                            tmp_path, capsys):
    target = tmp_path / "out"
    target.write_text("a file")
    status = main(["diagnose", "--model", str(small_model), "--setup",
                   str(small_set / "setup.toml"), str(small_set / "calibration.csv"),
                   str(small_set / "validation.csv"), "-o", str(target)])
    out, err = capsys.readouterr()
    assert status == 1 and one_line_error(err) and "not a folder" in err and out == ""


def test_simulate_into_a_file_is_refused(tmp_path, capsys):
    target = tmp_path / "set"
    target.write_text("a file")
    assert main(["simulate", str(target)]) == 1
    err = capsys.readouterr().err
    assert one_line_error(err) and "not a folder" in err and "File exists" not in err


def test_unknown_robot_is_named_once(small_set, tmp_path, capsys):
    setup = tmp_path / "setup.toml"
    setup.write_text('robot = "X"\nsmr_offset_mm = [60, 80, 90]\n')
    assert main(["fit", str(setup), str(small_set / "sweeps.csv"), "-o",
                 str(tmp_path / "m.json")]) == 1
    err = capsys.readouterr().err
    assert one_line_error(err) and err.count("unknown robot 'X'") == 1


def test_diagnose_shows_no_progress_bar_in_a_log(small_set, small_model, tmp_path):
    done = run_cli(["diagnose", "--model", str(small_model), "--setup",
                    str(small_set / "setup.toml"), str(small_set / "calibration.csv"),
                    str(small_set / "validation.csv"), "-o", str(tmp_path / "out"),
                    "--candidates", "tool_offset"])
    assert done.returncode == 0, done.stderr
    assert "rapidfix diagnose" not in done.stderr and "\r" not in done.stderr


# ---- 9: help texts and quiet acceptance --------------------------------------------------


def test_simulate_help_describes_every_option(capsys):
    with pytest.raises(SystemExit):
        main(["simulate", "--help"])
    text = " ".join(capsys.readouterr().out.split()).split("options:", 1)[1]
    for option, default in (("--calibration-points N", "default 60"),
                            ("--validation-points N", "default 40"),
                            ("--repeats N", "default 3")):
        after = text.split(option, 1)[1].split(" --", 1)[0]
        assert default in after, (option, after)


def test_fit_help_mentions_exit_status_3(capsys):
    with pytest.raises(SystemExit):
        main(["fit", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "3 finished with warnings" in text


def test_same_file_as_calibration_and_validation_warns(small_set, small_model, tmp_path,
                                                      capsys):
    status = main(["diagnose", "--model", str(small_model), "--setup",
                   str(small_set / "setup.toml"), str(small_set / "calibration.csv"),
                   str(small_set / "calibration.csv"), "-o", str(tmp_path / "out"),
                   "--candidates", "tool_offset"])
    err = capsys.readouterr().err
    assert status == 3
    assert "rapidfix: warning:" in err and "both the calibration and the validation" in err


def test_unknown_setup_key_warns(small_set, tmp_path, capsys):
    setup = tmp_path / "setup.toml"
    setup.write_text((small_set / "setup.toml").read_text() + "smr_ofset_mm = [1, 2, 3]\n")
    status = main(["fit", str(setup), str(small_set / "sweeps.csv"), "-o",
                   str(tmp_path / "m.json")])
    err = capsys.readouterr().err
    assert status == 3
    assert "rapidfix: warning:" in err and "unknown key 'smr_ofset_mm'" in err


def test_fit_summary_with_single_measurements_does_not_crash(tmp_path, capsys):
    from rapidfix.sim import simulate_cell

    cell = simulate_cell(tmp_path / "one", seed=2, repeats=1, step_deg=15.0,
                         n_calibration=5, n_validation=5)
    status = main(["fit", str(cell / "setup.toml"), str(cell / "sweeps.csv"), "-o",
                   str(tmp_path / "m.json")])
    out = capsys.readouterr().out
    assert status == 0 and "n/a" in out and (tmp_path / "m.json").exists()


def test_robot_reach_bounds_the_positions():
    from rapidfix.measure.files import robot_reach_mm

    reach = robot_reach_mm(load_robot("IRB1600-10/1.45"))
    # the flange at full stretch (θ2 = 90°, arm horizontal) is within the bound
    assert 1450.0 < reach < 2500.0


# ---- 9: a large program shows the step its rewrite is at, on a terminal only -----------


class _Terminal:
    """A standard error that says it is a terminal, keeping what is written."""

    def __init__(self) -> None:
        import io

        self.buffer = io.StringIO()

    def isatty(self) -> bool:
        return True

    def write(self, text: str) -> int:
        return self.buffer.write(text)

    def flush(self) -> None:
        pass


def test_a_large_rewrite_shows_its_steps_on_a_terminal_and_writes_the_same(
        small_model, tmp_path, capsys, monkeypatch):
    import sys

    from rapidfix.commands import rewrite as rewrite_command
    from rapidfix.postprocess import REWRITE_STEPS as STEPS

    source = SAMPLES / "cell.mod"
    plain = tmp_path / "plain.mod"
    assert main(["rewrite", str(source), "--model", str(small_model), "-o", str(plain)]) == 3
    quiet = capsys.readouterr()
    assert "rapidfix rewrite:" not in quiet.err  # not a terminal: no bar in the log
    terminal = _Terminal()
    monkeypatch.setattr(rewrite_command, "STEP_BAR_FROM_BYTES", 1)  # any file is large
    monkeypatch.setattr(sys, "stderr", terminal)
    shown = tmp_path / "shown.mod"
    status = main(["rewrite", str(source), "--model", str(small_model), "-o", str(shown)])
    monkeypatch.undo()
    assert status == 3
    bar = terminal.buffer.getvalue()
    assert [step for step in STEPS if f"rapidfix rewrite: {step}" in bar] == list(STEPS)
    assert shown.read_bytes() == plain.read_bytes()
    assert capsys.readouterr().out == quiet.out.replace(str(plain), str(shown))


def test_rewrite_reports_its_steps_in_order(small_model, tmp_path):
    from rapidfix.postprocess import REWRITE_STEPS as STEPS
    from rapidfix.postprocess import Compensator, RewriteOptions, rewrite_file

    comp = Compensator.load(str(small_model))
    steps: list[str] = []
    result = rewrite_file(SAMPLES / "ballbar.mod", tmp_path / "out.mod", comp,
                          RewriteOptions(), progress=steps.append)
    assert steps == list(STEPS) and result.written
    steps.clear()  # strict, with a move it cannot compensate: nothing is written
    result = rewrite_file(SAMPLES / "cell.mod", tmp_path / "cell.mod", comp,
                          RewriteOptions(strict=True), progress=steps.append)
    assert steps == list(STEPS[:5]) and not result.written
