#!/usr/bin/env python3
"""A small GPU check for authors with an NVIDIA GPU: does phonglab give the same answers in
``cuda_ad_rgb`` as in ``llvm_ad_rgb``?

    python scripts/gpu_check.py                 # from a checkout or with phonglab installed
    python scripts/gpu_check.py --spp 128 --out out/gpu_check

Steps (each a ``phonglab`` command in a subprocess, its output kept under --out):

1. ``phonglab doctor`` exits 0;
2. ``cornell_phong`` rendered in the CUDA variant and in ``llvm_ad_rgb`` at equal spp
   (independent seeds), compared with ``phonglab compare --json``: the mean difference must be
   within ``--z`` (default 4) standard errors, from the ``.stderr.exr`` files the renders write;
3. ``phonglab validate lambert|phong|diffuse --quick --variant cuda_ad_rgb`` each exit 0.

Exit 0: every step passed; 1: a step failed or mismatched (each named on stdout); 0 with a
line starting "SKIPPED" where no CUDA variant works (no GPU, no driver, a Mitsuba without
cuda variants) -- or 77 (the automake "skipped" code) with ``--require-gpu``, so a CI job on a
GPU runner fails loudly rather than skipping.

``--variant llvm_ad_rgb`` runs the same steps with the LLVM backend in place of CUDA (a dry
run of the script itself on a machine without a GPU).

Status: written 2026-12-04 on a machine without a GPU; only the skip and the ``--variant
llvm_ad_rgb`` dry run have been run -- it has not run on a GPU yet.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

SKIPPED = 77
ROOT = Path(__file__).resolve().parent.parent


def phonglab(*args, out: Path, name: str, timeout: float = 1800) -> subprocess.CompletedProcess:
    """``python -m phonglab.cli ARGS``, its stdout/stderr kept in OUT/NAME.log."""
    env = dict(os.environ)
    if (ROOT / "src" / "phonglab").is_dir():       # a checkout: its own phonglab first
        env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(ROOT / "src"),
                                                          env.get("PYTHONPATH")]))
    t0 = time.perf_counter()
    r = subprocess.run([sys.executable, "-m", "phonglab.cli", *map(str, args)],
                       capture_output=True, text=True, env=env, timeout=timeout)
    (out / f"{name}.log").write_text(f"$ phonglab {' '.join(map(str, args))}\n"
                                     f"exit {r.returncode} in {time.perf_counter() - t0:.1f} s\n"
                                     f"--- stdout\n{r.stdout}\n--- stderr\n{r.stderr}\n")
    return r


def variant_works(variant: str) -> str | None:
    """None when ``variant`` sets and runs a kernel, else why not (one line)."""
    code = ("import mitsuba as mi, drjit as dr\n"
            f"mi.set_variant({variant!r})\n"
            "x = dr.arange(mi.Float, 16) + 1\n"
            "assert float(dr.sum(x)[0]) == 136.0\n")
    try:
        r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                           timeout=300)
    except subprocess.TimeoutExpired:
        return f"{variant} did not start within 300 s"
    if r.returncode == 0:
        return None
    lines = [ln for ln in (r.stderr or r.stdout).strip().splitlines() if ln.strip()]
    return lines[-1][:300] if lines else f"exit {r.returncode}"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--variant", default="cuda_ad_rgb", help="the variant under test "
                    "(default cuda_ad_rgb; llvm_ad_rgb: a dry run without a GPU)")
    ap.add_argument("--reference", default="llvm_ad_rgb", help="the variant compared against")
    ap.add_argument("--spp", type=int, default=64, help="samples per pixel of both renders")
    ap.add_argument("--z", type=float, default=4.0,
                    help="largest |mean difference| / standard error accepted (default 4)")
    ap.add_argument("--out", default="out/gpu_check", help="where renders and logs go")
    ap.add_argument("--require-gpu", action="store_true",
                    help=f"exit {SKIPPED} instead of 0 when the variant does not work")
    ap.add_argument("--skip-validate", action="store_true", help="no validate step")
    args = ap.parse_args(argv)
    if args.spp < 1:
        ap.error(f"--spp must be at least 1, got {args.spp}")

    why = variant_works(args.variant)
    if why is not None:
        print(f"SKIPPED: {args.variant} does not work here ({why}); nothing was checked")
        return SKIPPED if args.require_gpu else 0
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    failures: list[str] = []

    def step(label: str, ok: bool, detail: str = "") -> None:
        print(f"{'ok  ' if ok else 'FAIL'} {label}" + (f": {detail}" if detail else ""),
              flush=True)
        if not ok:
            failures.append(label)

    r = phonglab("doctor", out=out, name="doctor")
    step("phonglab doctor", r.returncode == 0, f"exit {r.returncode}")

    images = []
    for seed, variant in enumerate((args.variant, args.reference), start=1):
        exr = out / f"cornell_phong_{variant}_seed{seed}.exr"    # independent noise
        r = phonglab("render", "cornell_phong", "--variant", variant, "--spp", args.spp,
                     "--seed", seed, "-o", exr, out=out, name=f"render_{variant}_seed{seed}")
        step(f"render cornell_phong in {variant} at {args.spp} spp", r.returncode == 0,
             f"exit {r.returncode}")
        images.append(exr)
    if not failures:
        r = phonglab("compare", *images, "--json",
                     "--diff", out / "difference.png", out=out, name="compare")
        try:
            c = json.loads(r.stdout)
            z = float(c["z"])
            step(f"compare {args.variant} against {args.reference}", abs(z) <= args.z,
                 f"mean difference {c['mean_diff']:.3g} ± {c['mean_diff_stderr']:.2g} "
                 f"(z = {z:.2f}, limit {args.z:g}), RMSE {c['rmse']:.3g}, "
                 f"means {c['mean_a']:.4g} / {c['mean_b']:.4g}")
        except (ValueError, KeyError, TypeError):
            step(f"compare {args.variant} against {args.reference}", False,
                 f"exit {r.returncode}, no JSON: {r.stderr.strip()[-300:]}")

    if not args.skip_validate:
        for name in ("lambert", "phong", "diffuse"):
            r = phonglab("validate", name, "--quick", "--variant", args.variant, out=out,
                         name=f"validate_{name}")
            last = (r.stdout.strip().splitlines() or [""])[-1]
            step(f"validate {name} --quick --variant {args.variant}", r.returncode == 0,
                 last or f"exit {r.returncode}")

    print(f"\n{'all steps passed' if not failures else f'{len(failures)} step(s) failed'}; "
          f"logs in {out}/")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
