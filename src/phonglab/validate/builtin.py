r"""A Mitsuba built-in's documented findings follow it wherever it appears: named by its type,
as a dict, in an XML file, as a material of a scene, or as the child of a plugin that wraps it.

``known=BUILTIN`` (what ``phonglab validate`` passes unless ``--no-known``) asks
:func:`phonglab.validate.core.run` for the findings of the plugin that is loaded:

* :func:`identify`: which built-in the loaded object is and its load-time parameters (the
  kind's ``identify`` part, :mod:`phonglab.validate.bsdf.identify`: its C++ class and what
  it was loaded from), so a type name, a dict, an XML file and a scene's object carrying the
  same built-in get the same findings by the same rule (:func:`phonglab.validate.known.mark_known`:
  a lane outside every signature stays a fail; ``at=`` conditions held against its parameters,
  those the XML gives included; ``given=`` settings against what it loaded);
* :func:`mark_inherited`: a plugin whose result flows through built-in children (a Python
  wrapper, a blend, a two-sided shell; the kind's ``children`` part) is judged on its own,
  and a row that still fails is *inherited* from a child only when all three hold:

  1. every failing lane lies in the signature of a finding of that child, held at the
     child's own parameters (a parameter row ``nested.eta.value`` only against the child at
     ``nested``);
  2. the child, judged alone on the row's topic (same seed and sizes), shows it: its own row
     of that name is KNOWN by the same finding;
  3. the plugin's row is no farther from its expected value than the child's, relative to
     the expected value (|m − e| / |e|, the row's tolerance as slack): what the wrapper adds on
     top (a pdf it scales, a weight it doubles) is its own to fix.

  An inherited row reads KNOWN, its reason "inherited from the child roughconductor
  (nested): finding beckmann-pdf-normalization: ...", ``details["inherited"]`` naming the
  child, its path and the findings; a row that matched a child's signature but failed 2. or
  3. stays a fail and says why (``details["not_inherited"]``).
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from ..verdict import Row
from .known import known_entries

#: ``known`` value asking for the loaded built-in's findings and its children's (module
#: docstring).
BUILTIN = "builtin"


@dataclass(frozen=True)
class Identity:
    """A Mitsuba built-in: its plugin type and its load-time parameters."""

    type: str
    params: dict

    def numbers(self) -> dict[str, float]:
        """The numeric parameters (what a cause's ``at`` is held against)."""
        return {k: float(v) for k, v in self.params.items()
                if isinstance(v, (int, float)) and not isinstance(v, bool)}

    def to_dict(self) -> dict:
        return {"type": self.type, "params": dict(self.params)}


@dataclass
class Child:
    """A built-in BSDF a plugin holds: where, what, its findings and parameter values."""

    path: str
    plugin: Any
    identity: Identity
    known: dict
    values: dict


def identify(kind, plugin, spec=None, origin=None) -> Identity | None:
    """The built-in ``plugin`` is (the kind's ``identify`` part), None when it is none or the
    kind cannot tell."""
    part = kind.part("identify")
    found = part(plugin, spec, origin) if part is not None else None
    return Identity(*found) if found else None


def findings(kind, identity: Identity | None) -> dict:
    """topic -> the documented causes of ``identity`` (the kind's ``known_for``), {} for none."""
    known_for = kind.part("known_for")
    if identity is None or known_for is None:
        return {}
    return known_for(identity.type, identity.params) or {}


def children(kind, plugin, values: Callable) -> list[Child]:
    """The built-in children of ``plugin`` that have findings (the kind's ``children`` part)."""
    part = kind.part("children")
    out = []
    for path, obj in (part(plugin) if part is not None else []):
        ident = identify(kind, obj)
        known = findings(kind, ident)
        if known:
            out.append(Child(path, obj, ident, known, {**values(obj), **ident.numbers()}))
    return out


def deviation(row: Row) -> float | None:
    """|measured − expected| / |expected| (|measured| where expected is 0; the excess over a
    bound ``≤ b``); None when the row has no numbers to compare."""
    m, e = row.measured, row.expected
    bound = False
    if isinstance(e, str):
        found = re.search(r"[-+0-9.eE]+", e)
        bound = e.strip().startswith("≤")
        try:
            e = float(found.group()) if found else None
        except ValueError:
            e = None
    if not isinstance(m, (int, float)) or not isinstance(e, (int, float)):
        return None
    if not np.isfinite(m):
        return float("inf")
    gap = max(0.0, m - e) if bound else abs(m - e)
    return gap / abs(e) if e else gap


def _slack(row: Row) -> float:
    t, e = row.tolerance, row.expected
    if not isinstance(t, (int, float)) or not np.isfinite(t):
        return 0.0
    e = e if isinstance(e, (int, float)) else None
    return t / abs(e) if e else t


def mark_inherited(rows: list[Row], kids: list[Child], judge: Callable,
                   covered: Callable) -> list[dict]:
    """Mark the failing ``rows`` inherited from ``kids`` (module docstring), in place; one
    record per inherited row.  ``judge(child, topic)``: the child's own rows on ``topic``;
    ``covered(row, causes)``: (all lanes covered?, the causes used) as
    :func:`phonglab.validate.known.mark_known` decides it."""
    records = []
    for r in rows:
        if r.status != "fail":
            continue
        owners = [k for k in kids if r.name.startswith(k.path + ".")]
        owner = max(owners, key=lambda k: len(k.path)) if owners else None
        why_not = []
        for kid in ([owner] if owner else kids):
            name = r.name[len(kid.path) + 1:] if kid is owner else r.name
            probe = Row(r.topic, name, r.measured, r.expected, r.stderr, r.tolerance, r.status,
                        r.reason, r.details)
            probe.failing_lanes = r.failing_lanes
            causes = [k for k in known_entries(kid.known.get(r.topic))
                      if k.names(probe) and k.holds_at(kid.values)]
            ok, used = covered(probe, causes) if causes else (False, [])
            if not ok:
                continue
            keys = [k.key or k.cause[:60] for k in used]
            mine = next((c for c in judge(kid, r.topic) if c.name == name), None)
            where = f"the child {kid.identity.type} ({kid.path})"
            if mine is None or mine.status != "KNOWN" or not (
                    set(mine.details.get("known_by") or keys) & set(keys)):
                shown = "passes this row" if mine is not None and mine.status == "pass" else (
                    f"reads {mine.status} on it" if mine is not None else "has no such row")
                why_not.append({"child": kid.identity.type, "path": kid.path, "findings": keys,
                                "why": f"{where}, judged alone, {shown}"})
                continue
            d_mine, d_kid = deviation(r), deviation(mine)
            if d_mine is not None and d_kid is not None and not d_mine <= d_kid + _slack(r) + 1e-9:
                why_not.append({"child": kid.identity.type, "path": kid.path, "findings": keys,
                                "why": f"{where} alone measures {mine.measured:.4g} against "
                                       f"{mine.expected}, this plugin {r.measured:.4g} against "
                                       f"{r.expected}: farther than the child"})
                continue
            r.status = "KNOWN"
            r.reason = (f"inherited from {where}: finding {', '.join(keys)}: "
                        f"{'; '.join(k.cause for k in used)} ({r.reason})")
            r.details["inherited"] = {"child": kid.identity.type, "path": kid.path,
                                      "findings": keys, "child_measured": mine.measured}
            r.details["known_by"] = keys
            records.append({"topic": r.topic, "row": r.name, "child": kid.identity.type,
                            "path": kid.path, "findings": keys})
            break
        else:
            if why_not:
                r.details["not_inherited"] = why_not
                r.reason += ("; not inherited: " + "; ".join(w["why"] for w in why_not)
                             + ", so the failure is this plugin's own")
    return records


def scene_object(kind, path, ident: str):
    """The plugin of ``kind`` with ``id="ident"`` in the scene file ``path`` as the scene loads
    it (the variant set, the plugin files run): a :class:`~phonglab.settings.Loaded` whose
    ``origin`` names the scene and the id (its XML element gives the load-time parameters its
    findings' ``at=`` conditions hold against).  Found among those the kind's ``in_scene`` part
    lists (a scene's shapes' materials) and inside them (the kind's ``children``: a material
    nested in a two-sided shell); a missing id is a
    :class:`~phonglab.validate.inputs.ValidateError` listing the ids there are."""
    from pathlib import Path

    from ..engine.scenes import load_scene
    from ..errors import SceneError
    from ..settings import Loaded
    from .inputs import ValidateError

    try:
        scene = load_scene(path)
    except SceneError as exc:
        raise ValidateError(str(exc)) from exc
    nested = kind.part("children") or (lambda plugin: [])
    found: dict = {}
    for top in kind.part("in_scene")(scene):
        for obj in [top] + [c for _, c in nested(top)]:
            found.setdefault(obj.id(), obj)
    if ident not in found:
        named = sorted(i for i in found if i and not i.startswith("_"))
        raise ValidateError(f"{path} has no {kind.word} with id {ident!r} on its shapes; "
                            + (f"its {kind.plural} with an id: {', '.join(named)}" if named
                               else f"give a <{kind.tag}> of it an id=\"...\""))
    plugin = found[ident]
    name = (identify(kind, plugin) or Identity(type(plugin).__name__, {})).type
    return Loaded(plugin, f"{ident} ({name}) in {Path(path).name}", None,
                  origin={"file": str(path), "id": ident})
