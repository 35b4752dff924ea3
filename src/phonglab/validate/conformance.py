r"""The records of the conformance tables, one per plugin kind: what ``make conformance``
(scripts/conformance.py ``--all-kinds``, or ``--kind NAME`` for one) runs, and what
docs/conformance*.md are rendered from (:mod:`phonglab.validate.markdown`).

A :class:`Catalogue` names a kind's cases, its documented Mitsuba findings (:class:`Finding`,
matched by signature), its open validator issues and the 3.9.1 plugins it leaves
out; what it is the table of -- the kind's name, words, topics, validator and the path of its
table -- is its :class:`~phonglab.validate.kind.Kind` (:attr:`Catalogue.kind`).  Each kind's
table is its ``catalogue`` part, in its folder's ``builtins`` module, given its kind by
:func:`phonglab.validate.registry.catalogue` (a kind's implementation cannot import its own
record: the record imports it).  Its cases are :class:`KindCase` (keyword options of their
validator, e.g. an area emitter's shape) or a kind's own case type with the same ``label``,
``spec``, ``known``, ``note``, ``plugin``, ``resolved_variant()`` and ``meta()``.

A :class:`Finding` pins a row that fails in Mitsuba to its source line (``file:line`` at tag
v3.9.1, commit :data:`MITSUBA_COMMIT`) and a short excerpt of the code there (which
scripts/check_citations.py checks against a v3.9.1 source tree), one sentence of cause, what the probe measures, what a
correct plugin gives and a reproducer in ``tests/repro/`` that exits 1 while the behaviour is
present; :func:`known_causes` turns findings into the ``known`` entries of the cases (their
rows are reported as KNOWN).  A :class:`ValidatorIssue` is a row traced to the validator (it
stays a fail in the JSON) while the validator's fix is open; the fixed ones are told in
docs/validator-fixes.md.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any, Callable

from .. import runtime
from .kind import Kind
from .known import Known


#: Mitsuba release the catalogue and the source lines refer to (tag v3.9.1).
MITSUBA_VERSION = "3.9.1"
#: The release commit the annotated tag v3.9.1 points to (``git rev-parse v3.9.1^{commit}``;
#: not ``a8c3ffd763c8…``, the tag object itself).
MITSUBA_COMMIT = "478e193a183c21723f4a8251afc3ad29a8da4c5e"
SOURCE_URL = f"https://github.com/mitsuba-renderer/mitsuba3/blob/v{MITSUBA_VERSION}/"


@dataclass(frozen=True)
class Finding:
    """A row that fails for a reason in Mitsuba 3.9.1 itself, pinned to its source line."""

    key: str                 #: short id, e.g. ``roughplastic-pdf-below-horizon``
    topic: str               #: the validator topic that fails
    labels: tuple[str, ...]  #: the cases it affects
    source: str              #: ``path/in/mitsuba3.cpp:LINE`` at tag v3.9.1
    cause: str               #: one sentence: what that line does wrong (or why it is by design)
    measured: str            #: what the probe measures
    expected: str            #: what a correct plugin gives
    reproducer: str          #: tests/repro/<script>.py: exits 1 while the behaviour is present
    bug: bool = True         #: False: intended behaviour of the model, documented as KNOWN
    #: the names of the rows it explains (a parameter name also matches ``nested.<name>``)
    rows: tuple[str, ...] = ()
    #: the failing lanes it explains (:mod:`phonglab.validate.bsdf.signatures`); None: all
    region: Any = None
    #: parameter values it holds at ((name, value) or (name, (lo, hi)), ...; () -- every point)
    at: tuple[tuple[str, Any], ...] = ()
    #: load-time settings its cause lives in ((name, value), ...; e.g. a BSDF's microfacet
    #: ``distribution``): validated away from the table, it explains nothing where the user's
    #: settings differ (() -- whatever they are)
    given: tuple[tuple[str, str], ...] = ()
    #: a short, distinctive fragment of the code at :attr:`source` (whitespace runs count as
    #: one space), e.g. ``opacity = sample_transmission ? 1.f : 0.f``: scripts/check_citations.py
    #: checks that the cited line holds it, in a v3.9.1 source tree (or, for the headers, the
    #: ones the mitsuba wheel ships)
    excerpt: str = ""

    def known_text(self) -> str:
        """The ``known`` entry of a case: ``file:line: cause``."""
        return f"{self.source}: {self.cause}"

    def known(self) -> Known:
        """The case's :class:`~phonglab.validate.known.Known`: the cause with its signature."""
        return Known(self.known_text(), self.rows, self.region, self.key, self.at)


@dataclass(frozen=True)
class ValidatorIssue:
    """A failing row traced to the validator itself, not to Mitsuba, whose fix in the validator
    is open (the row stays a fail in the JSON; the table names the issue beside it)."""

    key: str
    topic: str
    labels: tuple[str, ...]
    explanation: str         #: what the validator did wrong, with the measurement showing it
    statuses: tuple[str, ...] = ("fail",)   #: the row statuses it explains


@dataclass(frozen=True)
class KindCase:
    """One emitter or integrator at one setting."""

    label: str                       #: unique, e.g. ``area (sphere)``
    spec: Any                        #: the ``mi.load_dict`` dictionary
    variant: str | None = None       #: None: phonglab's default (``llvm_ad_rgb``)
    #: topic -> the documented causes (``Known``, with their signatures) of rows known to fail
    known: dict[str, tuple] = field(default_factory=dict)
    note: str = ""                   #: what the setting exercises, for the table
    #: keyword arguments of the kind's validator beyond spec and variant (``shape``)
    options: dict[str, Any] = field(default_factory=dict)
    #: why the case is reported as one skipped row instead of being validated ("" -- it runs)
    skip: str = ""

    @property
    def plugin(self) -> str:
        """The plugin type at the top of the spec."""
        return self.spec["type"]

    def resolved_variant(self) -> str:
        """The variant the case runs in."""
        return self.variant or runtime.default_variant()

    def meta(self) -> dict:
        """What the case adds to its report's meta (:func:`phonglab.validate.batch.run_case`)."""
        return {"note": self.note}


#: What regenerates every conformance table (the Makefile's target).
COMMAND = "make conformance"


@dataclass(frozen=True)
class Catalogue:
    """Everything one kind's conformance table needs."""

    cases: Callable[[], list]        #: every case, in table order
    cases_name: str                  #: where :attr:`cases` lives, for the markdown
    findings: tuple[Finding, ...]
    findings_name: str               #: where :attr:`findings` lives, for the markdown
    validator_issues: tuple[ValidatorIssue, ...]
    left_out: dict[str, str]
    tests: str                       #: the test file whose slow tier runs the reproducers
    #: how the markdown's header describes one case ("one BSDF at one parameter setting")
    case_text: str
    #: whether ``make conformance`` runs each case through its parameter sweep (else at its
    #: given point only)
    sweep: bool = True
    #: the kind it is the table of (:func:`phonglab.validate.registry.catalogue` gives it)
    kind: Kind | None = None

    @property
    def markdown(self) -> str:
        """The committed markdown (docs/...md, the kind's :attr:`~.kind.Kind.conformance`)."""
        return self.kind.conformance

    @property
    def json(self) -> str:
        """The committed JSON the markdown is rendered from, beside it."""
        return self.markdown.removesuffix(".md") + ".json"

    def open_issues(self) -> dict[tuple[str, str], ValidatorIssue]:
        """(label, topic) -> the open validator issue explaining that row's fail."""
        return {(label, v.topic): v for v in self.validator_issues for label in v.labels}

    def find(self, label: str):
        for c in self.cases():
            if c.label == label:
                return c
        raise KeyError(f"no case labelled {label!r} in the table of {self.cases_name}")


def with_known(cases: list, findings: tuple[Finding, ...]) -> list:
    """``cases`` with each one's ``known`` extended by the findings naming its label."""
    known = known_causes(findings)
    return [replace(c, known={**c.known, **known.get(c.label, {})}) for c in cases]


def known_causes(findings) -> dict[str, dict[str, tuple[Known, ...]]]:
    """label -> {topic: (Known, ...)} from ``findings``, each with its signature."""
    out: dict[str, dict[str, tuple[Known, ...]]] = {}
    for f in findings:
        for label in f.labels:
            topics = out.setdefault(label, {})
            topics[f.topic] = topics.get(f.topic, ()) + (f.known(),)
    return out


def known_of(cases, plugin: str, keep=lambda case: True) -> dict[str, tuple]:
    """topic -> every documented cause of the ``cases`` of ``plugin`` (a type name) that
    ``keep`` accepts, each once: the findings of a built-in validated outside its table."""
    out: dict[str, tuple] = {}
    for case in cases:
        if case.plugin != plugin or getattr(case, "skip", "") or not keep(case):
            continue
        for topic, causes in case.known.items():
            out[topic] = out.get(topic, ()) + tuple(c for c in causes
                                                    if c not in out.get(topic, ()))
    return out
