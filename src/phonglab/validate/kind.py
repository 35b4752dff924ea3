r"""What a plugin kind is: one :class:`Kind` record, all the validator needs to know of it.

A plugin kind is one folder of :mod:`phonglab.validate` and one line of
:data:`phonglab.validate.registry.KINDS`; no other module names it.  Its folder's ``__init__``
declares its :class:`Kind` (no Mitsuba import: the command line builds its help and checks its
input from these records); its *implementation module* (the folder's ``kind`` module, which imports
Mitsuba: the zero-argument function :attr:`Kind.implementation` the folder gives its record
imports it when a part is first asked for) holds the parts that run, looked up by name with
:meth:`Kind.part`:

==================  ==========================================================================
``options``         (quick, seed, topics) -> the sizes of a run
``statistical_tests``  (target, options, topics) -> m, the statistical tests a run makes
``runners``         (target, options, topics, m) -> {topic: () -> rows}
``load``            (spec, params, hint) -> :class:`~phonglab.settings.Loaded`: the plugin
                    loaded and wrapped in what its topics probe (an emitter attached to a
                    shape, an integrator rebuilt per scene); default: the plugin itself
``parameters``      (target, spec, pinned) -> the parameters a sweep varies (each with
                    ``name``, ``value``, ``range``, ``source``); absent: the kind is checked
                    at its given point only
``domain``          (target, spec) -> ({name: Range}, source): the declared or documented
                    ranges a ``--set`` value must lie in (absent: none is checked)
``values``          target -> {parameter: value} a documented cause's ``at`` is held against
``known_for``       (type name, params) -> {topic: causes}: the conformance table's findings
                    of a Mitsuba built-in named by its type
``identify``        (plugin, spec, origin) -> (type name, params) of the Mitsuba built-in a
                    loaded object is, None for any other (:mod:`.builtin`: a built-in's
                    findings follow what is loaded, not how it was named)
``children``        plugin -> [(path, child)]: the plugins of the kind it holds (a wrapper's
                    nested BSDF), whose findings its rows may inherit (:mod:`.builtin`)
``catalogue``       () -> its conformance table (:class:`~.conformance.Catalogue`; the table
                    is given its kind by :func:`.registry.catalogue`)
``returns``         (plugin, label) -> None: the types its Python methods return, checked on
                    one lane right after the default load (:mod:`.returns`); a mismatch is a
                    :class:`ValidateError`
``session``         () -> a context manager around a whole run (every point of a sweep):
                    what its topics keep across points, closed when it ends (a BSDF's
                    unpolarized reference process, :func:`.bsdf.intensity.session`)
``in_scene``        scene -> the plugins of the kind a loaded scene holds at its top (a
                    scene's shapes' materials): ``validate scene.xml --<tag> ID`` picks one
                    by id (:func:`.builtin.scene_object`); for a kind whose record names
                    :attr:`Kind.scene_noun`
==================  ==========================================================================

The kind's public validator, ``validate_<name>`` (``validate_bsdf``), is made by the package
face (:mod:`phonglab.validate`) from the record: the same function for every kind, keyword
options of its own (an emitter's ``shape``) named by :attr:`Kind.load_options`.

A field given on the record itself (a test's toy kind) takes the place of the module's part.
:func:`topic_row` makes a kind's row type from its topics, so no kind copies one.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable
from urllib.parse import urljoin

from .. import verdict
from ..errors import PhonglabError


class ValidateError(PhonglabError):
    """A plugin, plugin file, parameter or topic the validator cannot use."""


def _docs_url() -> str | None:
    """``$PHONGLAB_DOCS_URL``; else, run from a source checkout, the folder ``make docs`` builds
    the site into (``build/docs/``, as a ``file:`` URL); else None."""
    url = os.environ.get("PHONGLAB_DOCS_URL")
    if url:
        return url.rstrip("/") + "/"
    root = Path(__file__).resolve().parent.parent.parent.parent  # above src/ in a checkout
    if (root / "docs" / "conf.py").is_file():
        return (root / "build" / "docs").as_uri() + "/"
    return None


#: The docs site's root, which a row's :attr:`~phonglab.verdict.Row.doc` page is relative to
#: (:func:`_docs_url`): the HTML report links each row's topic to its page there.
DOCS_URL = _docs_url()


def topic_page(kind: str, topic: str) -> str:
    """The page of the docs site on ``topic`` of the kind named ``kind``, relative to its root
    (docs/topics/KIND/TOPIC.md builds it): what a validator row carries as ``doc``."""
    return f"topics/{kind}/{topic}.html"


def topic_url(page: str | None) -> str | None:
    """``page`` (a row's ``doc``) against :data:`DOCS_URL`; None when either is unknown."""
    return urljoin(DOCS_URL, page) if page and DOCS_URL else None


#: The parts :meth:`Kind.part` resolves (module docstring).
PARTS = ("options", "statistical_tests", "runners", "load", "parameters", "domain", "values",
         "known_for", "identify", "children", "catalogue", "returns", "session", "in_scene")


@dataclass(frozen=True)
class Kind:
    """One plugin kind (module docstring)."""

    name: str                  #: the meta key of the plugin's label and the kind's id ("bsdf")
    word: str                  #: the kind in messages ("BSDF", "phase function")
    plural: str                #: more than one ("BSDFs", "phase functions", "media")
    class_name: str            #: its Mitsuba class ``mi.<class_name>``
    register: str              #: what a ``--plugin`` file calls ("mi.register_bsdf")
    topics: tuple[str, ...]    #: every topic, in table order
    #: topics that measure and never fail (``cost``): a sweep runs them at the given point only
    informational: tuple[str, ...] = ()
    #: topics whose result no swept parameter changes (a medium's nested phase function, which
    #: comes from its properties): a sweep judges them at the given point only
    given_point_only: tuple[str, ...] = ()
    #: topics that hold a physical bound (a BSDF's albedo ≤ 1, an emitter's power) rather than
    #: an identity: a sweep judges them only inside the declared or documented domain, and an
    #: excess at a probed point outside it is advice (:func:`phonglab.validate.sweep.advise`)
    bounds: tuple[str, ...] = ()
    object_type: str = ""      #: its ``mi.ObjectType`` member ("BSDF", "PhaseFunction")
    tag: str = ""              #: its XML element ("bsdf", "phase")
    #: () -> the implementation module that holds its parts (module docstring); the kind's
    #: folder gives one that imports its ``kind`` module when called (None: a toy kind whose
    #: parts are all fields)
    implementation: Callable[[], Any] | None = None
    conformance: str = ""      #: its conformance table (docs/...md)
    #: what one is called as a part of a scene ("material"; "" -- the kind has none to pick
    #: by id): ``phonglab validate scene.xml --<tag> ID`` validates it (its ``in_scene`` part)
    scene_noun: str = ""
    #: keywords of its validator that are load-time parameters (an emitter's ``shape``)
    load_options: tuple[str, ...] = ()
    #: parts given here instead of by :attr:`implementation` (a toy kind in a test)
    options: Callable | None = None
    statistical_tests: Callable | None = None
    runners: Callable | None = None
    parameters: Callable | None = None
    values: Callable | None = None

    @property
    def function(self) -> str:
        """The public validator's name, ``validate_<name>``."""
        return f"validate_{self.name}"

    @property
    def assert_helper(self) -> str:
        """The pytest helper's name in :mod:`phonglab.testing`, ``assert_<name>_valid``."""
        return f"assert_{self.name}_valid"

    @property
    def article(self) -> str:
        return "an" if self.word[0].lower() in "aeiou" else "a"

    def module(self):
        """The implementation module (imports Mitsuba)."""
        return self.implementation()

    def part(self, name: str) -> Any:
        """The part ``name`` (:data:`PARTS`): the record's own field when set, else the
        implementation module's attribute, None when neither has it."""
        own = getattr(self, name, None) if name in self.__dataclass_fields__ else None
        if own is not None:
            return own
        return getattr(self.module(), name, None) if self.implementation else None

    def with_load_options(self, params, options: dict) -> dict | None:
        """``params`` with the validator keywords that are load-time parameters
        (:attr:`load_options`, e.g. an emitter's ``shape``) taken out of ``options`` and added;
        one given both ways is bad input."""
        for name in self.load_options:
            value = options.pop(name, None)
            if value is None:
                continue
            if name in (params or {}):
                raise ValidateError(f"give the {name} once: as {name}= or as --set {name}.*")
            params = {**(params or {}), name: value}
        return params

    def check_topics(self, topics) -> tuple[str, ...]:
        """The topics to run, in table order (all of them when ``topics`` is empty)."""
        return check_topics(topics, self.topics)


def check_topics(topics, table) -> tuple[str, ...]:
    """The topics to run, in ``table`` order (all of ``table`` when ``topics`` is empty)."""
    topics = tuple(topics or table)
    bad = [t for t in topics if t not in table]
    if bad:
        raise ValidateError(f"unknown topic {bad[0]!r}; choose from {', '.join(table)}")
    return tuple(t for t in table if t in topics)


def topic_row(topics: tuple[str, ...], word: str, module: str) -> type[verdict.Row]:
    """A :class:`phonglab.verdict.Row` type whose topic must be one of ``topics``: a misspelt
    topic fails where the row is built, not later in a report.  ``module`` is where the type
    is bound to the name ``Row`` (the kind's topics module), so that it pickles."""

    def __post_init__(self):
        if self.topic not in topics:
            raise ValueError(f"unknown topic {self.topic!r}; choose one of {', '.join(topics)}")
        verdict.Row.__post_init__(self)

    return type("Row", (verdict.Row,), {
        "__post_init__": __post_init__, "__module__": module, "__qualname__": "Row",
        "__doc__": f"A :class:`phonglab.verdict.Row` of one of the {word} kind's topics."})
