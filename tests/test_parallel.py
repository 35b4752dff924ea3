"""phonglab.parallel: serial, LocalCluster and a real Dask cluster give the same results.

The cluster tests start a real ``dask scheduler`` and two ``dask worker`` processes on the
loopback interface (random free port, each in its own process group, torn down in a
``finally``), run ``phonglab bench --quick --only stability`` there and compare its CSV,
timing columns aside, with a serial run of the same command, bit for bit; the same for four
conformance cases of ``phonglab validate``.  The slow tier adds the run with one worker
process killed (SIGKILL) mid-sweep and the whole ``validate --all-builtins`` command.
Timing columns (wall times, compile statistics) are measurements of the machine, not
results, and differ from run to run anyway.
"""

from __future__ import annotations

import csv
import json
import math
import os
import re
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import psutil
import pytest

from phonglab import parallel, runtime
from phonglab.bench import csvlog
from phonglab.bench.config import LOGS, STABILITY_CELLS
from phonglab.bench.jobs import put_in_order
from phonglab.cli import main
from phonglab.errors import PhonglabError
from phonglab.parallel import Job, Runner, check_address

#: Columns that are measured times or compile statistics (machine state, not results).
TIMING = {"wall_time_s", "first_call_s", "seconds", "t_a", "t_b", "ratio", "steady_s",
          "compile_ms", "kernels", "cache_hits", "cold_compile_ms", "t_graphics", "t_radiance"}
#: Methods whose sums Dr.Jit reduces with concurrent float64 atomic adds, so that their last
#: bits vary from run to run even serially: ``mis_optimal`` (physics.estimators.kernel.row_sums,
#: dr.scatter_reduce(Add, mode=ReduceMode.Local); measured: var_n differed in the last hex
#: digit between serial runs with 2 Dr.Jit threads, not with 1).
ATOMIC_SUMS = {"mis_optimal"}
#: Their float columns agree to summation-order round-off: a float64 sum of n <= 2^14 terms
#: reordered moves by at most n·2^-53 ≈ 2e-12 of Σ|terms|; 1e-9 relative leaves room for
#: the cancellation in the variance (Σx² − (Σx)²/n) without hiding a real difference.
ATOMIC_RTOL = 1e-9
BIN = Path(sys.executable).parent


def results(out: Path) -> dict[str, list[dict]]:
    """Every CSV of a bench folder, rows in file order, timing columns removed."""
    found = {}
    for path in sorted(out.glob("*.csv")):
        with path.open(newline="") as f:
            found[path.name] = [{k: v for k, v in r.items() if k not in TIMING}
                                for r in csv.DictReader(f)]
    return found


def assert_same_results(got: dict, want: dict) -> None:
    """``got == want``, bit for bit, except the float columns of :data:`ATOMIC_SUMS` rows."""
    assert got.keys() == want.keys()
    for name in want:
        assert len(got[name]) == len(want[name]), name
        for g, w in zip(got[name], want[name]):
            if w.get("method") not in ATOMIC_SUMS:
                assert g == w, name
                continue
            assert g.keys() == w.keys()
            for k in w:
                try:
                    a, b = float(g[k]), float(w[k])
                except ValueError:
                    assert g[k] == w[k], (name, k)
                    continue
                assert a == pytest.approx(b, rel=ATOMIC_RTOL, nan_ok=True), (name, k)


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _stop(proc: subprocess.Popen) -> None:
    """SIGTERM the process group, then SIGKILL what is left (no leaked workers)."""
    try:
        os.killpg(proc.pid, signal.SIGTERM)
    except ProcessLookupError:
        return
    try:
        proc.wait(timeout=10)
    except subprocess.TimeoutExpired:
        pass
    try:
        os.killpg(proc.pid, signal.SIGKILL)
    except ProcessLookupError:
        pass
    proc.wait(timeout=10)


@pytest.fixture(scope="module")
def cluster(tmp_path_factory):
    """A scheduler and two single-thread workers on 127.0.0.1: yields (address, worker Popens)."""
    tmp = tmp_path_factory.mktemp("cluster")
    port = free_port()
    address = f"tcp://127.0.0.1:{port}"
    env = dict(os.environ, PHONGLAB_WORKER_CACHE=str(tmp / "kernels"), MPLBACKEND="Agg")
    procs = []
    try:
        procs.append(subprocess.Popen(
            [BIN / "dask", "scheduler", "--host", "127.0.0.1", "--port", str(port),
             "--no-dashboard"], env=env, cwd=tmp, start_new_session=True,
            stdout=subprocess.DEVNULL, stderr=(tmp / "scheduler.log").open("w")))
        for k in range(2):
            procs.append(subprocess.Popen(
                [BIN / "dask", "worker", address, "--nthreads", "1", "--nworkers", "1",
                 "--no-dashboard", "--name", f"w{k}"], env=env, cwd=tmp, start_new_session=True,
                stdout=subprocess.DEVNULL, stderr=(tmp / f"worker{k}.log").open("w")))
        from distributed import Client

        with Client(address, timeout=30) as client:
            client.wait_for_workers(2, timeout=60)
        yield address, procs[1:]
    finally:
        for proc in reversed(procs):
            _stop(proc)


@pytest.fixture(scope="module")
def serial_stability(tmp_path_factory):
    """The CSVs of a serial ``phonglab bench --quick --only stability``."""
    out = tmp_path_factory.mktemp("serial") / "b"
    assert main(["bench", "--quick", "--only", "stability", "--out", str(out), "--no-progress"]) == 0
    return results(out)


def bench_cmd(out: Path, *extra: str) -> list[str]:
    return [str(BIN / "phonglab"), "bench", "--quick", "--only", "stability", "--out", str(out),
            "--no-progress", *extra]


def test_cluster_results_identical_to_serial(cluster, serial_stability, tmp_path):
    address, _ = cluster
    out = tmp_path / "b"
    assert main(["bench", "--quick", "--only", "stability", "--out", str(out), "--no-progress",
                 "--scheduler", address]) == 0
    assert_same_results(results(out), serial_stability)
    assert len(serial_stability["stability.csv"]) == STABILITY_CELLS
    assert json.loads((out / "run.json").read_text())["execution"]["where"] == address


@pytest.mark.slow
def test_cluster_survives_a_killed_worker(cluster, serial_stability, tmp_path):
    """SIGKILL one worker process mid-sweep: its job is rescheduled, the CSV is the same."""
    address, workers = cluster
    out = tmp_path / "b"
    log = out / LOGS["stability"][0]
    bench = subprocess.Popen(bench_cmd(out, "--scheduler", address), stdout=subprocess.PIPE,
                             stderr=subprocess.PIPE, text=True, start_new_session=True)
    try:
        deadline = time.monotonic() + 120
        while not (log.is_file() and len(log.read_text().splitlines()) > 60):
            assert bench.poll() is None and time.monotonic() < deadline
            time.sleep(0.05)
        # The worker process itself is the nanny's child; the nanny starts a new one.
        victim = psutil.Process(workers[0].pid).children(recursive=True)[0]
        victim.send_signal(signal.SIGKILL)
        rows_at_kill = len(log.read_text().splitlines()) - 1
        stdout, stderr = bench.communicate(timeout=300)
    finally:
        if bench.poll() is None:
            _stop(bench)
    assert rows_at_kill < STABILITY_CELLS          # the sweep was still running
    assert not victim.is_running() or victim.status() == psutil.STATUS_ZOMBIE
    assert bench.returncode == 0, stderr
    assert_same_results(results(out), serial_stability)


def test_unreachable_scheduler_is_one_sentence(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(parallel, "CONNECT_TIMEOUT", 1.0)
    out = tmp_path / "b"
    out.mkdir()
    (out / "stability.csv").write_text("kept\n")
    t0 = time.monotonic()
    code = main(["bench", "--quick", "--fresh", "--out", str(out),
                 "--scheduler", f"tcp://127.0.0.1:{free_port()}"])
    err = capsys.readouterr().err.strip()
    assert code == 2
    assert err.startswith("phonglab: error: cannot reach the Dask scheduler at tcp://127.0.0.1:")
    assert len(err.splitlines()) == 1 and "Traceback" not in err
    assert time.monotonic() - t0 < 30
    assert (out / "stability.csv").read_text() == "kept\n"     # --fresh deleted nothing


def test_scheduler_without_workers_is_one_sentence(tmp_path, capsys, monkeypatch):
    from distributed import LocalCluster

    monkeypatch.setattr(parallel, "CONNECT_TIMEOUT", 1.0)
    with LocalCluster(n_workers=0, processes=False, protocol="tcp", host="127.0.0.1",
                      dashboard_address=":0") as empty:
        code = main(["bench", "--quick", "--out", str(tmp_path / "b"),
                     "--scheduler", empty.scheduler_address])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1
    assert "has no workers after 1 s; start one on each machine with `dask worker" in err


@pytest.mark.parametrize("bad", ["127.0.0.1:8786", "tcp://", "http://host:1 2", ""])
def test_malformed_scheduler_address_is_one_sentence(bad):
    with pytest.raises(PhonglabError, match="not a Dask scheduler address"):
        check_address(bad)


def test_workers_must_be_positive():
    with pytest.raises(PhonglabError, match="--workers must be at least 1"):
        Runner(workers=0)


def test_serial_runner_runs_in_order_without_dask():
    code = ("import math, sys; from phonglab.parallel import Runner, Job\n"
            "with Runner(progress=False) as r:\n"
            "    print(r.run([Job(math.factorial, (k,), key=k) for k in range(5)]))\n"
            "print('distributed' in sys.modules, 'dask' in sys.modules)\n")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          cwd=Path(__file__).resolve().parents[1], timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.split("\n")[:2] == ["[1, 1, 2, 6, 24]", "False False"]


def test_local_cluster_reference_passes_bit_identical_to_serial(tmp_path):
    """A reference rendered as one job per pass on a 2-process LocalCluster, merged here,
    equals the serial render's image and standard error bit for bit (box filter)."""
    from phonglab.engine import references
    from phonglab.bench.cornell import CornellSpec

    spec = CornellSpec(walls="diffuse", boxes="phong", res=8)
    refs = []
    for name, runner in (("serial", Runner(progress=False)), ("local", Runner(2, progress=False))):
        cache = tmp_path / name
        with runner:
            refs.append(references.reference(spec.scene_file(cache), 32, spec.params(),
                                             "llvm_ad_rgb", max_depth=None, cache_dir=cache,
                                             runner=runner))
        if name == "local":
            assert len(runner.timings) == references.PASSES        # one job per pass
    (a, b) = refs
    assert np.array_equal(a.image, b.image) and np.array_equal(a.stderr, b.stderr)
    assert np.all(a.stderr > 0)


def test_rows_are_put_in_the_serial_order(tmp_path):
    log = csvlog.open_log(tmp_path, "cost")
    keys = [dict(scene="s", method=m, round=r) for r in range(2) for m in ("a", "b")]
    log.add(dict(scene="other", method="x", round=0, samples=1, seconds=0.5))
    for k in (keys[3], keys[0], keys[2], keys[1]):          # as a cluster returns them
        log.add(dict(k, samples=1, seconds=1.0))
    put_in_order(log, keys)
    again = csvlog.open_log(tmp_path, "cost")
    assert [(r["scene"], r["method"], r["round"]) for r in again.rows] == \
        [("other", "x", "0")] + [("s", k["method"], str(k["round"])) for k in keys]


def _without_timings(x):
    """A validate report (JSON data) without its wall-time fields (and its time profile)."""
    if isinstance(x, dict):
        return {k: _without_timings(v) for k, v in x.items()
                if k not in ("seconds", "topic_seconds", "wall_seconds", "profile")}
    if isinstance(x, list):
        return [_without_timings(v) for v in x]
    return x


def test_cluster_validate_cases_identical_to_serial(cluster):
    """Conformance cases as jobs on the cluster give the serial reports (timings aside)."""
    from phonglab.validate import batch
    from phonglab.validate.bsdf import builtins

    address, _ = cluster
    cases = builtins.cases()[:4]
    options = {"seed": 0, "quick": True, "topics": ["finite", "eval_pdf", "weight"]}
    serial = batch.run_all(cases, options)
    with Runner(scheduler=address, progress=False) as runner:
        distributed = batch.run_all(cases, options, runner=runner)
        assert len(runner.timings) == len(cases)
    assert [r["meta"]["case"] for r in distributed["reports"]] == [c.label for c in cases]
    assert _without_timings(distributed) == _without_timings(serial)


@pytest.mark.slow
def test_cluster_validate_all_builtins_cli_identical_to_serial(cluster, tmp_path):
    address, _ = cluster
    base = [str(BIN / "phonglab"), "validate", "--all-builtins", "--quick", "--only", "finite",
            "--only", "eval_pdf"]
    runs = {}
    for name, extra in (("serial", []), ("cluster", ["--scheduler", address])):
        path = tmp_path / f"{name}.json"
        proc = subprocess.run(base + ["--json", str(path)] + extra, capture_output=True,
                              text=True, timeout=600)
        assert proc.returncode in (0, 1), proc.stderr          # 1: a case fails a row
        runs[name] = json.loads(path.read_text())
    assert _without_timings(runs["cluster"]) == _without_timings(runs["serial"])


def test_kernel_cache_slots_are_exclusive_and_cleaned(tmp_path):
    """Each live process holds its own slot; a slot's stale Dr.Jit *.tmp files are removed."""
    from phonglab.parallel.worker import claim_slot

    stale = tmp_path / "worker-0" / ".drjit" / "0123.llvm.bin.tmp"
    stale.parent.mkdir(parents=True)
    stale.write_bytes(b"half a kernel")
    kept = stale.with_name("0123.llvm.bin")
    kept.write_bytes(b"a kernel")
    assert claim_slot(tmp_path) == tmp_path / "worker-0"
    assert not stale.exists() and kept.exists()
    # A second claimant (another open file description, as another process would have) is
    # refused the held slot and gets the next one.
    assert claim_slot(tmp_path) == tmp_path / "worker-1"


def scene_pixels(scene) -> int:
    """A job function taking a loaded mi.Scene (which cannot be pickled)."""
    return int(scene.sensors()[0].film().size()[0])


def kernel_thread_classes() -> tuple[int, list[int]]:
    """(pid, the scheduling policy of each Dr.Jit kernel thread of this process)."""
    return os.getpid(), [os.sched_getscheduler(t) for t in runtime.kernel_thread_ids()]


def kernels_on_the_pool(until_a_thread_in=None, most: int = 200) -> tuple[int, list[int]]:
    """Run kernels large enough to be split over Dr.Jit's threads (a kernel thread takes its
    name when it first runs a block) -- ``most`` of them, or until a kernel thread is in the
    class ``until_a_thread_in``; then :func:`kernel_thread_classes`."""
    import drjit as dr
    import mitsuba as mi

    for i in range(most):
        dr.eval(dr.sin(dr.arange(mi.Float, 1 << 22) + i))
        if until_a_thread_in is not None and until_a_thread_in in kernel_thread_classes()[1]:
            break
    return kernel_thread_classes()


@pytest.mark.skipif(not hasattr(os, "SCHED_IDLE"), reason="Linux's SCHED_IDLE class")
def test_kernel_threads_go_to_the_background_and_the_caller_stays(variant_llvm_rgb):
    """runtime.background_kernel_threads puts every Dr.Jit kernel thread in SCHED_IDLE (their
    spin between kernels then takes no core from another process) and leaves the calling
    thread in its own class."""
    import drjit as dr

    before = dr.thread_count()
    dr.set_thread_count(before + 1)      # a new kernel thread, in its creator's class
    try:
        _, classes = kernels_on_the_pool(until_a_thread_in=os.SCHED_OTHER)
        assert os.SCHED_OTHER in classes
        assert runtime.background_kernel_threads() == len(classes)
        assert set(kernel_thread_classes()[1]) == {os.SCHED_IDLE}
        assert os.sched_getscheduler(0) == os.SCHED_OTHER
    finally:
        dr.set_thread_count(before)


@pytest.fixture(scope="module")
def local_runner():
    """An embedded LocalCluster of two worker processes (phonglab's ``--workers 2``)."""
    with Runner(workers=2, progress=False) as runner:
        yield runner


def test_a_job_that_cannot_reach_a_worker_is_one_sentence(variant_llvm_rgb, local_runner):
    """A Job whose argument is a loaded Scene (it runs serially, but Dask cannot pickle it for
    a cluster) is one sentence before any job is sent, not Dask's pickling traceback."""
    import mitsuba as mi

    scene = mi.load_dict(mi.cornell_box())
    with Runner(progress=False) as serial:
        assert serial.run([Job(scene_pixels, (scene,), key="s")]) == [256]
    with pytest.raises(PhonglabError, match=r"job 's' cannot be sent to a worker "
                                            r"\(TypeError: cannot pickle 'Scene' object\)"):
        local_runner.run([Job(math.factorial, (3,), key="ok"),
                          Job(scene_pixels, (scene,), key="s")])
    assert local_runner.run([Job(math.factorial, (3,), key="ok")]) == [6]


def test_local_workers_malloc_threads_and_an_exr_texture(variant_llvm_rgb, local_runner,
                                                         tmp_path):
    """The embedded workers run without Dask's MALLOC_TRIM_THRESHOLD_ (which made every
    buffer of 128 KiB an mmap: 11 s of page faults in a 19 s sweep), with at least two
    Dr.Jit threads, so a sweep point whose plugin reads an EXR texture returns (at one
    thread Mitsuba 3.9.1's OpenEXR pool waits forever: tests/repro/exr_one_thread_hang.py;
    this test failed by its time limit before), and after a job their kernel threads are in
    the background (SCHED_IDLE: runtime.background_kernel_threads)."""
    from concurrent.futures import ThreadPoolExecutor

    import mitsuba as mi
    from phonglab.parallel import worker
    from phonglab.validate import sweep

    exr = tmp_path / "kd.exr"
    mi.Bitmap(np.full((8, 8, 3), 0.4, dtype=np.float32)).write(str(exr))
    spec = {"type": "diffuse", "reflectance": {"type": "bitmap", "filename": str(exr)}}
    options = {"kind": "bsdf", "variant": "llvm_ad_rgb", "plugins": [], "topics": ["finite"],
               "seed": 0, "quick": True, "known": None, "family": 1, "sizes": None}
    jobs = [Job(os.getenv, ("MALLOC_TRIM_THRESHOLD_",), key="env"),
            Job(worker.worker_report, key="report"),
            Job(sweep.run_point, (spec, {}, options), key="point")]
    pool = ThreadPoolExecutor(1)
    try:        # a hung worker must fail the test, not hang it: no wait for the thread
        env, report, point = pool.submit(local_runner.run, jobs).result(timeout=60)
    finally:
        pool.shutdown(wait=False)
    assert env is None
    assert report["threads"] >= runtime.MIN_KERNEL_THREADS
    # after a job the worker's kernel threads are in the background (SCHED_IDLE)
    local_runner.run([Job(kernels_on_the_pool, (None, 20), key=k) for k in range(4)])
    later = local_runner.run([Job(kernel_thread_classes, key=k) for k in range(4)])
    assert any(classes for _, classes in later), later
    assert all(set(classes) <= {os.SCHED_IDLE} for _, classes in later), later
    assert [r["status"] for r in point["results"]] == ["pass"] * len(point["results"])
    assert point["results"]


@pytest.mark.slow
def test_ctrl_c_of_a_workers_run_is_one_line_and_leaves_no_worker(tmp_path):
    """Ctrl-C reaches the whole process group and ends as one line: no LocalCluster worker
    prints its own KeyboardInterrupt traceback (which for `validate --all-builtins
    --workers 2` would be 88 lines)."""
    proc = subprocess.Popen([str(BIN / "phonglab"), "validate", "--all-builtins", "--quick",
                             "--workers", "2", "--json", str(tmp_path / "all.json")],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                            cwd=tmp_path, start_new_session=True)
    err, deadline = "", time.monotonic() + 240
    two_done = re.compile(r"\|\s*([2-9]|\d\d+)/\d+ \[")   # two cases done (tqdm may skip a count)
    while not two_done.search(err) and time.monotonic() < deadline:
        chunk = proc.stderr.read(1)
        if not chunk:
            break
        err += chunk
    assert two_done.search(err), err
    workers = [c.pid for c in psutil.Process(proc.pid).children(recursive=True)]
    assert workers, "no worker processes"
    os.killpg(proc.pid, signal.SIGINT)
    err += proc.stderr.read()
    assert proc.wait(timeout=60) == 130
    assert "Traceback" not in err and "KeyboardInterrupt" not in err, err[-3000:]
    lines = [ln.strip() for ln in err.replace("\r", "\n").splitlines() if ln.strip()]
    assert lines[-1] == "phonglab: interrupted; files already written are complete.", lines[-5:]
    time.sleep(1)
    assert not [p for p in workers if psutil.pid_exists(p)
                and psutil.Process(p).status() != psutil.STATUS_ZOMBIE], "workers left running"


def test_local_worker_counts_are_bounded_before_any_process_starts():
    """--workers 1000 on 2 cores started 1000 processes (each ~200 MB of Mitsuba)."""
    with pytest.raises(PhonglabError, match=r"--workers 1000 starts more than 4 processes per "
                                            r"core on this \d+-core machine"):
        Runner(workers=1000)
    with pytest.raises(PhonglabError, match=r"--workers 8 would need about 2.0 GiB"):
        parallel.check_local_workers(8, cores=4, memory=1 << 30)
    parallel.check_local_workers(2, cores=2, memory=1 << 30)
    Runner(workers=1000, scheduler="tcp://127.0.0.1:1")     # a cluster's size is its own


class _Meter:
    """A measured first job: its seconds, the cores the rest of the machine left free and
    the cores it kept busy itself."""

    def __init__(self, seconds, free, used):
        self.seconds, self.free, self.used = seconds, free, used


@pytest.mark.parametrize("jobs, seconds, free, used, share, memory, workers", [
    (10, 6.0, 2, 1.0, 0.0, 8 << 30, 2),     # 60 s of Python-bound work, two free cores: 30 s
    (10, 6.0, 2, 1.45, 0.0, 8 << 30, 2),    # a validate process (1.45 cores busy here): 30 s
    (10, 0.8, 2, 1.45, 0.0, 8 << 30, 1),    # ... a short sweep: 4 s, below the start's
    (10, 2.0, 2, 1.0, 0.7, 8 << 30, 1),     # 70 % in kernels, on both cores already: 3 s
    (3, 10.0, 2, 1.97, 0.95, 8 << 30, 1),   # a render-bound sweep (path)
    (10, 6.0, 8, 1.0, 0.0, 8 << 30, 5),     # as many as are free, as few as 2 rounds need ...
    (3, 3.3, 2, 1.4, 0.0, 8 << 30, 1),      # 3 points on 2: 2 rounds, 1.5x: 3.3 s (diffuse)
    (3, 30.0, 8, 1.0, 0.0, 8 << 30, 3),     # ... but no more than the jobs
    (10, 6.0, 8, 1.0, 0.0, 3 * parallel.WORKER_BYTES, 3),   # ... no more than memory holds
    (10, 6.0, 8, 1.0, 0.0, parallel.WORKER_BYTES, 1),       # memory for one: here
    (10, 6.0, 1, 1.0, 0.0, 8 << 30, 1),     # another process holds a core (a test runner's)
    (1, 100.0, 2, 1.0, 0.0, 8 << 30, 1),    # one job left: nothing to spread
])
def test_automatic_runner_spreads_only_what_saves_time_on_free_cores(jobs, seconds, free, used,
                                                                      share, memory, workers):
    """n worker processes, each keeping one free core busy (their kernel threads in the
    background), take the jobs in ⌈jobs/n⌉ rounds, g = jobs/⌈jobs/n⌉ times as fast, and
    save R·(1 − kernel share)·(1 − 1/g) of the serial remainder R."""
    where = parallel.auto_workers(jobs, _Meter(seconds, free, used), "points", memory=memory,
                                  kernel_share=share)
    assert where["workers"] == workers
    assert where["free_cores"] == free and where["first_seconds"] == seconds
    assert where["used_cores"] == used and where["kernel_share"] == share
    n = max(1, min(free, jobs, memory // parallel.WORKER_BYTES))
    g = jobs / math.ceil(jobs / n)
    assert where["predicted_saving_s"] == pytest.approx(
        jobs * seconds * (1 - share) * max(0.0, 1 - 1 / g), abs=0.051)
    assert "points" in where["reason"]


def test_automatic_runner_predicts_from_the_later_jobs_time():
    """A later sweep point runs no informational topic: its time, not the first point's,
    makes the prediction."""
    meter = _Meter(6.0, 2, 1.0)
    assert parallel.auto_workers(10, meter, "points", memory=8 << 30)["workers"] == 2
    where = parallel.auto_workers(10, meter, "points", memory=8 << 30, job_seconds=0.8)
    assert where["workers"] == 1 and where["job_seconds"] == 0.8
    assert where["predicted_saving_s"] == pytest.approx(4.0)


def test_core_meter_sees_a_core_taken_by_another_process():
    """A child process spinning on one core for the whole block leaves at most cores − 1 free
    (whatever else runs: a meter that ignored other processes would find every core free)."""
    spin = subprocess.Popen([sys.executable, "-c", "import time\nt = time.time()\n"
                             "while time.time() - t < 2.5: pass"])
    try:
        time.sleep(0.5)
        with parallel.CoreMeter() as busy:
            time.sleep(1.5)
    finally:
        spin.wait()
    assert busy.free <= len(os.sched_getaffinity(0)) - 1
    assert 1.4 < busy.seconds < 3.0
