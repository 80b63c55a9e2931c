"""Reading, validating and writing measurement files (setup.toml, sweeps and points CSV)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rapidfix.exceptions import MeasurementError
from rapidfix.measure.files import (
    MeasurementWarning,
    PointTable,
    Setup,
    SweepTable,
    ball_offsets,
    read_points,
    read_setup,
    read_sweeps,
    write_points,
    write_setup,
    write_sweeps,
)

SWEEPS = """sweep_joint,j1,j2,j3,j4,j5,j6,repeat,x,y,z
1,-10,0,0,0,45,0,1,2100.5,-300.25,400.125
1,-5,0,0,0,45,0,1,2110.5,-290.25,400.125
1,0,0,0,0,45,0,1,2120.5,-280.25,400.125
1,5,0,0,0,45,0,1,2130.5,-270.25,400.125
1,10,0,0,0,45,0,1,2140.5,-260.25,400.125
"""
POINTS = """point_id,j1,j2,j3,j4,j5,j6,x,y,z,payload_kg
P1,10,20,-30,40,50,60,1500,200,300,2.5
P2,-10,25,-35,45,55,65,1510,210,310,5
P3,20,30,-40,50,60,70,1520,220,320,0
"""


def write(tmp_path, name, text):
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def replace_cell(text, line, column, value):
    lines = text.splitlines()
    header = lines[0].split(",")
    cells = lines[line - 1].split(",")
    cells[header.index(column)] = value
    lines[line - 1] = ",".join(cells)
    return "\n".join(lines) + "\n"


def test_sweeps_are_read_in_radians_with_zero_based_joint(tmp_path):
    table = read_sweeps(write(tmp_path, "s.csv", SWEEPS))
    assert table.sweep_joint.tolist() == [0] * 5
    assert np.allclose(np.degrees(table.q[:, 0]), [-10, -5, 0, 5, 10])
    assert np.allclose(table.q[:, 4], np.pi / 4)
    assert table.xyz[0].tolist() == [2100.5, -300.25, 400.125]
    assert table.rows.tolist() == [2, 3, 4, 5, 6]
    assert table.payload_kg is None and table.time_s is None


def test_points_keep_optional_and_extra_columns(tmp_path):
    text = POINTS.replace("payload_kg", "payload_kg,length_mm").replace("\n", ",1.5\n")
    text = text.replace("payload_kg,length_mm,1.5", "payload_kg,length_mm")
    table = read_points(write(tmp_path, "p.csv", text))
    assert table.point_id.tolist() == ["P1", "P2", "P3"]
    assert table.payload_kg.tolist() == [2.5, 5.0, 0.0]
    assert table.extra["length_mm"].tolist() == [1.5, 1.5, 1.5]


@pytest.mark.parametrize(
    ("line", "column", "value", "words"),
    [
        (3, "j3", "abc", "not a number"),
        (4, "x", "nan", "finite"),
        (5, "z", "inf", "finite"),
        (2, "y", "", "empty"),
        (6, "sweep_joint", "7", "integer"),
        (3, "repeat", "1.5", "integer"),
    ],
)
def test_bad_sweep_cells_name_row_and_column(tmp_path, line, column, value, words):
    path = write(tmp_path, "s.csv", replace_cell(SWEEPS, line, column, value))
    with pytest.raises(MeasurementError) as info:
        read_sweeps(path)
    err = info.value
    assert (err.row, err.column) == (line, column)
    assert words in err.message
    assert f"row {line}, column '{column}'" in str(err) and "s.csv" in str(err)


@pytest.mark.parametrize("column", ["sweep_joint", "j4", "repeat", "z"])
def test_missing_column_is_named(tmp_path, column):
    lines = SWEEPS.splitlines()
    idx = lines[0].split(",").index(column)
    text = "\n".join(",".join(c for i, c in enumerate(line.split(",")) if i != idx)
                     for line in lines) + "\n"
    with pytest.raises(MeasurementError) as info:
        read_sweeps(write(tmp_path, "s.csv", text))
    assert (info.value.row, info.value.column) == (1, column)
    assert "missing column" in info.value.message


def test_duplicated_rows_are_refused(tmp_path):
    lines = SWEEPS.splitlines()
    text = "\n".join([*lines, lines[2]]) + "\n"
    with pytest.raises(MeasurementError) as info:
        read_sweeps(write(tmp_path, "s.csv", text))
    assert info.value.row == 7 and "duplicate of row 3" in info.value.message


def test_duplicated_point_ids_are_refused(tmp_path):
    text = POINTS.replace("P3,", "P1,")
    with pytest.raises(MeasurementError) as info:
        read_points(write(tmp_path, "p.csv", text))
    assert (info.value.row, info.value.column) == (4, "point_id")
    assert "row 2" in info.value.message


def test_positions_in_metres_are_refused(tmp_path):
    lines = SWEEPS.splitlines()
    rows = [lines[0]]
    for line in lines[1:]:
        cells = line.split(",")
        cells[8:11] = [str(float(c) / 1000.0) for c in cells[8:11]]
        rows.append(",".join(cells))
    with pytest.raises(MeasurementError) as info:
        read_sweeps(write(tmp_path, "s.csv", "\n".join(rows) + "\n"))
    assert "metres" in info.value.message and info.value.row == 2


def test_joints_in_radians_are_refused(tmp_path):
    lines = SWEEPS.splitlines()
    rows = [lines[0]]
    for k, line in enumerate(lines[1:]):
        cells = line.split(",")
        cells[1] = str(-90.0 + 45.0 * k)  # a sweep of joint 1 over ±90° ...
        cells[1:7] = [str(np.radians(float(c))) for c in cells[1:7]]  # ... in radians
        rows.append(",".join(cells))
    with pytest.raises(MeasurementError, match="radians"):
        read_sweeps(write(tmp_path, "s.csv", "\n".join(rows) + "\n"))


def test_short_row_and_negative_payload(tmp_path):
    text = POINTS.replace("P2,-10,25,-35,45,55,65,1510,210,310,5", "P2,-10,25")
    with pytest.raises(MeasurementError) as info:
        read_points(write(tmp_path, "p.csv", text))
    assert info.value.row == 3 and "fields" in info.value.message
    text = POINTS.replace(",5\n", ",-5\n")
    with pytest.raises(MeasurementError) as info:
        read_points(write(tmp_path, "p.csv", text))
    assert (info.value.row, info.value.column) == (3, "payload_kg")


def test_missing_and_empty_files(tmp_path):
    with pytest.raises(MeasurementError, match="not found"):
        read_sweeps(tmp_path / "nope.csv")
    with pytest.raises(MeasurementError, match="header"):
        read_points(write(tmp_path, "e.csv", "\n\n"))
    with pytest.raises(MeasurementError, match="no data rows"):
        read_points(write(tmp_path, "h.csv", POINTS.splitlines()[0] + "\n"))


GOOD_SETUP = 'robot = "IRB1600-10/1.45"\nsmr_offset_mm = [60, 80, 90]\ntracker_sigma_mm = 0.01\n'


def test_setup_is_read(tmp_path):
    setup = read_setup(write(tmp_path, "setup.toml", GOOD_SETUP))
    assert setup.robot == "IRB1600-10/1.45"
    assert setup.smr_offset_mm.tolist() == [60.0, 80.0, 90.0]
    assert setup.tracker_sigma_mm == 0.01 and setup.payload_kg == 0.0


@pytest.mark.parametrize(
    ("text", "line", "words"),
    [
        (GOOD_SETUP.replace("IRB1600-10/1.45", "IRB9999"), 1, "unknown robot"),
        (GOOD_SETUP.replace("[60, 80, 90]", "[0.06, 0.08, 0.09]"), 2, "metres"),
        (GOOD_SETUP.replace("[60, 80, 90]", "[60, 80]"), 2, "three numbers"),
        (GOOD_SETUP.replace("0.01", "-1"), 3, "positive"),
        (GOOD_SETUP + "payload_kg = 'heavy'\n", 4, "finite number"),
        (GOOD_SETUP.replace('robot = "IRB1600-10/1.45"\n', ""), None, "robot"),
        (GOOD_SETUP + "x = = 1\n", 4, "TOML"),
    ],
)
def test_bad_setup_names_the_line(tmp_path, text, line, words):
    with pytest.raises(MeasurementError) as info:
        read_setup(write(tmp_path, "setup.toml", text))
    assert words in info.value.message
    assert info.value.line == line


finite = st.floats(-1e4, 1e4, allow_nan=False).map(lambda v: round(v, 3))


@settings(max_examples=25, deadline=None)
@given(st.integers(3, 12), st.integers(0, 2**31 - 1), st.booleans())
def test_tables_round_trip(tmp_path_factory, n, seed, conditions):
    rng = np.random.default_rng(seed)
    tmp = tmp_path_factory.mktemp("rt")
    q = np.radians(np.round(rng.uniform(-170, 170, (n, 6)), 6))
    xyz = np.round(rng.uniform(-3000, 3000, (n, 3)), 4)
    extra = {"payload_kg": np.round(rng.uniform(0, 10, n), 3),
             "time_s": np.arange(n) * 2.5, "temp_c": np.round(20 + rng.uniform(0, 5, n), 4)}
    extra = extra if conditions else {}
    sweeps = SweepTable(sweep_joint=rng.integers(0, 6, n), q=q, repeat=rng.integers(1, 4, n),
                        xyz=xyz, rows=np.arange(n) + 2, **extra)
    back = read_sweeps(write_sweeps(tmp / "s.csv", sweeps))
    assert np.array_equal(back.sweep_joint, sweeps.sweep_joint)
    assert np.allclose(back.q, q, atol=1e-12) and np.allclose(back.xyz, xyz, atol=1e-9)
    for name, values in extra.items():
        assert np.allclose(getattr(back, name), values, atol=1e-9)
    points = PointTable(point_id=np.array([f"p{i}" for i in range(n)]), q=q, xyz=xyz,
                        rows=np.arange(n) + 2, **extra)
    back = read_points(write_points(tmp / "p.csv", points))
    assert back.point_id.tolist() == points.point_id.tolist()
    assert np.allclose(back.q, q, atol=1e-12) and np.allclose(back.xyz, xyz, atol=1e-9)


def test_setup_round_trip(tmp_path):
    setup = Setup("IRB1600-10/1.45", np.array([1.5, -2.0, 100.25]), 0.0125, 7.5,
                  extra={"operator": "test", "tracker_model": "AT960"})
    # keys rapidfix does not know are kept, and said to be ignored
    with pytest.warns(MeasurementWarning, match=r"unknown key '(operator|tracker_model)'"):
        back = read_setup(write_setup(tmp_path / "setup.toml", setup))
    assert back.robot == setup.robot and back.smr_offset_mm.tolist() == [1.5, -2.0, 100.25]
    assert (back.tracker_sigma_mm, back.payload_kg) == (0.0125, 7.5)
    assert back.extra == {"operator": "test", "tracker_model": "AT960"}


# --------------------------------------------------------------------------- ball nests

SETUP_ONE = 'robot = "IRB1600-10/1.45"\nsmr_offset_mm = [60, 80, 90]\n'
SETUP_TWO = 'robot = "IRB1600-10/1.45"\nsmr_offsets_mm = [[60, 80, 90], [-60, -80, 150]]\n'


def test_two_nests_round_trip_with_the_ball_of_every_row(tmp_path):
    setup = read_setup(write(tmp_path, "setup.toml", SETUP_TWO))
    assert setup.ball_offsets_mm.tolist() == [[60, 80, 90], [-60, -80, 150]]
    assert setup.smr_offset_mm.tolist() == [60, 80, 90]  # nest 0, the sweeps' ball
    text = POINTS.replace("payload_kg\n", "payload_kg,ball\n")
    text = "\n".join(line + ("" if i == 0 else f",{(i + 1) % 2}")
                     for i, line in enumerate(text.strip().splitlines())) + "\n"
    table = read_points(write(tmp_path, "p.csv", text))
    assert table.ball.tolist() == [0, 1, 0] and "ball" not in table.extra
    assert ball_offsets(table, setup).tolist() == [[60, 80, 90], [-60, -80, 150],
                                                   [60, 80, 90]]
    # written and read back: the same setup, the same rows, the same nests
    back_setup = read_setup(write_setup(tmp_path / "again.toml", setup))
    assert np.array_equal(back_setup.ball_offsets_mm, setup.ball_offsets_mm)
    assert "smr_offsets_mm = [[" in (tmp_path / "again.toml").read_text()
    back = read_points(write_points(tmp_path / "again.csv", table))
    assert back.ball.tolist() == [0, 1, 0]
    assert np.array_equal(back.xyz, table.xyz) and np.array_equal(back.q, table.q)


def test_single_ball_files_load_and_write_as_before(tmp_path):
    setup = read_setup(write(tmp_path, "setup.toml", SETUP_ONE))
    assert setup.smr_offsets_mm is None and setup.ball_offsets_mm.tolist() == [[60, 80, 90]]
    table = read_points(write(tmp_path, "p.csv", POINTS))
    assert table.ball is None
    assert ball_offsets(table, setup).tolist() == [[60, 80, 90]] * 3
    # the writers leave the old format as it was: one offset key, no ball column
    toml = write_setup(tmp_path / "again.toml", setup).read_text()
    assert "smr_offset_mm = [60.000000, 80.000000, 90.000000]" in toml
    assert "smr_offsets_mm" not in toml
    header = write_points(tmp_path / "again.csv", table).read_text().splitlines()[0]
    assert header == "point_id,j1,j2,j3,j4,j5,j6,x,y,z,payload_kg"
    # one nest listed under the new key is the old single ball
    one = read_setup(write(tmp_path, "one.toml", SETUP_ONE.replace(
        "smr_offset_mm = [60, 80, 90]", "smr_offsets_mm = [[60, 80, 90]]")))
    assert one.smr_offsets_mm is None and one.smr_offset_mm.tolist() == [60, 80, 90]


@pytest.mark.parametrize(("setup_text", "ball", "words"), [
    (SETUP_TWO, "2", "ball 2 has no offset: the setup (setup.toml) declares nests 0..1"),
    (SETUP_ONE, "1", "ball 1 has no offset: the setup (setup.toml) declares only one ball"),
])
def test_a_ball_without_an_offset_is_an_error_at_its_row_and_column(tmp_path, setup_text, ball,
                                                                    words):
    setup = read_setup(write(tmp_path, "setup.toml", setup_text))
    text = POINTS.replace("payload_kg\n", "payload_kg,ball\n")
    lines = text.strip().splitlines()
    lines[1:] = [line + f",{b}" for line, b in zip(lines[1:], ["0", "0", ball])]
    table = read_points(write(tmp_path, "p.csv", "\n".join(lines) + "\n"))
    with pytest.raises(MeasurementError) as err:
        ball_offsets(table, setup)
    message = str(err.value)
    assert "p.csv" in message and "row 4" in message and "'ball'" in message
    assert words in message and "\n" not in message


@pytest.mark.parametrize(("text", "words"), [
    ('smr_offset_mm = [1, 2, 3]\nsmr_offsets_mm = [[1, 2, 3], [4, 5, 60]]', "either"),
    ("smr_offsets_mm = [1, 2, 3]", "list of 1 to"),
    ("smr_offsets_mm = [[1, 2, 3], [1, 2]]", r"'smr_offsets_mm\[1\]' must be three numbers"),
    ("smr_offsets_mm = [[60, 80, 90], [61, 80, 90]]", "nests 0 and 1"),
    ("smr_offsets_mm = [[60, 80, 90], [0.1, 0.1, 0.1]]", "looks like metres"),
])
def test_bad_nests_are_refused_on_their_line(tmp_path, text, words):
    path = write(tmp_path, "setup.toml", 'robot = "IRB1600-10/1.45"\n' + text + "\n")
    with pytest.raises(MeasurementError, match=words) as err:
        read_setup(path)
    assert "setup.toml:" in str(err.value)


def test_a_ball_column_is_an_integer_and_the_sweeps_use_nest_0(tmp_path):
    text = POINTS.replace("payload_kg\n", "payload_kg,ball\n").strip().splitlines()
    text[1:] = [line + ",0.5" for line in text[1:]]
    with pytest.raises(MeasurementError, match=r"row 2, column 'ball'.*not an integer"):
        read_points(write(tmp_path, "p.csv", "\n".join(text) + "\n"))
    sweeps = SWEEPS.replace("x,y,z\n", "x,y,z,ball\n").strip().splitlines()
    sweeps[1:] = [line + (",1" if i == 2 else ",0") for i, line in enumerate(sweeps[1:])]
    with pytest.raises(MeasurementError, match=r"row 4, column 'ball'.*ball 0 only"):
        read_sweeps(write(tmp_path, "s.csv", "\n".join(sweeps) + "\n"))


@pytest.mark.parametrize("delimiter", [";", "\t"])
def test_semicolon_and_tab_exports_with_decimal_commas_read_as_the_comma_file(
        tmp_path, delimiter):
    plain = read_points(write(tmp_path, "p.csv", POINTS))
    other = "\n".join(delimiter.join(c.replace(".", ",") for c in line.split(","))
                      for line in POINTS.splitlines()) + "\n"
    table = read_points(write(tmp_path, "o.csv", other))
    assert table.point_id.tolist() == plain.point_id.tolist()
    assert np.array_equal(table.q, plain.q) and np.array_equal(table.xyz, plain.xyz)
    assert np.array_equal(table.payload_kg, plain.payload_kg)


def test_comment_lines_and_text_columns_are_skipped_with_a_warning(tmp_path):
    lines = POINTS.splitlines()
    text = "# exported by a tracker\n# units: mm, deg\n" + lines[0] + ",note\n"
    text += "\n".join(f"{line},{word}" for line, word in zip(lines[1:], ["ok", "re-shot", "ok"]))
    text = text.replace("P2,", "# a comment between rows\nP2,") + "\n"
    with pytest.warns(MeasurementWarning, match="'note' is not numeric"):
        table = read_points(write(tmp_path, "p.csv", text))
    plain = read_points(write(tmp_path, "plain.csv", POINTS))
    assert np.array_equal(table.xyz, plain.xyz) and "note" not in table.extra
    assert table.rows.tolist() == [4, 6, 7]  # line numbers in the file, comments counted
