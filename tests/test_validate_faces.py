"""Every face of the validator judges a plugin alike: the command line, the package face
(:func:`phonglab.validate.validate`), the pytest helper (:func:`phonglab.testing.assert_bsdf_valid`)
and the sweep's points run by the automatic runner on 2 worker processes (a Dask
LocalCluster) give the same rows, row
for row -- topic, name, parameter point, status and the numbers -- for one plugin at one seed.
They share one pipeline (:mod:`phonglab.validate.pipeline`); this is its proof from outside.
A quick, fast case: Mitsuba's ``diffuse`` through its sweep (reflectance at its ends), the
``finite`` topic and two whose numbers move with the seed (``energy``'s albedo estimate,
``chi2``'s p-value), so that a face drawing other samples would not agree.
"""

from __future__ import annotations

import json

from phonglab import parallel
from phonglab.cli import main
from phonglab.testing import assert_bsdf_valid
from phonglab.validate import sweep, validate

PLUGIN, SEED, TOPICS = "diffuse", 7, ("finite", "energy", "chi2")


def _rows(rows) -> list[tuple]:
    """The rows as their verdicts: what each judged and what it found (no timings)."""
    return [(r["topic"], r["name"], json.dumps(r.get("point"), sort_keys=True), r["status"],
             r["measured"], r["expected"], r["tolerance"]) for r in rows]


def _cli(tmp_path, *extra) -> list[tuple]:
    out = tmp_path / f"report{len(extra)}.json"
    argv = ["validate", PLUGIN, "--quick", "--seed", str(SEED), "--json", str(out), *extra]
    for t in TOPICS:
        argv += ["--only", t]
    assert main(argv) == 0
    return _rows(json.loads(out.read_text())["results"])


class _TwoFree(parallel.CoreMeter):
    """A meter that finds two cores free and one used, whatever else runs (a test runner's
    workers)."""

    def __exit__(self, *exc):
        super().__exit__(*exc)
        self.free, self.used = 2, 1.0


def test_cli_face_helper_and_workers_agree(variant_llvm_rgb, tmp_path, monkeypatch):
    options = dict(quick=True, seed=SEED, topics=list(TOPICS))
    face = validate(PLUGIN, **options).to_dict()["results"]
    helper = assert_bsdf_valid(PLUGIN, **options).to_dict()["results"]
    cli = _cli(tmp_path, "--workers", "1")
    # the default, automatic runner, told that the points would take long and cores are free:
    # the given point here, the others on 2 worker processes
    monkeypatch.setattr(parallel, "AUTO_MIN_SECONDS", 0.0)
    monkeypatch.setattr(sweep, "CoreMeter", _TwoFree)
    auto = _cli(tmp_path)
    assert json.loads((tmp_path / "report0.json").read_text())["meta"]["sweep"]["where"][
        "workers"] == 2
    assert len({r[2] for r in cli}) > 1, "no sweep: the workers would have nothing to spread"
    assert _rows(face) == cli == _rows(helper) == auto
