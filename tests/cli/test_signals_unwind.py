"""A signal whose exception lands in a callback Python calls for itself is not lost.

SIGTERM's handler raises `Terminated` wherever the main thread is. In a weak
reference's callback (the import system's module locks have them), in a `__del__`,
Python cannot raise it: it printed "Exception ignored ... Traceback" and went on, and a
batch stopped with SIGTERM went on writing (seen once in CI, under load). The CLI's
hook delivers the signal again to what runs next, and prints nothing.
"""

from __future__ import annotations

import signal
import sys
import time
import weakref

import pytest

from rapidfix import cli


class _Held:
    pass


@pytest.mark.parametrize("raised", [cli.Terminated, KeyboardInterrupt])
def test_a_signal_raised_in_a_callback_reaches_the_main_flow(raised, capfd):
    # Ctrl-C raises KeyboardInterrupt where SIGINT has Python's handler: a process started
    # in the background of a script has SIGINT ignored, and no KeyboardInterrupt at all
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        _raised_in_a_callback(raised)
    finally:
        signal.signal(signal.SIGINT, previous)
    err = capfd.readouterr().err
    assert "Traceback" not in err and "Exception ignored" not in err


def _raised_in_a_callback(raised: type[BaseException]) -> None:
    with cli.signals_unwind():
        held = _Held()

        def callback(_ref):
            raise raised()

        ref = weakref.ref(held, callback)
        waited = None
        with pytest.raises(raised):
            start = time.monotonic()
            del held  # the callback runs here, and its exception cannot go up
            while time.monotonic() - start < 5:
                waited = time.monotonic() - start
        assert ref() is None
    assert waited is not None and waited < 5  # delivered again, not lost


def test_other_exceptions_in_callbacks_go_to_the_hook_there_was(monkeypatch):
    seen = []
    monkeypatch.setattr(sys, "unraisablehook", lambda unraisable: seen.append(
        type(unraisable.exc_value)))
    with cli.signals_unwind():
        held = _Held()

        def callback(_ref):
            raise ValueError("a bug in a callback")

        ref = weakref.ref(held, callback)
        del held
        assert ref() is None
    assert seen == [ValueError]
