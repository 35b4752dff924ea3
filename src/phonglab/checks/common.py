"""What every check shares: the row collector, the settings, the test cases and the rendering
helpers.  The rows are :class:`phonglab.verdict.Row` records (the project's one result record).

:class:`Rows` gives each statistical row its tolerance z·s once the check knows how many
statistical tests m it made: z is :func:`phonglab.stats.z_critical` (or
:func:`phonglab.stats.t_critical` for a standard error from few passes) at the Šidák level of
m tests with family-wise α = :data:`phonglab.stats.ALPHA`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from .. import stats
from ..errors import PhonglabError
from ..engine.render import RenderResult, check_spp, render_scene
from ..runtime import require_memory
from ..engine.scenes import load_scene
from ..verdict import Row

#: float32 unit roundoff 2^-24.
EPS32 = 2.0 ** -24


# --------------------------------------------------------------------------------------------
# Rows
# --------------------------------------------------------------------------------------------

class Rows:
    """Collects a check's rows (:class:`phonglab.verdict.Row`, topic = the check's name);
    statistical rows get their tolerance z·s once m is known.

    A row's ``reason`` says what is compared; ``details["source"]`` where the expectation comes
    from and ``details["relation"]`` how measured and expected are compared: ``"=="`` passes
    when |measured − expected| ≤ tolerance, ``"<="`` when measured ≤ expected + tolerance,
    ``">="`` when measured ≥ expected − tolerance.  A row given a ``known_issue`` (kept in
    ``details["known_issue"]``) that does not pass is KNOWN (a documented discrepancy outside
    phonglab, with its measured size) and does not fail the run.
    """

    def __init__(self, check: str):
        self.check = check
        self.rows: list[Row] = []
        self._stat: list[tuple[Row, int, float, float | None]] = []

    def _row(self, name, compared, measured, expected, source, stderr, tolerance, passed,
             relation, known_issue, details) -> Row:
        known = {"known_issue": known_issue} if known_issue else {}
        row = Row(self.check, name, float(measured), float(expected), float(stderr),
                  float(tolerance), _status(passed, known_issue), compared,
                  {"source": source, "relation": relation, **known, **details})
        self.rows.append(row)
        return row

    def exact(self, name, compared, measured, expected, source, tolerance, *, relation="==",
              stderr=0.0, extra_ok=True, known_issue=None, **details) -> Row:
        """A deterministic row: passes on the float budget ``tolerance`` (and ``extra_ok``)."""
        passed = bool(_compare(measured, expected, tolerance, relation) and extra_ok)
        return self._row(name, compared, measured, expected, source, stderr, tolerance, passed,
                         relation, known_issue, details)

    def stat(self, name, compared, measured, expected, source, stderr, *, tests=1,
             floor=0.0, dof=None, known_issue=None, **details) -> Row:
        """A statistical row: |measured − expected| ≤ z·stderr (+ floor, a stated float budget).

        ``tests`` counts the independent tests the row stands for (e.g. the worst of 3 channels).
        ``dof``: degrees of freedom of a standard error estimated from few independent passes
        (Student t quantile instead of the normal one); None when it pools many pixels.
        """
        row = self._row(name, compared, measured, expected, source, stderr, math.nan, False,
                        "==", known_issue, details)
        self._stat.append((row, tests, floor, dof))
        return row

    def finish(self) -> list[Row]:
        """The rows, statistical ones with their tolerance and verdict."""
        m = sum(t for _, t, _, _ in self._stat)
        if m:
            # The worst of t tests at level a' passes at level 1 − (1 − a')^t: count all of them.
            for row, _, floor, dof in self._stat:
                z = (stats.z_critical(stats.ALPHA, m) if dof is None
                     else stats.t_critical(dof, stats.ALPHA, m))
                row.tolerance = z * row.stderr + floor
                passed = bool(np.isfinite(row.measured)
                              and abs(row.measured - row.expected) <= row.tolerance)
                row.status = _status(passed, row.details.get("known_issue"))
                row.details.setdefault("z", round(z, 3))
                if row.stderr > 0:
                    row.details.setdefault("z_score", (row.measured - row.expected) / row.stderr)
        return self.rows


def _status(passed: bool, known_issue: str | None = None) -> str:
    """A check row's status: pass, else KNOWN with a documented cause, else fail."""
    if passed:
        return "pass"
    return "KNOWN" if known_issue else "fail"


def _compare(measured, expected, tol, relation) -> bool:
    measured, expected, tol = float(measured), float(expected), float(tol)
    if not (math.isfinite(measured) and math.isfinite(expected)):
        return False
    if relation == "==":
        return abs(measured - expected) <= tol
    if relation == "<=":
        return measured <= expected + tol
    if relation == ">=":
        return measured >= expected - tol
    raise ValueError(f"unknown relation {relation!r}")


# --------------------------------------------------------------------------------------------
# Configuration
# --------------------------------------------------------------------------------------------

#: Memory of a ``phonglab check`` run: measured peak RSS 273 MB at --spp 256 and 433 MB at
#: 1024 (llvm_ad_rgb), i.e. ~210 KB per spp over a ~220 MB base, rounded up.
CHECK_BASE_BYTES = 256 << 20
CHECK_BYTES_PER_SPP = 256 << 10


@dataclass
class Config:
    """How hard the checks work.

    ``spp`` is the samples per pixel of every statistical render; BSDF-level Monte Carlo
    estimates use ``samples`` directions per case (default 1024·spp) and the χ² tests
    ``chi2_samples`` (default 4096·spp).  ``lambert``/``phong`` name the plugins under test
    (the tests register deliberately broken variants under other names).
    """

    spp: int = 256
    seed: int = 0
    samples: int | None = None
    chi2_samples: int | None = None
    passes: int = 8
    out_dir: Path = Path("out/checks")
    lambert: str = "lambert"
    phong: str = "phong"
    progress: Callable[[str], None] | None = None

    def __post_init__(self):
        if int(self.spp) < 8:
            raise PhonglabError(f"--spp must be at least 8 (the renders are split into passes "
                                f"for their standard errors), got {self.spp}.")
        self.spp = int(self.spp)
        check_spp(self.spp)
        require_memory(CHECK_BASE_BYTES + CHECK_BYTES_PER_SPP * self.spp, f"--spp {self.spp}",
                       "lower --spp", why=" (the BSDF checks draw 1024 directions and 4096 χ² "
                       "samples per spp)")
        if self.samples is None:
            self.samples = 1024 * self.spp
        if self.chi2_samples is None:
            self.chi2_samples = 4096 * self.spp
        self.out_dir = Path(self.out_dir)

    @classmethod
    def small(cls, **kw) -> "Config":
        """The test suite's settings: same checks, fewer samples."""
        kw.setdefault("spp", 16)
        return cls(**kw)

    def note(self, msg: str) -> None:
        if self.progress is not None:
            self.progress(msg)

    def rng(self, stream: int) -> np.random.Generator:
        """The random generator of one numbered stream of this run's seed."""
        return np.random.default_rng([self.seed, stream])


# --------------------------------------------------------------------------------------------
# Test cases
# --------------------------------------------------------------------------------------------

def gray(name: str, **params) -> dict:
    """A ``mi.load_dict`` spec of plugin ``name``; ``*reflectance`` params become gray RGB."""
    d = {"type": name}
    for k, v in params.items():
        d[k] = {"type": "rgb", "value": float(v)} if k.endswith("reflectance") else v
    return d


def phong_dict(name, kd, ks, p) -> dict:
    """A ``mi.load_dict`` spec of a modified-Phong plugin with gray k_d, k_s and exponent p."""
    return {"type": name, "diffuse_reflectance": {"type": "rgb", "value": float(kd)},
            "specular_reflectance": {"type": "rgb", "value": float(ks)}, "exponent": float(p)}


# --------------------------------------------------------------------------------------------
# Rendering and reducing
# --------------------------------------------------------------------------------------------

def render(cfg: Config, scene_name: str, stream: int, integrator=None, spp=None, passes=None,
           **params) -> RenderResult:
    """Load a shipped scene with ``params`` and render it in passes (seed from ``stream``)."""
    scene = load_scene(scene_name, **{k: str(v) for k, v in params.items()})
    spp = int(spp or cfg.spp)
    return render_scene(scene, spp, seed=cfg.seed * 1000 + stream, passes=passes or cfg.passes,
                        integrator=integrator)


def image_mean(res: RenderResult, channel: int | None = 0) -> tuple[float, float, float]:
    """Mean over pixels of one channel, its standard error (pixels are independent with a box
    filter: SE = √(Σ se²)/N), and the mean per-pixel standard deviation of one sample."""
    img = res.image[..., channel].astype(np.float64)
    se = res.stderr[..., channel].astype(np.float64)
    n = img.size
    return float(img.mean()), float(math.sqrt(np.sum(se * se)) / n), float(np.mean(se))


def worst(values, target: float) -> float:
    """The entry of ``values`` (as float64) farthest from ``target`` (the first one on ties)."""
    a = np.asarray(values, dtype=np.float64)
    return float(a.flat[np.argmax(np.abs(a - target))])
