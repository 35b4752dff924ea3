r"""One conformance table per plugin kind: what ``make conformance`` (scripts/conformance.py
``--kind bsdf|emitter|integrator``) runs, and what docs/conformance*.md are rendered from.

A :class:`Catalogue` names a kind's cases, the validator function that checks one case, its
topics, its documented Mitsuba findings (:class:`~.findings.Finding`, matched by signature),
its open and fixed validator issues and the 3.9.1 plugins it leaves out.  The BSDF catalogue
is :mod:`.catalogue`; the emitter and integrator ones are
:mod:`phonglab.validate.emitter.builtins` and :mod:`phonglab.validate.integrator.builtins`,
whose cases are :class:`KindCase` (a BSDF :class:`~.catalogue.Case` has a delta flag and a
sweep; these have keyword options of their validator instead, e.g. an area emitter's shape).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable

from ... import runtime
from .. import registry
from .findings import Finding, ValidatorIssue


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


@dataclass(frozen=True)
class Catalogue:
    """Everything one kind's conformance table needs."""

    kind: str                        #: "bsdf", "emitter" or "integrator"
    noun: str                        #: "BSDFs", "emitters", "integrators" (the title's)
    word: str                        #: one case is one <word> at one setting
    cases: Callable[[], list]        #: every case, in table order
    topics: tuple[str, ...]
    validate: str                    #: the phonglab.validate function name
    cases_name: str                  #: where :attr:`cases` lives, for the markdown
    findings: tuple[Finding, ...]
    validator_issues: tuple[ValidatorIssue, ...]
    left_out: dict[str, str]
    json: str                        #: the committed JSON (docs/...)
    markdown: str                    #: the committed markdown (docs/...)
    command: str                     #: what regenerates them
    #: how the markdown's header describes one case ("... at one parameter setting")
    case_text: str = ""

    def open_issues(self) -> dict[tuple[str, str], ValidatorIssue]:
        """(label, topic) -> the open validator issue explaining that row's fail."""
        return {(label, v.topic): v for v in self.validator_issues if not v.fixed
                for label in v.labels}

    def find(self, label: str):
        for c in self.cases():
            if c.label == label:
                return c
        raise KeyError(f"no built-in {self.kind} case labelled {label!r}")


def with_known(cases: list, findings: tuple[Finding, ...]) -> list:
    """``cases`` with each one's ``known`` extended by the findings naming its label."""
    from dataclasses import replace

    from .findings import known_causes
    known = known_causes(findings)
    return [replace(c, known={**c.known, **known.get(c.label, {})}) for c in cases]


#: The kinds with a conformance table: every kind of :data:`phonglab.validate.registry.KINDS`.
KINDS = registry.names()


def catalogue(kind: str = "bsdf") -> Catalogue:
    """The :class:`Catalogue` of ``kind`` (one of :data:`KINDS`): the kind's ``catalogue`` part."""
    return registry.by_name(kind).part("catalogue")()


def bsdf_catalogue() -> Catalogue:
    """The BSDF kind's table: the cases of :func:`phonglab.validate.builtins.cases` (looked up
    at call time, so a test can patch them) and the findings of :mod:`.findings`."""
    from .. import builtins as package
    from ..bsdf.topics import TOPICS
    from .catalogue import LEFT_OUT
    from .findings import FINDINGS, VALIDATOR_ISSUES
    return Catalogue("bsdf", "BSDFs", "BSDF", lambda: package.cases(), TOPICS, "validate_bsdf",
                     "phonglab.validate.builtins.cases()", FINDINGS, VALIDATOR_ISSUES, LEFT_OUT,
                     "docs/conformance.json", "docs/conformance.md", "make conformance",
                     case_text="one BSDF at one parameter setting")


def _shape_key(shape: dict | None) -> dict:
    """What identifies a surface emitter's shape for its findings: every entry but the file."""
    return {k: v for k, v in (shape or {}).items() if k != "filename"}


def known_for(kind: str, plugin: str, shape: dict | None = None) -> dict[str, tuple]:
    """topic -> the documented causes of the ``kind`` catalogue's cases of ``plugin`` (an
    emitter or integrator type name), for that plugin validated outside the table (``phonglab
    validate area --set shape.type=sphere``).  A surface emitter's cases count only with the
    same shape (type and flags, boolean flags False when absent; ``shape`` None: the rectangle
    an area emitter loaded alone is attached to): the vertex-normal mesh finding says nothing
    of a rectangle, the sphere's nothing of a disk.  Each cause still holds only inside its own
    signature."""
    from ..emitter.setup import DEFAULT_SHAPE

    wanted = _shape_key(shape or DEFAULT_SHAPE)
    out: dict[str, tuple] = {}
    for case in catalogue(kind).cases():
        if case.plugin != plugin or case.skip:
            continue
        have = _shape_key(case.options.get("shape") or (DEFAULT_SHAPE if plugin == "area"
                                                        else None))
        if kind == "emitter" and plugin == "area" and any(
                have.get(k, False) != wanted.get(k, False) for k in {*have, *wanted}):
            continue
        for topic, causes in case.known.items():
            out[topic] = out.get(topic, ()) + tuple(c for c in causes
                                                    if c not in out.get(topic, ()))
    return out
