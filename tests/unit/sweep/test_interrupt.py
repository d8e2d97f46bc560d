"""Ctrl-C is never lost and never printed as a traceback (issue 13, B18)."""
import gc
import os
import signal

import pytest

from screening.sweep.interrupt import (deferred_interrupt, interrupt_guard, interruptible, interrupted,
                                       raise_if_interrupted, shielded)


class _RaisesInDel:
    """Stands for dask's GC callback: a Ctrl-C landing in it is 'ignored' by Python."""

    def __del__(self):
        raise KeyboardInterrupt


def test_interrupt_swallowed_by_a_finalizer_is_silent_and_remembered(capsys):
    with interrupt_guard():
        _RaisesInDel()
        gc.collect()
        assert interrupted()
        with pytest.raises(KeyboardInterrupt):
            raise_if_interrupted()
    assert capsys.readouterr().err == ""
    assert not interrupted()            # nothing leaks into the next run in this process
    raise_if_interrupted()


def test_other_ignored_exceptions_still_reach_the_previous_hook(monkeypatch):
    import sys

    seen = []
    monkeypatch.setattr(sys, "unraisablehook", lambda u: seen.append(type(u.exc_value).__name__))

    class Fails:
        def __del__(self):
            raise ValueError("boom")

    with interrupt_guard():
        Fails()
        gc.collect()
        assert not interrupted()
    assert seen == ["ValueError"]


def test_sigint_raises_at_once_and_the_handler_is_restored():
    before = signal.getsignal(signal.SIGINT)
    with pytest.raises(KeyboardInterrupt), interrupt_guard():
        os.kill(os.getpid(), signal.SIGINT)
        for _ in range(10**6):          # the handler runs between bytecodes
            pass
    assert signal.getsignal(signal.SIGINT) is before


def test_deferred_interrupt_holds_the_press_back():
    with deferred_interrupt() as pressed:
        os.kill(os.getpid(), signal.SIGINT)
        for _ in range(10**5):
            pass
    assert pressed == [True]
    assert not interrupted()


def _press():
    os.kill(os.getpid(), signal.SIGINT)
    for _ in range(10**5):              # the handler runs between bytecodes
        pass


def test_shielded_block_records_and_raises_only_where_safe():
    reached = []
    with pytest.raises(KeyboardInterrupt), interrupt_guard():
        with shielded():
            _press()                    # lands in "dask code": recorded only
            reached.append("after the press")
            for item in interruptible([1, 2]):
                reached.append(item)    # never: the recorded press is raised before the first wait
    assert reached == ["after the press"]


def test_press_while_waiting_raises_at_once():
    def waits():
        yield 1
        _press()                        # pressed while the next item is being waited for
        reached.append("still waiting")
        yield 2

    reached = []
    with pytest.raises(KeyboardInterrupt), interrupt_guard(), shielded():
        for item in interruptible(waits()):
            reached.append(item)
    assert reached == [1]


def test_shielded_block_raises_when_it_ends():
    with pytest.raises(KeyboardInterrupt), interrupt_guard():
        with shielded():
            _press()
        pytest.fail("the recorded press must be raised when the shielded block ends")
