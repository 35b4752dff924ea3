"""The errors phonglab raises for its users: each message is one sentence naming the problem and the fix.

The command line prints such an error as one line and exits with status 2 (``--debug``
shows the traceback); a Python caller can catch :class:`PhonglabError` for all of them.

* :class:`SceneError`   a scene that cannot be found, parsed or loaded;
* :class:`ExrError`     a file that is not a readable OpenEXR image, or an image EXR cannot hold;
* :class:`CompareError` two images (or an image and its standard-error map) that cannot be compared;
* :class:`PlanError`    a render plan that cannot be made;
* :class:`WriteError`   an output that could not be written to the end (full disk, file too
  large, I/O error): the previous file at that path is left as it was.

An unphysical material is reported by the plugins themselves as
``phonglab.plugins._common.MaterialError`` (a ``ValueError``): plugins import only Mitsuba,
Dr.Jit and numpy, so that class cannot derive from :class:`PhonglabError`; :func:`user_errors`
lists it beside the others.
"""

from __future__ import annotations


class PhonglabError(Exception):
    """An error for the user: one sentence saying what is wrong and how to fix it."""


class SceneError(PhonglabError):
    """A scene file that is missing, malformed, or that Mitsuba cannot load."""


class ExrError(PhonglabError, ValueError):
    """A file that is not a readable OpenEXR image, or an image EXR cannot hold."""


class CompareError(PhonglabError, ValueError):
    """Two images (or an image and its standard-error map) that cannot be compared."""


class PlanError(PhonglabError):
    """A render plan that cannot be made (no variant for the scene's colour model, ...)."""


def user_errors() -> tuple[type[BaseException], ...]:
    """Exception types whose message is written for the user (no traceback needed).

    ``ValueError`` is included because Mitsuba's Python bindings and argument parsing report
    bad values with it; ``--debug`` shows the traceback of any of them.
    """
    from .plugins._common import MaterialError  # lazy: importing the plugins imports Mitsuba

    return (PhonglabError, FileNotFoundError, ValueError, MaterialError)


class WriteError(PhonglabError, RuntimeError):
    """An output that could not be written completely; the previous file is unchanged."""
