"""Plugins written the way authors write them (tests/corpus/: Mitsuba's tutorial style,
``active`` without a default, float and tuple returns, ``mi.Vector3f`` radiance, AOVs,
``props.get_texture`` textures, ``dr.while_loop`` integrators, no ``to_string``/``traverse``),
each validated by the command an author runs (``phonglab validate NAME --plugin FILE --quick
--json``): a control passes with its physics topics judged; a plugin with one bug fails on
the topic of that bug with a measured row (not a crash of the check); a plugin's own error is
its message and file:line.  tests/corpus/README.md holds what each plugin is and what it
renders in Mitsuba; catalog.json the style, bug and topic of each.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from helpers import run_cli

HERE = Path(__file__).parent
CORPUS = HERE / "corpus"
CATALOG = {c["name"]: c for c in json.loads((CORPUS / "catalog.json").read_text())}

#: The topics whose rows must be judged (pass) for a control of each kind.
PHYSICS = {"bsdf": {"weight", "chi2", "energy", "reciprocity", "component"},
           "phase": {"weight", "chi2", "normalization"},
           "emitter": {"weight"},
           "integrator": {"bias", "agreement"}}


#: (name, extra arguments, report) -> (exit code, JSON report or None, stderr, HTML report or
#: None): one run of a command per test process, shared by the tests that read it.
_RUNS: dict = {}


@pytest.fixture
def validate(capfd, tmp_path_factory, monkeypatch):
    """validate(name, *extra, report=False): (exit code, JSON report or None, stderr) of the
    author's command on a corpus plugin, run in this process, in a folder of its own; stderr
    holds what Python and the libraries below it (Dr.Jit, Mitsuba) wrote.  With ``report``
    the command also writes its HTML report (``--report``: :func:`html_of` gives it), which
    only the tests that read it ask for (its figures cost more than most runs)."""
    def run(name: str, *extra, report: bool = False):
        key = (name, extra, report)
        if key not in _RUNS:
            where = tmp_path_factory.mktemp(name)
            out, html = where / f"{name}.json", where / f"{name}.html"
            monkeypatch.chdir(where)
            capfd.readouterr()
            rc, _, err = run_cli(["validate", name, "--plugin", CORPUS / CATALOG[name]["file"],
                                  "--variant", "llvm_ad_rgb", "--quick", "--json", out,
                                  *(["--report", html] if report else []), *extra],
                                 seconds=600)
            _RUNS[key] = (rc, json.loads(out.read_text()) if out.exists() else None,
                          err + capfd.readouterr().err,
                          html.read_text() if html.exists() else None)
        return _RUNS[key][:3]
    return run


def html_of(name: str, *extra) -> str | None:
    return _RUNS[(name, extra, True)][3]


def test_the_catalog_lists_every_corpus_file_and_at_least_15():
    files = {p.name for p in CORPUS.glob("*.py")}
    assert files == {c["file"] for c in CATALOG.values()}
    assert len(CATALOG) >= 15
    assert {c["kind"] for c in CATALOG.values()} == {"bsdf", "phase", "emitter", "integrator"}


CONTROLS = [n for n, c in CATALOG.items() if c["bug"] is None]


@pytest.mark.parametrize("name", [pytest.param(n, marks=pytest.mark.slow) if n == "aov_depth"
                                  else n for n in CONTROLS])
def test_a_control_passes_with_its_physics_judged(validate, name):
    """The tutorial-style BSDFs and phase function (``active`` positional without a default)
    are called as Mitsuba calls them; the Python environment light's power is judged; the AOV
    integrator is judged on more than ``finite``."""
    rc, report, err = validate(name)
    assert rc == 0, err[-2000:]
    assert report["meta"]["not_covered"] == []
    rows = report["results"]
    judged = {r["topic"] for r in rows if r["status"] == "pass"}
    # a topic that cannot apply to what the plugin is (weight and chi2 of a delta-only BSDF)
    inapplicable = {t for t in PHYSICS[CATALOG[name]["kind"]]
                    if all(r["details"].get("not_applicable") for r in rows if r["topic"] == t)}
    missing = PHYSICS[CATALOG[name]["kind"]] - judged - inapplicable
    assert not missing, f"{name}: nothing judged on {missing}"
    assert judged & PHYSICS[CATALOG[name]["kind"]]


#: name -> (topic, a word of the failing row's name, extra arguments): each runs the topic its
#: test reads alone (``--only``)
DEFECTS = {
    "tut_delta_importance": ("reciprocity", "Importance mode", ("--only", "reciprocity")),
    "textured_plastic_gain": ("energy", "albedo", ("--only", "energy")),
    "two_lobe_ignores_component": ("component", "restricted context",
                                   ("--no-sweep", "--only", "component")),
    "two_lobe_ignores_type_mask": ("component", "type_mask",
                                   ("--no-sweep", "--only", "component")),
    "cosine_ratio_nonreciprocal": ("reciprocity", "reflection",
                                   ("--no-sweep", "--only", "reciprocity")),
    "hg_sign_flip": ("chi2", "sampling", ("--no-sweep", "--only", "chi2")),
    "while_loop_sampler_missing": ("bias", "enclosure", ("--only", "bias")),
    "env_light_never_added": ("bias", "glass sphere furnace", ("--only", "bias")),
}


def test_every_defect_of_the_catalog_has_a_test():
    bugs = {n for n, c in CATALOG.items() if c["bug"] is not None}
    assert bugs == set(DEFECTS) | {"traverse_renamed_api", "unimplemented_pdf",
                                   "sample_name_error"}


@pytest.mark.parametrize("name", sorted(DEFECTS))
def test_a_defect_fails_on_its_topic_with_a_measured_row(validate, name):
    topic, word, extra = DEFECTS[name]
    rc, report, err = validate(name, *extra)
    assert rc == 1, err[-2000:]
    failing = [r for r in report["results"] if r["status"] == "fail"]
    mine = [r for r in failing if r["topic"] == topic and word in r["name"]]
    assert mine, [(r["topic"], r["name"]) for r in failing]
    assert all(r["measured"] is not None for r in mine)      # a finding, not a crash


def test_a_textured_parameter_is_swept_over_the_domain_of_its_name(validate):
    """A BSDF whose parameters are mi.Textures is swept (not "no parameter swept"), so its
    energy gain at small roughness (albedo 1.2 at 0.1) fails."""
    rc, report, _ = validate("textured_plastic_gain",
                             *DEFECTS["textured_plastic_gain"][2])
    assert rc == 1
    swept = {p["name"]: p for p in report["meta"]["sweep"]["parameters"]}
    assert swept["roughness"]["source"] == "named" and swept["roughness"]["hi"] == 1.0
    gains = [r for r in report["results"] if r["status"] == "fail" and r["topic"] == "energy"
             and "roughness" in (r.get("point") or {})]
    assert gains and all(r["measured"] > 1 for r in gains)


def test_a_traverse_that_raises_is_one_sentence_with_the_plugins_file_and_line(validate):
    """Not a raw traceback: one sentence, exit 2."""
    rc, report, err = validate("traverse_renamed_api")
    assert rc == 2 and report is None
    assert "traverse() of the BSDF 'traverse_renamed_api' raised AttributeError" in err
    assert "put_parameter" in err and "traverse_renamed_api.py:" in err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1


def test_an_unimplemented_method_is_not_implemented_not_a_physics_failure(validate):
    rc, report, _ = validate("unimplemented_pdf", "--no-sweep")
    assert rc == 1
    failing = [r for r in report["results"] if r["status"] == "fail"]
    assert failing and all(r["reason"].startswith("not implemented: pdf") for r in failing)
    assert all(r["details"]["not_implemented"] == "pdf" for r in failing)


def test_an_integrators_own_error_is_its_message_and_line_not_see_above(validate):
    """Each row gives the plugin's message and line, not Dr.Jit's "error while performing a
    custom differentiable operation. (see above)"."""
    rc, report, _ = validate("sample_name_error", "--no-sweep", report=True)
    assert rc == 1
    for r in report["results"]:
        assert "see above" not in r["reason"]
        assert "NameError" in r["reason"] and "sample_name_error.py:" in r["reason"]
        where = r["details"]["plugin_error"]
        assert where["file"].endswith("sample_name_error.py") and where["function"] == "sample"


def test_the_html_report_is_titled_by_kind_and_shows_the_plugins_error(validate):
    """An integrator's report is titled by its kind and name (not "phonglab validate: ?")."""
    rc, _, _ = validate("sample_name_error", "--no-sweep", report=True)
    text = html_of("sample_name_error", "--no-sweep")
    assert rc == 1
    assert "<title>phonglab validate: integrator sample_name_error (llvm_ad_rgb)" in text
    source = (CORPUS / "sample_name_error.py").read_text().splitlines()
    line = next(k for k, t in enumerate(source, 1) if "bsdf_ctx," in t)
    assert f"sample_name_error.py:{line}, in sample" in text
