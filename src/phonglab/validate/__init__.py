"""Physics conformance of any Mitsuba 3 plugin: one validator per kind, and its report.

The kinds are listed once, in :data:`~.registry.KINDS` (:mod:`.registry`; what a kind is:
:mod:`.kind`); this face gives each its ``validate_<kind>`` function (the kind's
:attr:`~.kind.Kind.function`) and :func:`validate`, which detects the kind.  The runner is
kind-independent (:mod:`.core`: guarded topics, Šidák over the statistical rows, KNOWN causes
(:mod:`.known`), the report) and so is the parameter sweep (:mod:`.sweep`); a kind's folder
brings its topics (its record's :attr:`~.kind.Kind.topics`, one module per topic family).

Rows and reports: :mod:`phonglab.verdict`; user input: :mod:`.inputs` and
:mod:`phonglab.settings`; Mitsuba's built-ins and their findings: each kind's ``builtins`` module; many
cases as jobs: :mod:`.batch`.  Importing this package does not import Mitsuba (the CLI
starts fast); the validators do.
"""

from ..verdict import Report
from .registry import KINDS, detect

__all__ = ["KINDS", "validate", *(k.function for k in KINDS)]


def validate(spec, *, variant=None, params=None, plugins=(), sweep=True, runner=None,
             **options) -> Report:
    """Validate ``spec`` as the plugin kind it is (:func:`~.registry.detect`): the variant
    set, the ``plugins`` files run once, the plugin loaded once, then checked across its
    kind's parameter sweep (``sweep=False``: at the given point).  ``options``: topics, seed,
    quick, known, family, sizes, progress (:func:`phonglab.validate.pipeline.validate`)."""
    from . import pipeline  # lazy: imports Mitsuba

    return pipeline.validate(spec, variant=variant, params=params, plugins=plugins,
                             sweep=sweep, runner=runner, **options)


def _face(kind):
    """``validate_<kind>``: one plugin of ``kind`` on every topic of its kind."""

    def validate_kind(spec, *, params=None, sweep=False, **options) -> Report:
        from . import pipeline  # lazy: imports Mitsuba

        params = kind.with_load_options(params, options)
        return pipeline.validate(spec, kind=kind, params=params, sweep=sweep, **options)

    validate_kind.__name__ = validate_kind.__qualname__ = kind.function
    validate_kind.__doc__ = (
        f"Validate {kind.article} {kind.word} on every topic of its kind "
        f"({', '.join(kind.topics)}); one :class:`~phonglab.verdict.Report`.\n\n"
        f"``spec``: a plugin type name, a dict for ``mi.load_dict``, an XML file holding one "
        f"``<{kind.tag}>``, or a loaded ``mi.{kind.class_name}``; ``params`` are added to a "
        f"name's or dict's parameters"
        + "".join(f", and so is ``{o}``" for o in kind.load_options)
        + ".  ``plugins``: Python files that call ``" + kind.register + "``, run once after "
        "``variant`` is set.  ``known``: topic -> documented causes (a failing row is KNOWN "
        "when every failing lane lies in a cause's signature), or ``\"builtin\"``: the "
        "findings of the Mitsuba built-in that is loaded, however it was given, and those a "
        "wrapper inherits from its built-in children (:mod:`phonglab.validate.builtin`).  ``sweep``: every point of the "
        "parameter sweep (:mod:`phonglab.validate.sweep`; ``params`` pinned, ``runner`` says "
        "where the points run), not the given point alone.  ``topics``, ``seed``, ``quick``, "
        "``family``, ``sizes``: :func:`phonglab.validate.core.run`.  Bad input raises "
        ":class:`~phonglab.validate.inputs.ValidateError` with one sentence.")
    return validate_kind


for _kind in KINDS:
    globals()[_kind.function] = _face(_kind)
