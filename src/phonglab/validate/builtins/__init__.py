"""Mitsuba 3.9.1's built-in BSDFs under ``phonglab validate --all-builtins``: the catalogue of
cases (:mod:`.catalogue`), the findings registry (:mod:`.findings`: the Mitsuba source lines
behind failing rows, and the validator's own issues) and the writer of docs/conformance.md
(:mod:`.markdown`), apart; :mod:`.kinds` gives the emitter and integrator tables the same
shape (:func:`kind_catalogue`).  This package names what scripts/conformance.py, batch and the
tests use.
"""

from .catalogue import (LEFT_OUT, POLARIZED, SPECTRAL, Case, bump_texture, cases,
                        known_for_plugin, load, normal_texture)
from .findings import (FINDINGS, MITSUBA_COMMIT, MITSUBA_VERSION, SOURCE_URL, VALIDATOR_ISSUES,
                       Finding, ValidatorIssue, known_causes, validator_issues)
from . import kinds
from .kinds import Catalogue, KindCase
from .kinds import catalogue as kind_catalogue   # not `catalogue`: that is the BSDF module
from .markdown import PLOT_ONLY, cell_status, render_markdown, without_plot_data

__all__ = ["Case", "Catalogue", "KindCase", "kind_catalogue", "kinds", "FINDINGS", "Finding", "LEFT_OUT", "MITSUBA_COMMIT", "MITSUBA_VERSION",
           "PLOT_ONLY", "POLARIZED", "SOURCE_URL", "SPECTRAL", "VALIDATOR_ISSUES",
           "ValidatorIssue", "bump_texture", "cases", "cell_status", "known_causes",
           "known_for_plugin", "load",
           "normal_texture", "render_markdown", "validator_issues", "without_plot_data"]
