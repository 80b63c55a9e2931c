"""Model files are validated when loaded (issue #15, item 5): shapes, finiteness and
ranges of every parameter, so a damaged file is refused instead of silently used."""

from __future__ import annotations

import json

import numpy as np
import pytest

from rapidfix.error_model.joint_rbf import JointRBF, fit_network
from rapidfix.error_model.model import ErrorModel
from rapidfix.error_model.model_file import load_model, save_model
from rapidfix.exceptions import ModelError


@pytest.fixture(scope="module")
def model_doc(tmp_path_factory):
    x = np.radians(np.linspace(-90.0, 90.0, 19))
    nets = [fit_network(x, 1e-3 * np.sin(2 * x + j))[0] for j in range(6)]
    path = save_model(ErrorModel("IRB1600-10/1.45", [JointRBF(nets)]),
                      tmp_path_factory.mktemp("m") / "model.json")
    return json.loads(path.read_text())


def _load(doc, tmp_path, text=None):
    path = tmp_path / "m.json"
    path.write_text(text if text is not None else json.dumps(doc))
    return load_model(path)


def test_the_valid_model_loads(model_doc, tmp_path):
    assert _load(model_doc, tmp_path).robot == "IRB1600-10/1.45"


def _copy(doc):
    return json.loads(json.dumps(doc))


def _network(doc, j=0):
    return doc["effects"][0]["state"]["networks"][j]


@pytest.mark.parametrize("value, words", [
    ("NaN", "finite"), ("Infinity", "finite"), ("1" + "0" * 400, "finite"),
    ("1e6", "physical bound"), ('"0.1"', "not a number"), ("true", "not a number"),
])
def test_a_bad_weight_is_refused(model_doc, tmp_path, value, words):
    doc = _copy(model_doc)
    doc["effects"][0]["params"]["j2_w004_rad"] = json.loads(value)
    with pytest.raises(ModelError, match=words) as err:
        _load(doc, tmp_path)
    assert "j2_w004_rad" in str(err.value)


def test_cut_centres_are_refused_not_misread(model_doc, tmp_path):
    doc = _copy(model_doc)
    _network(doc)["centres_rad"] = _network(doc)["centres_rad"][:-3]
    with pytest.raises(ModelError, match="centres_rad"):
        _load(doc, tmp_path)


def test_extra_parameters_are_refused(model_doc, tmp_path):
    doc = _copy(model_doc)
    doc["effects"][0]["params"]["j1_w999_rad"] = 0.0
    with pytest.raises(ModelError, match="unexpected 'j1_w999_rad'"):
        _load(doc, tmp_path)


@pytest.mark.parametrize("key, value, words", [
    ("width_rad", -0.1, "positive"),
    ("width_rad", float("nan"), "finite|positive"),
    ("smoothing", -1.0, "not negative"),
    ("range_rad", [1.0, -1.0], "interval"),
    ("range_rad", [-1e3, 1e3], "10 turns"),
    ("range_rad", [0.0], "interval"),
    ("cv_rms_rad", -1.0, "not negative"),
])
def test_bad_network_state_is_refused(model_doc, tmp_path, key, value, words):
    doc = _copy(model_doc)
    _network(doc, 3)[key] = value
    with pytest.raises(ModelError, match=words) as err:
        _load(doc, tmp_path)
    assert "networks[3]" in str(err.value) or "joint 4" in str(err.value)


def test_a_nan_anywhere_in_the_state_is_refused(model_doc, tmp_path):
    doc = _copy(model_doc)
    _network(doc, 5)["centres_rad"][2] = float("nan")
    with pytest.raises(ModelError):
        _load(doc, tmp_path)
