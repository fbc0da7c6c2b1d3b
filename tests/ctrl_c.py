"""Ctrl-C in tests, pressed on events of the computation under test, never after a delay.

``_thread.interrupt_main()`` does what a real Ctrl-C does (it trips SIGINT; the next check of
the signal handlers runs the handler). A thread presses it; when is decided by events, so a
loaded machine changes how much work is done before the press is heard, not where:

* ``arm()``: the computation's own callback (a progress report, the N-th evaluation of a
  torque function) allows the press of a ``CtrlC(armed=False)`` (by default it is allowed at
  once); without ``inside``, ``arm()`` presses it itself: the callback hears it;
* ``inside``: the name of a compiled call (``"shaking"``, ``"simulate"``, ...) the press must
  land in. The thread presses only while the main thread is inside that call (seen through
  ``sys.setprofile``'s ``c_call`` / ``c_return``), and the handler counts only the times the
  call itself heard it (its poll of the signal handlers, from the frame that made the call);
  the ``polls``-th raises ``KeyboardInterrupt``, the others are pressed again. The library
  polls at most once per unit of work (a state, a step), so ``polls=2`` means some work was
  done before the call stopped.
"""

from __future__ import annotations

import _thread
import signal
import sys
import threading

import pytest


def _noop() -> None:
    """A Python call: its start checks the signal handlers."""


class CtrlC:
    def __init__(self, inside: str | None = None, polls: int = 1, armed: bool = True):
        self.inside, self.polls = inside, polls
        self.heard = 0            # presses the call heard (counted by the handler)
        self.ended = None         # how the `inside` call ended: "c_return" or "c_exception"
        self._cond = threading.Condition(threading.RLock())
        self._armed, self._pending, self._done, self._raised = armed, False, False, False
        self._caller = None       # the frame that called `inside`, while the call runs

    def arm(self) -> None:
        """Allows the press. Without ``inside`` it is pressed here, so the callback that arms
        hears it (Python checks the signal handlers after each call) before it returns."""
        with self._cond:
            self._armed = True
            self._cond.notify_all()
            if self.inside is None and not (self._pending or self._done):
                self._pending = True
                _thread.interrupt_main()

    def _watch(self) -> None:
        with self._cond:
            while not (self._done or self._raised):
                inside = self.inside is None or self._caller is not None
                if self._armed and inside and not self._pending:
                    self._pending = True
                    _thread.interrupt_main()
                self._cond.wait()

    def _handler(self, signum, frame) -> None:
        with self._cond:
            self._pending = False
            counted = not self._done and (
                self.inside is None or (self._caller is not None and frame is self._caller))
            if counted:
                self.heard += 1
                self._raised = self.heard >= self.polls
            self._cond.notify_all()
            stop = counted and self._raised
        if stop:
            raise KeyboardInterrupt

    def _profile(self, frame, event, arg) -> None:
        if getattr(arg, "__name__", None) != self.inside:
            return
        with self._cond:
            if event == "c_call" and self._caller is None:
                self._caller = frame
            elif event in ("c_return", "c_exception") and frame is self._caller:
                self._caller, self.ended = None, event
            self._cond.notify_all()

    def run(self, call) -> KeyboardInterrupt:
        """``call()`` under this Ctrl-C: the ``KeyboardInterrupt`` it raised (a failure if it
        ended before it heard the press)."""
        error = self.attempt(call)
        if error is None:
            pytest.fail(f"the computation ended before it heard Ctrl-C (heard {self.heard} "
                        f"of {self.polls}): give it more work")
        return error

    def attempt(self, call) -> KeyboardInterrupt | None:
        """``call()`` under this Ctrl-C: the ``KeyboardInterrupt`` it raised, or ``None`` if
        it ended first."""
        previous = signal.signal(signal.SIGINT, self._handler)
        watcher = threading.Thread(target=self._watch, daemon=True)
        profile = sys.getprofile()
        error = None
        watcher.start()
        if self.inside is not None:
            sys.setprofile(self._profile)
        try:
            call()
        except KeyboardInterrupt as e:
            error = e
        finally:
            sys.setprofile(profile)
            with self._cond:
                self._done = True
                self._cond.notify_all()
            watcher.join()
            while self._pending:  # a press not heard yet: heard here, by our handler
                _noop()
            signal.signal(signal.SIGINT, previous)
        return error
