"""Helpers for the test suites of plugin authors: one line validates a plugin inside pytest.

::

    # test_mybsdf.py, beside mybsdf.py
    from pathlib import Path

    from phonglab.testing import assert_bsdf_valid

    HERE = Path(__file__).parent      # the plugin file whatever the working directory

    def test_mybsdf_is_physical():
        assert_bsdf_valid("mybsdf", plugins=[HERE / "mybsdf.py"], quick=True)

There is one helper per kind of :data:`phonglab.validate.registry.KINDS`
(``assert_<kind>_valid``), and :func:`assert_valid`, which detects the kind.  The options are
those of the kind's validator (:func:`phonglab.validate.validate_bsdf`: variant, params, topics,
seed, quick, known, plugins); by default the plugin is checked across its kind's parameter
sweep (:mod:`phonglab.validate.sweep`; ``params`` are pinned), ``sweep=False`` checks the given
point alone.  On failure the AssertionError's message is the table of the failing rows, grouped by
the parameter point they failed at, so pytest shows what is wrong and where.
:func:`assert_emitter_valid` does the same for an emitter
(:func:`phonglab.validate.validate_emitter`; ``shape`` attaches an area emitter to a shape)::

    assert_emitter_valid("mylight", plugins=[HERE / "mylight.py"], quick=True)

:func:`assert_integrator_valid` does the same for an integrator
(:func:`phonglab.validate.validate_integrator`)::

    assert_integrator_valid("mypath", plugins=[HERE / "mypath.py"], quick=True)
"""

from __future__ import annotations

from .validate import KINDS
from .verdict import point_label, table

__all__ = ["assert_valid", *(k.assert_helper for k in KINDS)]


def assert_valid(spec, kind: str | None = None, sweep: bool = True, timeout=None,
                 allow_uncovered: bool = False, **options):
    """Validate ``spec`` (of ``kind``, e.g. "bsdf"; None: detected) across its kind's parameter
    sweep (``sweep=False``: at the given point alone; a kind without a sweep is checked at the
    given point); raise AssertionError listing the failing rows, each with its point, or --
    unless ``allow_uncovered`` -- naming the applicable topics that judged nothing (every row
    skipped: :func:`phonglab.validate.core.not_covered`) with their skip reasons.
    ``timeout``: seconds a topic may run before it is stopped and becomes a failing row ("did
    not finish within N s"; :func:`phonglab.validate.timeout.topic_timeout`: Python code only, in
    the main thread -- a compiled Dr.Jit kernel runs to its end); loading a plugin file or the
    plugin that takes longer is a ValidateError.  A plugin that calls ``sys.exit`` or
    ``os._exit`` (:func:`phonglab.runtime.exits_intercepted`) is a failing row or an
    AssertionError naming the call, never the end of the test process.  Returns the report."""
    from . import runtime
    from . import validate as face
    from .dispatch import exit_call
    from .validate import registry, validate
    from .validate.timeout import topic_timeout

    try:
        with runtime.exits_intercepted(), topic_timeout(timeout):
            if kind is None:
                report = validate(spec, sweep=sweep, **options)
                kind = report.meta.get("kind") or next(k.name for k in KINDS
                                                       if k.name in report.meta)
            else:
                report = getattr(face, registry.by_name(kind).function)(spec, sweep=sweep,
                                                                         **options)
    except (SystemExit, runtime.PluginExited) as exc:   # never the plugin's status as pytest's
        raise AssertionError(f"{spec}: {exit_call(exc)}, so nothing was judged; a plugin must "
                             f"return or raise, never end the process") from exc
    if not report.passed:
        by_point = {}
        for r in report.failing:
            by_point.setdefault(point_label(r.point) if r.point is not None else "", []).append(r)
        text = "\n".join((f"at {label}:\n" if label else "") + table(rows)
                         for label, rows in by_point.items())
        raise AssertionError(f"{report.meta.get(kind, spec)} failed "
                             f"{len(report.failing)} check(s) in {report.meta.get('variant')}:\n"
                             + text)
    if report.not_covered and not allow_uncovered:
        skipped = [r for r in report.rows if r.topic in report.not_covered]
        raise AssertionError(f"{report.meta.get(kind, spec)}: not covered: "
                             f"{', '.join(report.not_covered)} judged nothing (every row "
                             f"skipped; allow_uncovered=True accepts it):\n" + table(skipped))
    return report


def _helper(kind):
    def assert_kind_valid(spec, sweep: bool = True, timeout=None, allow_uncovered: bool = False,
                          **options):
        return assert_valid(spec, kind.name, sweep, timeout, allow_uncovered, **options)

    assert_kind_valid.__name__ = assert_kind_valid.__qualname__ = kind.assert_helper
    assert_kind_valid.__doc__ = (f"Validate the {kind.word} ``spec`` (:func:`assert_valid`); "
                                 f"raise AssertionError listing the failing rows.")
    return assert_kind_valid


for _kind in KINDS:
    globals()[_kind.assert_helper] = _helper(_kind)
