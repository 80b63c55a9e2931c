"""Fuzzing the inputs (issue #15 acceptance): random corruptions of valid measurement
CSVs, setup files and model files give a result or the project's one-line error — never
another exception, never a runaway (each run is limited to 2 GB of address space).

Few examples on a tiny data set keep this within the default test run; the examples are
derandomised, so a failure is reproduced by running the test again.
"""

from __future__ import annotations

import json

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rapidfix.sim import simulate_cell

from .conftest import SAMPLES, one_line_error, run_cli

GB = 1 << 30
FUZZ = settings(max_examples=5, deadline=None, derandomize=True, database=None,
                suppress_health_check=[HealthCheck.function_scoped_fixture,
                                       HealthCheck.too_slow])

TOKENS = ["1e308", "-1e308", "1e200", "1e20", "nan", "inf", "-inf", "", "abc", "0", "-0",
          "99999999", "1_000", "0x10", "\u0661\u0662", "1e-320", "3600.0001", '"', "1,2"]
JSON_VALUES = [float("nan"), float("inf"), -float("inf"), 1e308, -1e308, 0, -1, 1e20, "x",
               None, [], {}, True, 10**400, 1e-320]


@pytest.fixture(scope="module")
def tiny_set(tmp_path_factory):
    """A very small set: 30° sweeps, two repeats, 20 calibration and 5 validation points."""
    return simulate_cell(tmp_path_factory.mktemp("tiny") / "set", seed=8, repeats=2,
                         step_deg=30.0, n_calibration=20, n_validation=5)


def assert_result_or_one_line_error(done) -> None:
    """A finished command: success (0, or 3 with warnings) or one `rapidfix: error:` line."""
    assert done.returncode >= 0, f"killed by signal {-done.returncode}: {done.stderr[-2000:]}"
    assert "Traceback" not in done.stderr and "internal error" not in done.stderr, done.stderr
    if done.returncode not in (0, 3):
        assert done.returncode in (1, 2) and one_line_error(done.stderr), done.stderr


def corrupt_text(data: st.DataObject, text: str) -> bytes:
    """One random corruption of a line-oriented text file."""
    lines = text.splitlines()
    kind = data.draw(st.sampled_from(["cell", "cell", "drop", "copy", "swap", "cut", "bytes",
                                      "column"]), label="kind")
    i = data.draw(st.integers(0, len(lines) - 1), label="line")
    if kind == "cell":
        cells = lines[i].split(",")
        k = data.draw(st.integers(0, len(cells) - 1), label="cell")
        cells[k] = data.draw(st.sampled_from(TOKENS), label="token")
        lines[i] = ",".join(cells)
    elif kind == "drop":
        del lines[i]
    elif kind == "copy":
        lines.insert(i, lines[i])
    elif kind == "swap":
        j = data.draw(st.integers(0, len(lines) - 1), label="other line")
        lines[i], lines[j] = lines[j], lines[i]
    elif kind == "column":
        lines[i] += "," + data.draw(st.sampled_from(TOKENS), label="token")
    raw = ("\n".join(lines) + "\n").encode()
    if kind == "cut":
        raw = raw[: data.draw(st.integers(0, len(raw)), label="cut at")]
    elif kind == "bytes":
        at = data.draw(st.integers(0, len(raw)), label="at")
        raw = raw[:at] + data.draw(st.binary(min_size=1, max_size=8), label="bytes") + raw[at:]
    return raw


@FUZZ
@given(data=st.data())
def test_fuzz_measurement_csv(tiny_set, tmp_path_factory, data):
    name = data.draw(st.sampled_from(["sweeps.csv", "validation.csv"]), label="file")
    folder = tmp_path_factory.mktemp("csv")
    files = {n: tiny_set / n for n in ("setup.toml", "sweeps.csv", "validation.csv")}
    files[name] = folder / name
    files[name].write_bytes(corrupt_text(data, (tiny_set / name).read_text()))
    done = run_cli(["fit", str(files["setup.toml"]), str(files["sweeps.csv"]), "--validation",
                    str(files["validation.csv"]), "-o", str(folder / "m.json")],
                   memory_bytes=2 * GB)
    assert_result_or_one_line_error(done)
    assert (folder / "m.json").exists() == (done.returncode in (0, 3))


SETUP_VALUES = ["1e308", "nan", "inf", "-1", "0", '"IRB120-3/0.58"', '"X"', "[1e308, 0, 0]",
                "[0.06, 0.08, 0.09]", "[1, 2]", "true", '"60"', "[]", "{}", "1e-320"]


@FUZZ
@given(data=st.data())
def test_fuzz_setup_file(tiny_set, tmp_path_factory, data):
    folder = tmp_path_factory.mktemp("setup")
    text = (tiny_set / "setup.toml").read_text()
    if data.draw(st.booleans(), label="value or text"):
        lines = text.splitlines()
        i = data.draw(st.integers(0, len(lines) - 1), label="line")
        key = lines[i].split("=", 1)[0].strip()
        lines[i] = f"{key} = {data.draw(st.sampled_from(SETUP_VALUES), label='value')}"
        raw = ("\n".join(lines) + "\n").encode()
    else:
        raw = corrupt_text(data, text)
    (folder / "setup.toml").write_bytes(raw)
    done = run_cli(["fit", str(folder / "setup.toml"), str(tiny_set / "sweeps.csv"), "-o",
                    str(folder / "m.json")], memory_bytes=2 * GB)
    assert_result_or_one_line_error(done)


@pytest.fixture(scope="module")
def tiny_model(tiny_set, tmp_path_factory):
    out = tmp_path_factory.mktemp("tiny_model") / "model.json"
    done = run_cli(["fit", str(tiny_set / "setup.toml"), str(tiny_set / "sweeps.csv"), "-o",
                    str(out)])
    assert done.returncode in (0, 3), done.stderr
    return out


def _leaves(doc, path=()):
    """Paths to every value of a JSON document (containers included)."""
    yield path
    if isinstance(doc, dict):
        for key, value in doc.items():
            yield from _leaves(value, (*path, key))
    elif isinstance(doc, list):
        for i, value in enumerate(doc):
            yield from _leaves(value, (*path, i))


def corrupt_model(data: st.DataObject, text: str) -> bytes:
    """One random corruption of a model file: a value, a key, a list, or its bytes."""
    doc = json.loads(text)
    # the interesting parts: the effects (the statistics are only printed)
    paths = [p for p in _leaves(doc) if p[:1] in (("effects",), ("robot",), ("format",),
                                                   ("version",))]
    path = data.draw(st.sampled_from(paths), label="path")
    kind = data.draw(st.sampled_from(["value", "value", "delete", "cut list", "bytes"]),
                     label="kind")
    if kind == "bytes":
        raw = text.encode()
        at = data.draw(st.integers(0, len(raw)), label="at")
        return raw[:at] + data.draw(st.binary(max_size=4), label="bytes")
    if not path:
        return b"[]"
    parent = doc
    for key in path[:-1]:
        parent = parent[key]
    last = path[-1]
    if kind == "value":
        parent[last] = data.draw(st.sampled_from(JSON_VALUES), label="value")
    elif kind == "delete":
        del parent[last]
    elif isinstance(parent[last], list) and parent[last]:
        parent[last] = parent[last][: data.draw(st.integers(0, len(parent[last]) - 1))]
    return json.dumps(doc).encode()


@FUZZ
@given(data=st.data())
def test_fuzz_model_file(tiny_model, tmp_path_factory, data):
    folder = tmp_path_factory.mktemp("model")
    (folder / "model.json").write_bytes(corrupt_model(data, tiny_model.read_text()))
    out = folder / "out.mod"
    done = run_cli(["rewrite", str(SAMPLES / "ballbar.mod"), "--model",
                    str(folder / "model.json"), "-o", str(out)], memory_bytes=2 * GB)
    assert_result_or_one_line_error(done)
    assert out.exists() == (done.returncode in (0, 3))
