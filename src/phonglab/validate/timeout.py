r"""How long a plugin's Python code may run: a topic, the loading of a plugin or a ``--plugin``
file, each stopped at the limit :func:`topic_timeout` sets for a block.

A topic that runs past it becomes one failing row (:func:`phonglab.validate.core.guarded`),
a plugin or plugin file that loads past it one sentence; a run without a limit has none.
The mechanism, SIGALRM in the main thread, and what it cannot stop: :func:`topic_timeout`.
"""

from __future__ import annotations

import contextlib
import signal
import threading

from .inputs import ValidateError

__all__ = ["TopicTimeout", "alarm", "limit", "topic_timeout", "within_topic_limit"]


class TopicTimeout(BaseException):
    """Raised by SIGALRM inside a topic that ran past :func:`topic_timeout`'s limit.  A
    BaseException, so a plugin's own ``except Exception`` does not swallow it."""


#: The limit of one topic in seconds (None: none), set by :func:`topic_timeout`.
_TIMEOUT: float | None = None


def limit() -> float | None:
    """The limit :func:`topic_timeout` set for the block running now (None: none)."""
    return _TIMEOUT


@contextlib.contextmanager
def topic_timeout(seconds: float | None):
    """For the block, each topic :func:`phonglab.validate.core.run` runs is stopped after
    ``seconds`` and becomes one failing row ("did not finish within N s"); the other topics
    still run.

    How: SIGALRM (``signal.setitimer``), whose Python handler raises :class:`TopicTimeout` in
    the main thread at its next bytecode -- so it stops Python code (a plugin's ``eval`` that
    loops forever), not a compiled Dr.Jit kernel or a C++ call, which run to their end before
    Python sees the signal (a kernel that never ends still hangs).  Only in the main thread and
    on POSIX; elsewhere the limit is not applied.  SIGINT is routed separately
    (:func:`phonglab.runtime.interrupts_routed`) and is not touched."""
    global _TIMEOUT
    if seconds is not None and (isinstance(seconds, bool) or not isinstance(seconds, (int, float))
                                or not seconds > 0 or seconds == float("inf")):
        raise ValidateError(f"the timeout must be a number of seconds > 0, got {seconds!r}")
    old, _TIMEOUT = _TIMEOUT, seconds
    try:
        yield
    finally:
        _TIMEOUT = old


@contextlib.contextmanager
def alarm(seconds: float | None):
    """For the block, SIGALRM after ``seconds`` raises :class:`TopicTimeout`; yields a dict
    whose "fired" says whether it did (a C++ caller in between -- ``mi.render``'s custom op --
    may re-raise it as a RuntimeError).  Inside a block whose timer is still running (loading
    a plugin inside a ``check`` that is itself limited) the outer limit holds and no second
    timer is set."""
    state = {"fired": False}
    if (not seconds or not hasattr(signal, "setitimer")
            or threading.current_thread() is not threading.main_thread()
            or signal.getitimer(signal.ITIMER_REAL)[0] > 0):   # an outer limit holds already
        yield state
        return

    def expired(signum, frame):
        state["fired"] = True
        raise TopicTimeout()

    previous = signal.signal(signal.SIGALRM, expired)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield state
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


def within_topic_limit():
    """:func:`alarm` at the limit :func:`topic_timeout` set (none: no limit), for a call that
    runs a plugin's Python code outside a topic (the return-type check of :mod:`.returns`,
    ``phonglab fit``)."""
    return alarm(_TIMEOUT)
