"""``make test`` from a fresh clone, cold and warm (:mod:`phonglab.bench.fast_tier` says how).

    python scripts/fast_tier_timing.py [--warm 2] [--own-home 1] [--json docs/bench/fast_tier.json]

Nothing else should run meanwhile: the record keeps the load averages of every run.
"""

from __future__ import annotations

import argparse
import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from phonglab.bench.fast_tier import summary
from phonglab.engine.outputs import write_json

ROOT = Path(__file__).resolve().parents[1]


def run(cmd: list[str], cwd: Path, env: dict) -> tuple[float, str, int]:
    """(wall seconds, stdout and stderr, exit code) of ``cmd``."""
    t0 = time.perf_counter()
    # Ctrl-C as at a terminal: a background job inherits SIGINT ignored, which Python then
    # keeps (no KeyboardInterrupt), and the tests of phonglab's Ctrl-C routing would fail
    proc = subprocess.run(cmd, cwd=cwd, env=env, capture_output=True, text=True,
                          preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    return time.perf_counter() - t0, proc.stdout + proc.stderr, proc.returncode


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--warm", type=int, default=2, help="warm runs after the cold one")
    ap.add_argument("--own-home", type=int, default=0, metavar="N",
                    help="then N runs with this machine's own HOME (its long-used kernel cache)")
    ap.add_argument("--json", metavar="PATH", help="write the record (docs/bench/fast_tier.json)")
    args = ap.parse_args()
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, text=True,
                            capture_output=True, check=True).stdout.strip()
    with tempfile.TemporaryDirectory() as tmp:
        clone, home = Path(tmp) / "clone", Path(tmp) / "home"
        home.mkdir()
        subprocess.run(["git", "clone", "--quiet", str(ROOT), str(clone)], check=True)
        env = dict(os.environ)
        setup_s, out, code = run(["make", "setup"], clone, env)
        if code:
            print(out[-3000:], file=sys.stderr)
            print(f"make setup failed in the clone (exit {code})", file=sys.stderr)
            return 2
        print(f"make setup: {setup_s:.1f} s", flush=True)
        own = dict(env)
        env["HOME"] = str(home)
        runs = []
        for mode in ["cold"] + ["warm"] * args.warm + ["own HOME"] * args.own_home:
            before = round(os.getloadavg()[0], 2)
            seconds, out, code = run(["make", "test"], clone, own if mode == "own HOME" else env)
            record = {"mode": mode, "seconds": round(seconds, 1), "exit_code": code,
                      "load_before": before, "load_after": round(os.getloadavg()[0], 2),
                      **summary(out),
                      "failures": [line for line in out.splitlines()
                                   if line.startswith(("FAILED", "ERROR"))]}
            runs.append(record)
            print(record, flush=True)
    data = {"commit": commit, "cores": len(os.sched_getaffinity(0)),
            "setup_seconds": round(setup_s, 1), "runs": runs}
    if args.json:
        write_json(Path(args.json), data, indent=1)
    return 0 if all(r["exit_code"] == 0 for r in runs) else 1


if __name__ == "__main__":
    sys.exit(main())
