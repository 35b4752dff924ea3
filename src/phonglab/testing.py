"""Helpers for the test suites of BSDF authors: one line validates a BSDF inside pytest.

::

    # test_mybsdf.py, beside mybsdf.py
    from pathlib import Path

    from phonglab.testing import assert_bsdf_valid

    HERE = Path(__file__).parent      # the plugin file whatever the working directory

    def test_mybsdf_is_physical():
        assert_bsdf_valid("mybsdf", plugins=[HERE / "mybsdf.py"], quick=True)

The options are those of :func:`phonglab.validate.validate_bsdf` (variant, params, topics,
seed, quick, known, plugins).  On failure the AssertionError's message is the table of the
failing rows, so pytest shows what is wrong and where.
"""

from __future__ import annotations

from .validate import validate_bsdf

__all__ = ["assert_bsdf_valid"]


def assert_bsdf_valid(spec, **options):
    """Validate ``spec``; raise AssertionError listing the failing rows. Returns the report."""
    report = validate_bsdf(spec, **options)
    if not report.passed:
        raise AssertionError(f"{report.meta.get('bsdf', spec)} failed "
                             f"{len(report.failing)} check(s) in {report.meta.get('variant')}:\n"
                             + report.table(report.failing))
    return report
