"""The docs site (docs/, ``make docs``): every command, public module and validate topic has its
page, the reports link each row to its topic's page, and the site builds with every warning an
error (slow tier: ``sphinx-build -W``, skipped where the ``docs`` extra is not installed)."""

from __future__ import annotations

import importlib.util
import json
import subprocess
import sys
from pathlib import Path

import pytest

from phonglab.cli import SUBCOMMANDS, main
from phonglab.validate import kind, validate_phase
from phonglab.validate.registry import KINDS

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
#: The public modules the API reference documents (docs/api/<module>.md).
PUBLIC = ["phonglab.testing", "phonglab.validate", "phonglab.probe", "phonglab.dispatch",
          "phonglab.plugins.lambert", "phonglab.plugins.phong"]


@pytest.mark.parametrize("kind_", KINDS, ids=lambda k: k.name)
def test_every_topic_of_every_kind_has_its_page(kind_):
    for topic in kind_.topics:
        page = kind.topic_page(kind_.name, topic)
        assert page == f"topics/{kind_.name}/{topic}.html"
        source = DOCS / Path(page).with_suffix(".md")
        assert source.is_file(), f"{kind_.word} topic {topic!r} has no page {source}"
        text = source.read_text()
        for section in ("What it checks", "Expected value", "Tolerance",
                        "What a failing row means", "What usually causes it"):
            assert f"\n## {section}\n" in text, (source, section)
    index = (DOCS / "topics" / kind_.name / "index.md").read_text()
    assert all(f"\n{t}\n" in index for t in kind_.topics)       # its toctree lists them all


def test_every_command_and_public_module_has_its_page():
    for name in SUBCOMMANDS:
        text = (DOCS / "commands" / f"{name}.md").read_text()
        assert f":path: {name}\n" in text and ".. argparse::" in text
    for module in PUBLIC:
        assert f".. automodule:: {module}\n" in (DOCS / "api" / f"{module}.md").read_text()


def test_the_docs_url_is_the_environments_or_the_checkouts_build(monkeypatch):
    monkeypatch.setenv("PHONGLAB_DOCS_URL", "https://example.org/phonglab")
    assert kind._docs_url() == "https://example.org/phonglab/"
    monkeypatch.delenv("PHONGLAB_DOCS_URL")
    assert kind._docs_url() == (ROOT / "build" / "docs").as_uri() + "/"
    monkeypatch.setattr(kind, "DOCS_URL", "https://example.org/phonglab/")
    assert kind.topic_url("topics/bsdf/energy.html") == \
        "https://example.org/phonglab/topics/bsdf/energy.html"
    monkeypatch.setattr(kind, "DOCS_URL", None)
    assert kind.topic_url("topics/bsdf/energy.html") is None


def test_a_reports_rows_link_their_topics_page(variant_llvm_rgb, tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(kind, "DOCS_URL", "https://example.org/phonglab/")
    out_json, out_html = tmp_path / "r.json", tmp_path / "r.html"
    # a sweep (its points' reports merged from their JSON) and the HTML report
    assert main(["validate", "lambert", "--quick", "--only", "weight", "--only", "cost",
                 "--json", str(out_json), "--report", str(out_html)]) == 0
    rows = json.loads(out_json.read_text())["results"]
    assert {r["topic"] for r in rows} == {"weight", "cost"}
    assert all(r["doc"] == f"topics/bsdf/{r['topic']}.html" for r in rows)
    page = out_html.read_text()
    for topic in ("weight", "cost"):
        url = f"https://example.org/phonglab/topics/bsdf/{topic}.html"
        assert f'<a href="{url}">{topic}</a>' in page
    report = validate_phase("hg", quick=True, topics=["weight"])    # another kind, from Python
    assert report.rows and all(r.doc == "topics/phase/weight.html" for r in report.rows)
    assert all(r.to_dict()["doc"] == r.doc for r in report.rows)


@pytest.mark.slow
def test_the_site_builds_without_a_warning(tmp_path):
    missing = [m for m in ("sphinx", "myst_parser", "myst_nb", "sphinxarg", "furo")
               if importlib.util.find_spec(m) is None]
    if missing:
        pytest.skip(f"the docs extra is not installed ({', '.join(missing)} missing): "
                    f"make docs-setup, or pip install -c constraints.txt -e '.[docs]'")
    proc = subprocess.run([sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b",
                           "html", str(DOCS), str(tmp_path / "html")],
                          capture_output=True, text=True, cwd=ROOT, timeout=900)
    assert proc.returncode == 0, proc.stderr[-6000:]
    for page in ("index", "commands/validate", "api/phonglab.testing", "topics/bsdf/energy",
                 "topics/phase/chi2", "notebooks/06_plugin_authors", "conformance-phase"):
        assert (tmp_path / "html" / f"{page}.html").is_file(), page
