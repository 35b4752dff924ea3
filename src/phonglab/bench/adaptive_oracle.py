r"""The bench's adaptive-sampling oracle rows at three image sizes, and where the time goes.

At the bench's size (128², :attr:`Config.adaptive_oracle_scenes`) an adaptive render lasts
0.1–2.6 s, and the medians of its oracle rows (:func:`phonglab.bench.adaptive_sweeps.oracle_row`)
moved by up to 0.23 of the time oracle between two runs of unchanged code: start-up noise
decides them.  Here the same rows run at the bench's size scaled by 1, 2 and 4 in each
direction (:data:`SCALES`: 128², 256², 512²; nb_sphere_row keeps its 4:1 aspect, 512×128 to
2048×512; the furnace, 32² in the bench, goes 32², 64², 128²), so the fixed costs of a
render (launches, the host's work per pass) weigh less and the rows show what is left.

**Per row** (scene, size, its planner-bench target E, full depth, against a full-depth
reference whose own noise the errors have removed):

* the sample oracle mean(u)/mean(√u)² and the time oracle mean(u)·mean(c)/mean(√(u c))²
  (:func:`phonglab.bench.adaptive_sweeps.oracle_limits`: 256-spp map of u, cost map);
* per seed (:func:`phonglab.bench.adaptive_sweeps.oracle_seed`), the adaptive render, then
  right after it ``mi.render`` at its mean spp (the pair: the ratio of the two is robust to
  drift of the machine's speed slower than a pair), then the two single-pass wavefront
  traces of the decomposition.  One warm-up seed first, dropped (kernels compiled, memory
  touched), then ``seeds`` seeds;
* achieved = median over seeds of t_u (e_u/e)²/t (the speed-up at equal error, i.e. at equal
  time: noise ∝ 1/√time), its min and max; the share achieved / time oracle; the target
  (:func:`phonglab.bench.adaptive_sweeps.oracle_summary`): ≥ 0.8 of the time oracle where it
  is ≥ 1.3, adaptive's cost ≤ 1.05x uniform's where it is about 1 (the furnace);
* the decomposition of adaptive's time over ``mi.render``'s at the same samples
  (:func:`phonglab.bench.adaptive_sweeps.cost_factors`): wavefront × placement × passes ×
  host, of the medians over seeds.

**What holds a missed row back** (:func:`account`).  With G the speed-up at equal samples,
O_s and O_t the sample and time oracles and P the measured placement factor, the share is,
up to the spread of the seeds (a median of ratios against a product of medians),

    achieved / O_t = (G / O_s) · (O_s / (O_t · P)) · 1/wavefront · 1/passes · 1/host,

since achieved ≈ G / (cost of one of adaptive's samples over one of uniform's) and that cost
is wavefront · P · passes · host.  The first term, **allocation**, is how well the samples
were placed against the best placement (the guards, the estimates' noise); the second,
**path cost**, what their paths cost against what the time oracle trades for (> 1 where
adaptive's samples sit in pixels cheaper than the oracle allows for; below 1 where the cost
map underprices them); the last three are the pass structure's overheads, which the oracle
does not have.  Where passes < 1 (one pass of the final counts ran slower than the passes
that traced the same samples) the one-pass trace is no floor, the split between placement
and passes is not resolved, and path cost and passes are one term.  The account
(:func:`share_terms`) names the fewest terms below 1, smallest first, whose removal lifts
the measured share to 0.8.  For the furnace (O_t ≈ 1) the cost is 1/achieved, and the
account names the fewest factors above 1 whose removal brings it to 1.05.

**References** (:func:`reference_spp`).  At the bench's size a row uses the bench's own
reference (:data:`phonglab.bench.adaptive_sweeps.ORACLE_REFERENCE_SPP` = 4096 spp, the same
cache entry).  At 4096 spp the eight references of a size take ~2.5 min on 2 quiet cores at
the bench's size, so ×4 and ×16 that at 256² and 512² (~53 min in all).  A larger size's
reference therefore has the fewest spp, in steps of :data:`REFERENCE_STEP`, whose relative
noise (:func:`phonglab.engine.metrics.relative_noise` of its image and stderr image),
predicted from the next smaller size's reference as ∝ 1/√spp (the noise one sample adds to a
pixel hardly changes with the pixel's size), is at most E/4 (:data:`REFERENCE_NOISE_SHARE`),
and at most 4096.  The errors subtract the reference's noise
(:func:`phonglab.engine.metrics.relative_rmse` with its stderr: e² − mean(s_r²/(r² + ε))),
so the reference's noise does not bias them, and the rule keeps what is subtracted small
beside what is measured.  Where 4096 spp does not reach E/4 (scenes whose uniform renders
need thousands of spp for E, as in the bench's own references) the cap holds; every
reference's measured noise / E is recorded and shown.

Results: ``scripts/adaptive_oracle.py`` (``make adaptive-oracle``) writes
``docs/bench/adaptive_oracle.json``; :func:`report_section` renders it into BENCHMARKS.md.
"""

from __future__ import annotations

import math
import os
import statistics
import time
from typing import Any, Callable

from ..engine import metrics, references, scenes
from ..runtime import quiet_mitsuba
from .adaptive_sweeps import (COST_FACTORS, ORACLE_MATTERS, ORACLE_REFERENCE_SPP, ORACLE_SHARE,
                              OVERHEAD_TARGET, UNIFORM_SCENE, cost_factors, oracle_limits,
                              oracle_seed, oracle_summary)
from .config import VARIANT
from .report_data import RunData, fmt_met, part_record

#: Image sizes as scales of the bench's (each direction): 128², 256², 512².
SCALES = (1, 2, 4)
#: A larger size's reference noise is at most this share of E (module docstring).
REFERENCE_NOISE_SHARE = 0.25
#: Reference spp are multiples of this (16 passes of 16).
REFERENCE_STEP = 256
#: The JSON file :func:`report_section` reads from the bench folder.
JSON_NAME = "adaptive_oracle.json"
#: Quiet enough: the 1-minute load average a timed run waits to fall below (2 cores).
QUIET_LOAD = 1.5


def scaled_params(params: dict[str, Any], scale: int) -> dict[str, Any]:
    """The scene parameters at ``scale`` times the bench's size in each direction."""
    return {k: v * scale if k in ("res", "width", "height") else v for k, v in params.items()}


def size_label(params: dict[str, Any]) -> str:
    """'128²' or '512×128'."""
    if "width" in params:
        return f"{params['width']}×{params['height']}"
    return f"{params['res']}²"


def reference_spp(smaller_noise: float, smaller_spp: int, target: float,
                  share: float = REFERENCE_NOISE_SHARE, step: int = REFERENCE_STEP,
                  cap: int = ORACLE_REFERENCE_SPP) -> int:
    """The fewest spp, a multiple of ``step`` and at most ``cap``, at which a reference whose
    relative noise was ``smaller_noise`` at ``smaller_spp`` (the next smaller size's) is
    predicted (noise ∝ 1/√spp) to have relative noise ≤ ``share`` · ``target``."""
    need = smaller_spp * (smaller_noise / (share * target)) ** 2
    return int(min(cap, max(step, step * math.ceil(need / step))))


def wait_for_quiet(limit: float = QUIET_LOAD, step: float = 60.0, most: float = 1200.0,
                   log: Callable[[str], None] = print,
                   load: Callable[[], tuple] = os.getloadavg,
                   sleep: Callable[[float], None] = time.sleep) -> dict[str, Any]:
    """Wait (``step`` s at a time, at most ``most`` s) until the 1-minute load average is
    below ``limit``; what was seen: the load averages at the end and the seconds waited."""
    waited = 0.0
    while True:
        now = load()
        if now[0] <= limit or waited >= most:
            return {"load": [round(x, 2) for x in now], "waited_s": waited,
                    "quiet": now[0] <= limit}
        log(f"load average {now[0]:.2f} > {limit}: waiting {step:g} s")
        sleep(step)
        waited += step


# --- the measurement ---

def _open(name: str, params: dict[str, Any]):
    """The scene loaded in the bench's variant, and its full-depth ``path`` integrator."""
    info = scenes.inspect_scene(name, **params)
    with quiet_mitsuba():
        loaded = scenes.load_scene(info.path, VARIANT, **params)
    return loaded, scenes.path_integrator(-1, info)


def prepare_row(name: str, target: float, params: dict[str, Any], spp: int) -> dict[str, Any]:
    """The untimed part of a row: its reference (rendered if not cached) with its relative
    noise, and the two oracles (:func:`~phonglab.bench.adaptive_sweeps.oracle_limits`)."""
    t0 = time.perf_counter()
    ref = references.reference(name, spp, params=params)
    noise = metrics.relative_noise(ref.image, ref.stderr)
    loaded, integ = _open(name, params)
    limits = oracle_limits(loaded, integ, target)
    return {"scene": name, "params": params, "target": target, "reference_spp": ref.spp,
            "reference_noise": noise, "reference_noise_e": noise / target,
            "reference_render_seconds": float(ref.metadata.get("render_seconds", "nan")),
            "prepare_seconds": time.perf_counter() - t0, **limits}


def timed_row(prepared: dict[str, Any], seeds: int) -> dict[str, Any]:
    """The timed part of a row: a warm-up seed (dropped), then ``seeds`` seeds of
    :func:`~phonglab.bench.adaptive_sweeps.oracle_seed` with the decomposition; the row's
    figures (:func:`~phonglab.bench.adaptive_sweeps.oracle_summary`,
    :func:`~phonglab.bench.adaptive_sweeps.cost_factors`)."""
    name, params, target = prepared["scene"], prepared["params"], prepared["target"]
    ref = references.reference(name, prepared["reference_spp"], params=params)
    loaded, integ = _open(name, params)
    oracle_seed(loaded, integ, target, None, 50, decompose=True)          # warm-up, dropped
    rows = [oracle_seed(loaded, integ, target, ref, s, decompose=True) for s in range(seeds)]
    return {**prepared, **oracle_summary(prepared, rows), **cost_factors(rows), "rows": rows}


# --- the account of a missed row (pure) ---

def share_terms(row: dict[str, Any]) -> dict[str, float]:
    """The terms whose product is a row's share of the time oracle (module docstring), each
    below 1 where it costs share: allocation G/O_s, path cost O_s/(O_t·P), 1/wavefront,
    1/passes, 1/host.  Where passes < 1 (one pass of the final counts ran slower than the
    passes that traced them, so the one-pass trace is no floor and the split between
    placement and passes is not resolved) the two are one term, O_s/(O_t·P·passes)."""
    f = row["factors"]
    terms = {"allocation": row["equal_samples"] / row["oracle"]}
    if f["passes"] < 1.0:
        terms["path cost and passes (split unresolved)"] = (
            row["oracle"] / (row["oracle_time"] * f["placement"] * f["passes"]))
    else:
        terms["path cost"] = row["oracle"] / (row["oracle_time"] * f["placement"])
        terms["passes"] = 1.0 / f["passes"]
    return {**terms, "wavefront": 1.0 / f["wavefront"], "host": 1.0 / f["host"]}


def account(row: dict[str, Any]) -> str | None:
    """What holds a missed row back, in one sentence from its figures; None where the row met
    its target or has none."""
    if row.get("met") is not False:
        return None
    if row["oracle_time"] >= ORACLE_MATTERS:
        terms, have, goal = share_terms(row), row["share_time"], ORACLE_SHARE
        product = math.prod(terms.values())
        losers = sorted(((v, k) for k, v in terms.items() if v < 1.0))
        lifted, names = have, []
        for v, k in losers:
            lifted /= v
            names.append(f"{k} ×{v:.2f}")
            if lifted >= goal:
                break
        spread = have / product
        rest = ("" if abs(spread - 1.0) <= 0.05 else
                f"; the seeds' spread, a median of ratios against a product of medians, "
                f"×{spread:.2f}")
        tail = ("" if lifted >= goal else
                f"; even without every such term it would reach only {lifted:.2f}")
        return (f"{_figure(have, goal)} of the time oracle (the terms multiply to "
                f"{product:.2f}{rest}): "
                f"held back by {', '.join(names) or 'nothing below 1'}; without "
                f"{'it' if len(names) == 1 else 'them'} {lifted:.2f}{tail}.")
    cost = 1.0 / row["achieved"]["median"]
    f = row["factors"]
    gainers = sorted(((v, k) for k, v in f.items() if v > 1.0), reverse=True)
    lowered, names = cost, []
    for v, k in gainers:
        lowered /= v
        names.append(f"{k} ×{v:.2f}")
        if lowered <= OVERHEAD_TARGET:
            break
    tail = ("" if lowered <= OVERHEAD_TARGET else
            f"; even without every factor above 1 it would be {lowered:.2f}x")
    return (f"cost {cost:.2f}x uniform (the factors multiply to "
            f"{math.prod(f.values()):.2f}x): held back by {', '.join(names) or 'no factor above 1'}"
            f"; without {'it' if len(names) == 1 else 'them'} {lowered:.2f}x{tail}.")


# --- the BENCHMARKS.md section (pure) ---

def _achieved(a: dict) -> str:
    return f"{a['median']:.2f}x [{a['min']:.2f}–{a['max']:.2f}]" if a else "—"


def _figure(x: float, bound: float) -> str:
    """``x`` to 2 decimals, or 3 where 2 would round it onto the other side of ``bound``."""
    return f"{x:.3f}" if (round(x, 2) >= bound) != (x >= bound) else f"{x:.2f}"


def _share_cell(r: dict) -> str:
    if r["oracle_time"] >= 1.05:
        return _figure(r["share_time"], ORACLE_SHARE)
    return f"cost {_figure(1.0 / r['achieved']['median'], OVERHEAD_TARGET + 1e-12)}x"


def report_rows(data: dict[str, Any]) -> list[str]:
    """The section's lines from the JSON record ``data`` (:func:`report_section`)."""
    rows, meta = data["rows"], data["meta"]
    scales = sorted({r["scale"] for r in rows})
    scenes_ = list(dict.fromkeys(r["scene"] for r in rows))
    at = {(r["scene"], r["scale"]): r for r in rows}
    labels = [statistics.mode(size_label(r["params"]) for r in rows if r["scale"] == s)
              for s in scales]
    nb = [size_label(at[("nb_sphere_row", s)]["params"]) for s in scales
          if ("nb_sphere_row", s) in at]
    furnace = [size_label(at[(UNIFORM_SCENE, s)]["params"]) for s in scales
               if (UNIFORM_SCENE, s) in at]
    lo, hi = meta["load_start"], meta["load_end"]
    L = ["\n### Adaptive sampling against its limit at three sizes (issue 53)\n",
         f"`scripts/adaptive_oracle.py` (`make adaptive-oracle`, "
         f"`phonglab.bench.adaptive_oracle`; docs/adaptive.md): the oracle rows above at the "
         f"bench's size scaled by {', '.join(str(s) for s in scales)} in each direction "
         f"({', '.join(labels)}"
         + (f"; nb_sphere_row keeps 4:1, {', '.join(nb)}" if nb else "")
         + (f"; the furnace {', '.join(furnace)}" if furnace else "")
         + f"), measured {meta['date']} on {meta.get('cores', '?')} cores "
         f"in one timed run of {meta['timed_seconds'] / 60:.1f} min (1-minute load average "
         f"{lo[0]} at its start, {hi[0]} at its end, the run's own threads included; "
         f"references, rendered where not cached, "
         f"and oracle maps computed before, {meta['prepare_seconds_all'] / 60:.1f} min). "
         f"Per row a warm-up seed, dropped, then {meta['seeds']} seeds, each an adaptive "
         f"render followed right after by "
         f"`mi.render` at its mean spp, so the ratio of a pair is robust to slow drift of the "
         f"machine's speed; achieved = median [min–max] over the seeds. Target: ≥ "
         f"{ORACLE_SHARE} of the time oracle where it is ≥ {ORACLE_MATTERS}x, cost ≤ "
         f"{OVERHEAD_TARGET}x uniform on the furnace (shown as 'cost').\n"]
    cores = meta.get("cores") or 1
    if lo[0] > QUIET_LOAD or hi[0] - cores > QUIET_LOAD:
        L.append(f"> **Note:** other processes shared the cores (load average {lo[0]} before "
                 f"the run, {hi[0]} at its end with its own ~{cores} threads): the rows are "
                 f"noisier than a quiet run's.\n")
    head = "| scene | E | " + " | ".join(
        f"{lab}: time oracle | achieved | / time oracle | met" for lab in labels) + " |"
    L += [head, "|---|---|" + "---|---|---|---|" * len(scales)]
    for sc in scenes_:
        first = next(at[(sc, s)] for s in scales if (sc, s) in at)
        cells = []
        for s in scales:
            r = at.get((sc, s))
            cells += (["—"] * 4 if r is None else
                      [f"{r['oracle_time']:.2f}x", _achieved(r["achieved"]), _share_cell(r),
                       fmt_met(r["met"])])
        L.append(f"| {sc} | {first['target']:g} | " + " | ".join(cells) + " |")
    L += ["\n**Where adaptive's time goes, by size**: adaptive's time over `mi.render`'s at its "
          "mean spp = wavefront (one pass of uniform counts / `mi.render`) × placement (one "
          "pass of adaptive's final counts / uniform counts) × passes (the render's own tracing "
          "/ that one pass: launches, Q) × host (the whole render / its tracing); medians over "
          "the seeds.\n",
          "| scene | size | adaptive [s] | `mi.render` [s] | spp | passes run | equal samples "
          "| " + " | ".join(COST_FACTORS) + " | total |",
          "|---|---|---|---|---|---|---|" + "---|" * (len(COST_FACTORS) + 1)]
    for sc in scenes_:
        for s in scales:
            r = at.get((sc, s))
            if r is None:
                continue
            m = r["medians"]
            L.append(f"| {sc} | {size_label(r['params'])} | {m['seconds']:.3f} | "
                     f"{m['pair_seconds']:.3f} | {m['spp']:.0f} | {m['passes']:.0f} | "
                     f"{r['equal_samples']:.2f}x | "
                     + " | ".join(f"{r['factors'][k]:.2f}" for k in COST_FACTORS)
                     + f" | {r['total']:.2f} |")
    trend = []
    for k in COST_FACTORS:
        meds = [statistics.median(at[(sc, s)]["factors"][k] for sc in scenes_ if (sc, s) in at)
                for s in scales]
        trend.append(f"{k} " + " → ".join(f"{v:.2f}" for v in meds))
    L.append(f"\nMedian over the scenes, {' → '.join(labels)}: " + "; ".join(trend) + ".\n")
    L += [f"References (full depth, spp and their own relative noise / E; at "
          f"{labels[0]} the bench's, larger sizes by the rule of "
          f"`phonglab.bench.adaptive_oracle.reference_spp`: noise ≤ {REFERENCE_NOISE_SHARE:g} E "
          f"predicted from the next smaller size, at most {ORACLE_REFERENCE_SPP} spp):\n",
          "| scene | " + " | ".join(labels) + " |", "|---|" + "---|" * len(scales)]
    for sc in scenes_:
        L.append(f"| {sc} | " + " | ".join(
            "—" if (sc, s) not in at else
            f"{at[(sc, s)]['reference_spp']} spp, {at[(sc, s)]['reference_noise_e']:.2f} E"
            for s in scales) + " |")
    met = {s: [at[(sc, s)]["met"] for sc in scenes_ if (sc, s) in at] for s in scales}
    L.append("\nTargets met: " + ", ".join(
        f"{lab} {sum(m is True for m in met[s])} of {sum(m is not None for m in met[s])}"
        for lab, s in zip(labels, scales)) + ".\n")
    missed = [(sc, s) for sc in scenes_ for s in scales
              if (sc, s) in at and at[(sc, s)]["met"] is False]
    if missed:
        L.append("What holds each missed row back, from its figures "
                 "(`phonglab.bench.adaptive_oracle.account`). The share of the time oracle is, "
                 "up to the seeds' spread, the product of allocation (equal samples / sample "
                 "oracle: the guards, the estimates), path cost (sample oracle / time oracle / "
                 "placement: what the samples' paths cost against what the time oracle trades "
                 "for), 1/wavefront, 1/passes and 1/host; where passes < 1 the one-pass trace "
                 "is no floor and path cost and passes are one term. Named: the terms below 1, "
                 "smallest first, until the share without them reaches the target; on the "
                 "furnace the factors above 1 until the cost reaches 1.05x.\n")
        L += [f"* {sc} {size_label(at[(sc, s)]['params'])}: {account(at[(sc, s)])}"
              for sc, s in missed]
    return L + [""]


def report_section(d: RunData) -> list[str]:
    """BENCHMARKS.md's three-size oracle section (empty when ``adaptive_oracle.json`` is not
    in the bench folder)."""
    data = part_record(d, JSON_NAME)
    return report_rows(data) if data else []
