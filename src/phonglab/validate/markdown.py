r"""docs/conformance.md from the JSON of ``phonglab validate --all-builtins --json``, and that
JSON as committed (docs/conformance.json, :func:`without_plot_data`).

:func:`render_markdown` turns the document of :func:`phonglab.validate.batch.run_all` (one
report per case of a kind's table, :func:`phonglab.validate.registry.catalogue`) into the conformance table, each
case's rows that do not pass, the Mitsuba findings and the validator's own issues
(:mod:`.conformance`), and the plugins left out; the numbers in ``docs/conformance.md`` come from
that JSON only.
"""

from __future__ import annotations

from ..verdict import point_label
from . import registry
from .conformance import COMMAND, MITSUBA_COMMIT, MITSUBA_VERSION, SOURCE_URL, Catalogue
from .known import at_text

#: Row details that only feed the HTML report's plots (lobe slices, chi2 histograms).
PLOT_ONLY = ("lobes", "histogram", "pdf", "expected")


def without_plot_data(data: dict) -> dict:
    """A copy of a ``--all-builtins`` JSON document without :data:`PLOT_ONLY` arrays, and
    without mi.chi2's log text of ACCEPTED cells (their p-value and sums stay).

    docs/conformance.json keeps every number the table and the sections quote; the plot
    arrays (megabytes) are what ``phonglab validate BSDF --report`` draws.
    """
    def drop(k, v, x) -> bool:
        if k in PLOT_ONLY and isinstance(v, (list, dict)):
            return True
        return k == "messages" and x.get("status") == "pass" and "p_value" in x

    def strip(x):
        if isinstance(x, dict):
            return {k: strip(v) for k, v in x.items() if not drop(k, v, x)}
        if isinstance(x, list):
            return [strip(v) for v in x]
        return x
    return strip(data)


def cell_status(rows: list[dict]) -> str:
    """One table cell for a topic's rows: fail > KNOWN > pass > skipped ('' when no row)."""
    statuses = {r["status"] for r in rows}
    for s in ("fail", "KNOWN", "pass", "skipped"):
        if s in statuses:
            return s
    return ""


def _num(x) -> str:
    if x is None:
        return "-"
    if isinstance(x, float):
        return f"{x:.4g}"
    return str(x)


def _md(text) -> str:
    """Text safe inside a markdown table cell."""
    return str(text).replace("|", "\\|").replace("\n", " ")


def _source_link(source: str) -> str:
    """A link to Mitsuba 3.9.1's source line, or to phonglab's own file (``plugins/...``,
    relative to docs/)."""
    path, _, line = source.partition(":")
    if path.startswith(("plugins/", "src/phonglab/")):
        return f"[`{source}`](../{path}#L{line})"
    return f"[`{source}`]({SOURCE_URL}{path}#L{line})"


def _label(report: dict) -> str:
    return report["meta"]["case"]


def _table(data: dict, cat: Catalogue) -> list[str]:
    """One line per case: the worst status of each topic over the case's sweep points."""
    TOPICS = cat.kind.topics
    head = "| case | variant | points | " + " | ".join(TOPICS) + " |"
    lines = [head, "|" + "---|" * (len(TOPICS) + 3)]
    for report in data["reports"]:
        by_topic = {t: [r for r in report["results"] if r["topic"] == t] for t in TOPICS}
        cells = [cell_status(by_topic[t]) or " " for t in TOPICS]
        cells = [f"**{c}**" if c == "fail" else c for c in cells]
        variant = str(report["meta"].get("variant", "")).replace("llvm_ad_", "")
        points = (report["meta"].get("sweep") or {}).get("points", 1)
        lines.append(f"| `{_label(report)}` | {variant} | {points} | " + " | ".join(cells)
                     + " |")
    return lines


def _case_section(report: dict, cat: Catalogue) -> list[str]:
    """The fail and KNOWN rows of one case, with their documented causes."""
    bad = [r for r in report["results"] if r["status"] in ("fail", "KNOWN")]
    if not bad:
        return []
    label = _label(report)
    out = [f"### `{label}`", ""]
    spec = report["meta"].get("spec")
    if spec:
        out += [f"Spec: `{_md(spec)}`; {report['meta'].get('note', '')}.", ""]
    swept = any("point" in r for r in bad)
    out += [("| point " if swept else "") + "| status | topic | check | measured | expected "
            "| tolerance | reason |", "|---" * (8 if swept else 7) + "|"]
    for r in bad:
        where = f"| {_md(point_label(r['point']))} " if swept else ""
        out.append(f"{where}| {r['status']} | {r['topic']} | {_md(r['name'])} "
                   f"| {_num(r['measured'])} | {_num(r['expected'])} | {_num(r['tolerance'])} "
                   f"| {_md(r['reason'])} |")
    explaining = _explaining(report)
    causes = [f for f in cat.findings if f.key in explaining]
    for f in causes:
        out.append("")
        out.append(f"* {f.topic}: [{f.key}](#{f.key}) -- {_source_link(f.source)}, reproducer "
                   f"`{f.reproducer}`")
    issues = cat.open_issues()
    by_validator = {issues[(label, r["topic"])].key: issues[(label, r["topic"])]
                    for r in bad if r["status"] == "fail" and (label, r["topic"]) in issues}
    for v in by_validator.values():
        out += ["", f"* {v.topic}: **validator**, [{v.key}](#{v.key}) -- not a Mitsuba finding"]
    explained = {v.topic for v in by_validator.values()} | {f.topic for f in causes}
    unexplained = sorted({r["topic"] for r in bad if r["status"] == "fail"} - explained)
    if unexplained:
        out += ["", f"* **Unexplained fail** ({', '.join(unexplained)}): no documented cause "
                f"in `{cat.findings_name}` yet."]
    return out + [""]


def _explaining(report: dict) -> set[str]:
    """The findings that explain rows of one report: those its KNOWN rows name
    (``details.known_by``) and those whose signature a failing row was held against
    (``details.outside_signature.findings``).  A finding that names the case but whose
    signature or parameter values keep it off every row is not one of them."""
    out = set()
    for r in report["results"]:
        details = r.get("details") or {}
        if r["status"] == "KNOWN":
            out.update(details.get("known_by") or ())
        elif r["status"] == "fail":
            out.update((details.get("outside_signature") or {}).get("findings") or ())
    return out


def _findings_section(data: dict, cat: Catalogue) -> list[str]:
    seen = {_label(r) for r in data["reports"]}
    tests = cat.tests
    own = ("" if not any(f.source.startswith("plugins/") for f in cat.findings)
           else " (a `plugins/...` source is phonglab's own plugin: a *by design* entry "
           "documents the scope of its model)")
    out = ["## Findings", "",
           "Each is pinned to the line of Mitsuba 3.9.1's source (tag v3.9.1, commit "
           f"`{MITSUBA_COMMIT[:12]}`){own} and has a minimal reproducer in `tests/repro/` that "
           f"exits 1 while the behaviour is present (`pytest -m slow {tests}` runs "
           "them all).  A finding explains a *signature*: the rows it names and the region of "
           "inputs it says fails.  A failing row is KNOWN only when every one of its failing "
           "lanes (or χ² cells) lies in the signature of a finding; a lane outside keeps it a "
           "fail.  The *measured* lines are what the reproducer (or the named mi.chi2 run) "
           "prints; the rows above are the JSON's.", ""]
    explained = {}
    for rep in data["reports"]:
        for key in _explaining(rep):
            explained.setdefault(key, set()).add(_label(rep))
    idle = []
    for f in cat.findings:
        labels = [label for label in f.labels if label in explained.get(f.key, ())]
        if not labels:
            if any(label in seen for label in f.labels):
                idle.append(f)
            continue
        out += _finding(f, f"* cases: {', '.join(f'`{x}`' for x in labels)}")
    if idle:
        out += ["## Findings that explain no row of this run", "",
                "Each names cases of this table, but no row above is theirs: they hold at "
                "other parameter values than the points run here (their `at`; the sweep of "
                "docs/validate.md finds them) or describe what no row here counts.  They are "
                "listed for the cases' users, not as causes of the rows above.", ""]
        for f in idle:
            labels = [label for label in f.labels if label in seen]
            out += _finding(f, f"* cases it names: {', '.join(f'`{x}`' for x in labels)}")
    return out


def _finding(f, cases: str) -> list[str]:
    kind = "bug" if f.bug else "by design"
    return [f"### {f.key}", "",
            f"*{f.topic}, {kind}* -- {_source_link(f.source)}: {f.cause}.", "",
            f"* measured: {f.measured}", f"* expected: {f.expected}",
            f"* reproducer: `{f.reproducer}`",
            f"* signature: {_signature(f)}", cases, ""]


def _signature(f) -> str:
    rows = ", ".join(f"`{r}`" for r in f.rows)
    at = ("; at " + at_text(f.at)) if f.at else ""
    given = "".join(f"; only with {name} = {value}" for name, value in f.given)
    return f"{f.topic} rows {rows}; " + (f.region.text if f.region is not None
                                         else "every failing lane of those rows") + at + given


def _validator_section(data: dict, cat: Catalogue) -> list[str]:
    """Open validator issues whose rows show in this run (docs/validator-fixes.md tells the
    fixed ones)."""
    shown = {(_label(rep), r["topic"], r["status"]) for rep in data["reports"]
             for r in rep["results"]}
    issues = [(v, [label for label in v.labels
                   if any((label, v.topic, st) in shown for st in v.statuses)])
              for v in cat.validator_issues]
    issues = [(v, labels) for v, labels in issues if labels]
    out = []
    if issues:
        out = ["## Rows that fail (or are skipped) because of the validator", "",
               "These rows keep their status in the JSON (a tolerance is never widened to hide "
               "them); the fix belongs in `phonglab.validate` / `phonglab.probe`.", ""]
        for v, labels in issues:
            out += [f"### {v.key}", "", f"*{v.topic}* -- {v.explanation}.", "",
                    f"* cases: {', '.join(f'`{x}`' for x in labels)}", ""]
    return out


def render_markdown(data: dict, cat: Catalogue | None = None) -> str:
    """docs/conformance.md from the JSON of ``phonglab validate --all-builtins --json``
    (:func:`phonglab.validate.batch.run_all`: ``{"meta": {...}, "reports": [...]}``);
    ``cat``: the kind's :class:`~.conformance.Catalogue` (default: that of the JSON's
    ``options["kind"]``, else of :data:`~.registry.DEFAULT`)."""
    meta = data.get("meta", {})
    options = meta.get("options") or {}
    counts: dict[str, int] = {}
    for report in data["reports"]:
        for r in report["results"]:
            counts[r["status"]] = counts.get(r["status"], 0) + 1
    if "seconds" in meta:
        took = f"{_num(float(meta['seconds']))} s wall time"
    else:
        took = (f"{_num(float(sum(r['meta'].get('wall_seconds', 0) for r in data['reports'])))}"
                " s (sum of the cases' wall times)")
    mode = "--quick" if options.get("quick") else "default settings"
    cat = cat or registry.catalogue(options.get("kind") or registry.DEFAULT.name)
    swept = bool(options.get("sweep"))
    script = f"`scripts/conformance.py --kind {cat.kind.name}" + (" --sweep`" if swept else "`")
    lines = [
        f"# Conformance of Mitsuba {MITSUBA_VERSION}'s built-in {cat.kind.plural}", "",
        f"Generated by `{COMMAND}` ({script}) from `{cat.json}`;"
        f" do not edit by hand.  Each case is {cat.case_text} "
        f"(`{cat.cases_name}`), validated by `phonglab.validate.{cat.kind.function}` "
        f"with {mode}, seed {options.get('seed', 0)}: {len(data['reports'])} cases, "
        + ", ".join(f"{counts.get(s, 0)} {s}" for s in ("pass", "fail", "KNOWN", "skipped"))
        + f" rows, {took}.", "",
        "A cell is the worst status of the topic's rows (fail > KNOWN > pass > skipped; empty: no "
        "row).  KNOWN means the row fails for a documented cause in Mitsuba (see Findings); "
        "it is still reported, never hidden by a wider tolerance.", "",
    ]
    if swept:
        lines += [
            "Each case runs through its parameter sweep (docs/validate.md, \"The parameter "
            "sweep\"): the given point, each swept parameter alone at its range's values, and "
            "the two corners; `points` counts the points run, a cell is the worst over them, "
            "and each row below names its point.", ""]
    else:
        lines += [
            "Each case is run at its given point only (not through the parameter sweep).", ""]
    lines += _table(data, cat) + ["", "## Rows that do not pass", ""]
    for report in data["reports"]:
        lines += _case_section(report, cat)
    lines += _findings_section(data, cat)
    lines += _validator_section(data, cat)
    lines += ["## Plugins left out", ""]
    for name, why in cat.left_out.items():
        lines.append(f"* `{name}`: {why}")
    return "\n".join(lines) + "\n"
