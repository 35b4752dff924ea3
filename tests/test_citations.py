"""Every conformance finding cites its line exactly: scripts/check_citations.py against the
headers the mitsuba wheel ships (always) and against a Mitsuba v3.9.1 source tree (when one is
at hand: $MITSUBA_SRC, a folder, or the workplace's git mirror)."""

import importlib.util
import os
import re
import sys
from dataclasses import replace
from pathlib import Path

import pytest

SCRIPT = Path(__file__).resolve().parent.parent / "scripts" / "check_citations.py"
SOURCE = re.compile(r"^(src|include|plugins)/[\w/]+\.(cpp|h|py):\d+$")


@pytest.fixture(scope="module")
def cc():
    spec = importlib.util.spec_from_file_location("check_citations", SCRIPT)
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod             # its dataclass looks its module up there
    spec.loader.exec_module(mod)
    return mod


@pytest.fixture(scope="module")
def every(cc):
    return cc.every_finding()


def source_tree(cc):
    """A v3.9.1 source tree to check the .cpp citations against, or None."""
    from phonglab.validate.conformance import MITSUBA_COMMIT

    if os.environ.get("MITSUBA_SRC"):
        return cc.DirTree(os.environ["MITSUBA_SRC"])
    if cc.MIRROR.is_dir():
        tree = cc.GitTree(cc.MIRROR, MITSUBA_COMMIT)
        if tree._git("cat-file", "-e", f"{MITSUBA_COMMIT}^{{commit}}").returncode == 0:
            return tree
    return None


def test_every_finding_has_a_line_and_an_excerpt(every):
    findings, _ = every
    assert len(findings) > 60
    # a finding another kind reuses as it is (the phase kind's sggx findings in a medium's
    # phase topic) keeps its key and its citation
    assert len({f.key for f in findings}) == len({(f.key, f.source, f.excerpt) for f in findings})
    for f in findings:
        assert SOURCE.match(f.source), f.key
        assert f.excerpt.strip() and "\n" not in f.excerpt, f.key


def test_header_citations_hold_their_excerpts(cc, every):
    headers = cc.wheel_headers()
    assert headers is not None, "the mitsuba wheel ships include/mitsuba"
    findings, issues = every
    res = cc.check(cc.HeaderTree(headers), findings, issues)
    assert res.mismatches == []
    cited = [f for f in findings if f.source.startswith("include/")]
    assert len(cited) >= 10 and res.checked >= len(cited)


def test_checker_catches_a_wrong_line_and_a_blank_one(cc, every):
    findings, _ = every
    f = next(f for f in findings if f.key == "plastic-fdr-fit-energy")     # fresnel.h:341
    wrong = replace(f, source="include/mitsuba/render/fresnel.h:340")
    blank = replace(f, cause=f.cause + " (fresnel.h:344-345)")            # 344 is blank
    res = cc.check(cc.HeaderTree(cc.wheel_headers()), [f, wrong, blank])
    assert len(res.mismatches) == 2, res.mismatches
    assert "fresnel.h:340 does not hold" in res.mismatches[0]
    assert "line 344 of include/mitsuba/render/fresnel.h is blank" in res.mismatches[1]


def test_source_citations_hold_their_excerpts(cc, every):
    tree = source_tree(cc)
    if tree is None:
        pytest.skip("no Mitsuba v3.9.1 source tree: set MITSUBA_SRC to check the .cpp citations")
    findings, issues = every
    res = cc.check(tree, findings, issues)
    assert res.mismatches == []
    assert res.skipped == [] and res.checked >= len(findings)
