"""The report's plain statement for each outcome (accepted, at the noise floor, unexplained)."""

from types import SimpleNamespace

from rapidfix.diagnose.report import alternatives, statement


def _trial(kind, gain, verdict="passes", accepted=False, round_no=1, after=""):
    return SimpleNamespace(kind=kind, delta_bic=gain, verdict=verdict, accepted=accepted,
                           round=round_no, after=after, stage=object())


def _selection(before_mm, floor_mm, accepted=(), after_mm=None, others=()):
    def stage(mean):
        return SimpleNamespace(validation=SimpleNamespace(mean_mm=mean))

    trials = [_trial(k, 100.0, "accepted", True) for k in accepted]
    return SimpleNamespace(
        before=stage(before_mm),
        floor_mm=floor_mm,
        accepted=trials,
        trials=[*trials, *others],
        final=stage(after_mm) if accepted else None,
    )


def test_statement_names_the_effects_and_the_numbers():
    text = statement(_selection(0.126, 0.024, ("joint_compliance", "tool_offset"), 0.031))
    assert "joint_compliance and tool_offset" in text
    assert "0.1260 mm to 0.0310 mm" in text


def test_statement_at_the_noise_floor():
    assert "already at the noise floor" in statement(_selection(0.027, 0.024))
    assert "close to the noise floor" in statement(_selection(0.034, 0.024))


def test_statement_when_nothing_explains_a_large_residual():
    text = statement(_selection(0.300, 0.024))
    assert "No candidate effect explains the residual" in text and "0.3000 mm" in text


def test_an_explanation_the_data_cannot_tell_apart_is_named_beside_the_accepted_one():
    others = [_trial("thermal_drift", 95.0), _trial("link_geometry", 60.0),
              _trial("tool_offset", 99.0, verdict="BIC gain 2 ≤ 10"),
              _trial("joint_coupling", 98.0, round_no=2)]
    sel = _selection(0.065, 0.025, ("registration",), 0.030, others)
    assert alternatives(sel) == {"registration": ["thermal_drift"]}
    text = statement(sel)
    assert "thermal_drift explains it nearly as well as registration" in text
    assert "link_geometry" not in text and "tool_offset" not in text
    assert alternatives(_selection(0.065, 0.025, ("registration",), 0.030)) == {}
