"""The report's plain statement for each outcome (accepted, at the noise floor, unexplained)."""

from types import SimpleNamespace

from rapidfix.diagnose.report import statement


def _selection(before_mm, floor_mm, accepted=(), after_mm=None):
    def stage(mean):
        return SimpleNamespace(validation=SimpleNamespace(mean_mm=mean))

    trials = [SimpleNamespace(kind=k) for k in accepted]
    return SimpleNamespace(
        before=stage(before_mm),
        floor_mm=floor_mm,
        accepted=trials,
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
