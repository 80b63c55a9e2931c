"""The model file: exact round trip, versioning, wrong-robot refusal, clear errors."""

import json

import numpy as np
import pytest

from rapidfix.digest import sha256_file
from rapidfix.error_model.joint_rbf import JointRBF, fit_network
from rapidfix.error_model.model import ErrorModel
from rapidfix.error_model.model_file import load_model, save_model
from rapidfix.error_model.registry import effect_from_dict
from rapidfix.exceptions import ModelError

X = np.radians(np.arange(-100.0, 100.1, 5.0))


def _model():
    nets = [None] * 6
    for j in (0, 2, 5):
        nets[j] = fit_network(X, np.radians(0.01 * np.sin(2 * X + j) + 0.003 * j))[0]
    eff = JointRBF(nets, policy="refuse")
    eff.uncertainty = np.full(len(eff.param_names), 1e-6)
    return ErrorModel("IRB1600-10/1.45", [eff], {"joints": [{"joint": 1, "cv_rms_deg": 1e-4}]},
                      [{"name": "sweeps.csv", "sha256": "ab" * 32, "role": "sweeps"}])


def test_round_trip_is_exact(tmp_path):
    model = _model()
    path = save_model(model, tmp_path / "m.json")
    loaded = load_model(path, "IRB1600-10/1.45")
    q = np.radians(np.random.default_rng(0).uniform(-90, 90, (50, 6)))
    assert np.array_equal(loaded.delta(q), model.delta(q))
    eff = loaded.effects[0]
    assert eff.policy == "refuse"
    assert [n is None for n in eff.networks] == [False, True, False, True, True, False]
    assert np.array_equal(eff.params(), model.effects[0].params())
    assert np.array_equal(eff.uncertainty, model.effects[0].uncertainty)
    assert loaded.statistics == model.statistics
    assert loaded.data_files == model.data_files
    doc = json.loads(path.read_text())
    assert (doc["format"], doc["version"]) == ("rapidfix-model", 1)
    assert [p.name for p in tmp_path.iterdir()] == ["m.json"]  # no temporary files left


def test_model_for_another_robot_is_refused(tmp_path):
    path = save_model(_model(), tmp_path / "m.json")
    expected = r"made for robot 'IRB1600-10/1\.45', not 'IRB120-3/0\.58'"
    with pytest.raises(ModelError, match=expected):
        load_model(path, "IRB120-3/0.58")


@pytest.mark.parametrize(
    ("mutate", "message"),
    [
        (lambda d: d.pop("robot"), "missing key 'robot'"),
        (lambda d: d.update(version=2), "version 2 is not supported"),
        (lambda d: d.update(format="other"), "not a rapidfix model file"),
        (lambda d: d["effects"][0].pop("params"), r"effects\[0\]: missing key 'params'"),
        (lambda d: d["effects"][0].update(type="warp_drive"), "unknown effect type 'warp_drive'"),
        (lambda d: d["effects"][0]["params"].pop("j1_offset_rad"), "missing 'j1_offset_rad'"),
        (lambda d: d.update(effects={}), "'effects' should be a list"),
    ],
)
def test_malformed_file_names_the_file_and_the_key(tmp_path, mutate, message):
    path = save_model(_model(), tmp_path / "m.json")
    doc = json.loads(path.read_text())
    mutate(doc)
    path.write_text(json.dumps(doc))
    with pytest.raises(ModelError, match=message) as info:
        load_model(path)
    assert str(path) in str(info.value)


def test_invalid_json_gives_line_and_column(tmp_path):
    path = tmp_path / "m.json"
    path.write_text('{\n  "format": "rapidfix-model",\n  "version": 1,,\n}')
    with pytest.raises(ModelError) as info:
        load_model(path)
    assert info.value.line == 3 and str(path) in str(info.value)


def test_effect_registry_round_trips_by_type_name():
    eff = _model().effects[0]
    again = effect_from_dict(json.loads(json.dumps(eff.to_dict())))
    assert isinstance(again, JointRBF)
    assert np.array_equal(again.params(), eff.params())


def test_free_parameter_vector_is_stacked_and_written_back():
    model = _model()
    p = model.free_params()
    assert len(model.free_param_names()) == p.size
    model.set_free_params(2 * p)
    assert np.array_equal(model.effects[0].params(), 2 * p)
    with pytest.raises(ValueError):
        model.set_free_params(p[:-1])


def test_sha256_matches_hashlib_of_the_bytes(tmp_path):
    import hashlib

    path = tmp_path / "a.csv"
    path.write_bytes(b"x,y\n1,2\n" * 10000)
    assert sha256_file(path) == hashlib.sha256(path.read_bytes()).hexdigest()
