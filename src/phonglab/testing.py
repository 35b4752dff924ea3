"""Helpers for the test suites of BSDF, emitter and integrator authors: one line validates a
plugin inside pytest.

::

    # test_mybsdf.py, beside mybsdf.py
    from pathlib import Path

    from phonglab.testing import assert_bsdf_valid

    HERE = Path(__file__).parent      # the plugin file whatever the working directory

    def test_mybsdf_is_physical():
        assert_bsdf_valid("mybsdf", plugins=[HERE / "mybsdf.py"], quick=True)

The options are those of :func:`phonglab.validate.validate_bsdf` (variant, params, topics,
seed, quick, known, plugins); by default the BSDF is checked across its parameter sweep
(:mod:`phonglab.validate.sweep`; ``params`` are pinned), ``sweep=False`` checks the given point
alone.  On failure the AssertionError's message is the table of the failing rows, grouped by
the parameter point they failed at, so pytest shows what is wrong and where.
:func:`assert_emitter_valid` does the same for an emitter, at the given point
(:func:`phonglab.validate.validate_emitter`; ``shape`` attaches an area emitter to a shape)::

    assert_emitter_valid("mylight", plugins=[HERE / "mylight.py"], quick=True)

:func:`assert_integrator_valid` does the same for an integrator
(:func:`phonglab.validate.validate_integrator`)::

    assert_integrator_valid("mypath", plugins=[HERE / "mypath.py"], quick=True)
"""

from __future__ import annotations

from .validate import validate_bsdf, validate_emitter, validate_integrator
from .verdict import point_label, table

__all__ = ["assert_bsdf_valid", "assert_emitter_valid", "assert_integrator_valid"]


def assert_bsdf_valid(spec, sweep: bool = True, **options):
    """Validate ``spec`` across its parameter sweep (``sweep=False``: at the given point
    alone); raise AssertionError listing the failing rows, each with its point. Returns the
    report."""
    report = validate_bsdf(spec, sweep=sweep, **options)
    if not report.passed:
        by_point = {}
        for r in report.failing:
            by_point.setdefault(point_label(r.point) if r.point is not None else "", []).append(r)
        text = "\n".join((f"at {label}:\n" if label else "") + table(rows)
                         for label, rows in by_point.items())
        raise AssertionError(f"{report.meta.get('bsdf', spec)} failed "
                             f"{len(report.failing)} check(s) in {report.meta.get('variant')}:\n"
                             + text)
    return report


def assert_emitter_valid(spec, **options):
    """Validate the emitter ``spec``; raise AssertionError listing the failing rows. Returns
    the report."""
    return _passed_or_raise(validate_emitter(spec, **options), "emitter", spec)


def assert_integrator_valid(spec, **options):
    """Validate the integrator ``spec``; raise AssertionError listing the failing rows. Returns
    the report."""
    return _passed_or_raise(validate_integrator(spec, **options), "integrator", spec)


def _passed_or_raise(report, word: str, spec):
    """``report`` when it passed; else AssertionError listing its failing rows."""
    if not report.passed:
        raise AssertionError(f"{report.meta.get(word, spec)} failed "
                             f"{len(report.failing)} check(s) in {report.meta.get('variant')}:\n"
                             + report.table(report.failing))
    return report
