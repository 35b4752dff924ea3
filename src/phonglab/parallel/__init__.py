r"""One execution layer: a list of independent jobs mapped to their results, here or on Dask.

phonglab's heavy work is many independent jobs (bench cells, stability cells, the passes of a
reference render).  A :class:`Job` is a top-level (picklable) function and its arguments,
which carry everything the result depends on (its seed included), so the result is the same
wherever the job runs.  A :class:`Runner` maps a list of jobs to their results:

* **serially** (``workers=1``, no ``scheduler``): in this process, in list order; Dask is not
  imported;
* on an **embedded** :class:`distributed.LocalCluster` (``workers=N > 1``): N worker processes
  with one thread each (Mitsuba and Dr.Jit keep per-thread state and Python plugins must not
  be loaded concurrently, so parallelism is by process);
* on a **running cluster** (``scheduler="tcp://HOST:PORT"``, started by hand with
  ``dask scheduler`` / ``dask worker``; docs/cluster.md).

Every worker process is prepared once by :class:`phonglab.parallel.worker.PhonglabWorker`
(a ``distributed.WorkerPlugin``): its own Dr.Jit kernel-cache folder, the Mitsuba variant
set and phonglab's plugins registered.  Results stream back as jobs finish
(``distributed.as_completed``, a tqdm bar); :meth:`Runner.run` hands each to a callback at
once (the bench writes its CSV row there, so an interrupted run resumes) and returns them in
job order, so what is written from them does not depend on which worker was faster.

**Automatic** (``auto=True``, ``validate``'s default where no ``--workers`` is given): the
first job runs here while :class:`CoreMeter` measures how many cores the rest of the
machine left idle meanwhile; the remaining jobs then go to an embedded cluster of
:func:`auto_workers` processes (one per free core, as many as the memory holds) when two or
more cores are free and the processes are predicted to save at least
:data:`AUTO_MIN_SECONDS` (each job as long as the first; only the time outside Dr.Jit's
kernels spreads), else they run here too.  A cluster's start (~3 s with its workers'
imports and plugin loads) would double a short sweep; under another load (a test runner's
workers) the cores are not free and nothing starts.

Faults: a job whose worker dies (killed, out of memory) is rescheduled on another worker by
the scheduler (``distributed.scheduler.allowed-failures``, 3 by default, bounds how often);
a job whose function raises is re-run up to :data:`RETRIES` times, then its exception is
raised here.  A job that cannot be pickled (a loaded ``mi.Scene`` as an argument) is one
sentence before any job of the batch is sent (:func:`check_sendable`).  A scheduler that
cannot be reached within :data:`CONNECT_TIMEOUT` seconds is one
:class:`~phonglab.errors.PhonglabError` sentence.
"""

from __future__ import annotations

import logging
import os
import re
import signal
import time
from dataclasses import dataclass, field
from typing import Any, Callable, Hashable, Iterator, Sequence

from tqdm import tqdm

from ..errors import PhonglabError
from ..registration import register
from ..runtime import MIN_KERNEL_THREADS, available_memory, require_memory

#: Seconds to wait for a ``--scheduler`` before giving up with one sentence.
CONNECT_TIMEOUT = 5.0
#: Re-runs of a job whose function raised (a lost worker is rescheduled regardless).
RETRIES = 2
#: Local worker processes per core a LocalCluster may start (more only queue for the cores).
WORKERS_PER_CORE = 4
#: Memory of one worker process (Python, Mitsuba, Dr.Jit and kernels; a render process is
#: ~200 MB, phonglab.engine.render.BASE_BYTES), rounded up.
WORKER_BYTES = 256 << 20
#: Seconds an automatic runner's cluster must be predicted to save before it starts: its
#: start costs 1-3 s on 2 cores, and the prediction (:func:`auto_workers`) is an upper bound,
#: 2.5-3.6 times what 2 processes saved on 2 cores in the shortest sweeps that pay (--quick,
#: 2026-12-07: roughplastic predicted 9 s, 15.7/16.2 s here against 13.3/13.6 s on 2 workers;
#: principled 4.9 s, 12.5/12.2 against 10.4/10.5; hair 3 s, 9.2 against 8.0 s), so a sweep
#: predicted to save 5 s saves about 1.5-2 s net of the start (principled, just below, stays
#: here: 12.0 s).
AUTO_MIN_SECONDS = 5.0
#: Dask configuration an embedded cluster's workers start with.  Dask's nanny sets
#: ``MALLOC_TRIM_THRESHOLD_=65536`` in every worker's environment
#: (``distributed.nanny.pre-spawn-environ``, distributed.yaml), and glibc then stops raising
#: its mmap threshold (mallopt(3): setting M_TRIM_THRESHOLD disables the dynamic threshold),
#: so each numpy array or Dr.Jit buffer of 128 KiB or more is a fresh mmap and munmap: a
#: validate worker took 500,000 page faults in 4 s, 11 s of system time over a roughplastic
#: ``--quick`` sweep on 2 workers, which ran 19.0 s against 15.2-17.4 s serial; unset (None,
#: which the nanny leaves out) 13.5-14.2 s.  The others (OMP, MKL and OpenBLAS at one
#: thread: one process per core) stay.
WORKER_ENVIRON = {"distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None}
#: The variant jobs run in unless a Runner is told otherwise.
DEFAULT_VARIANT = "llvm_ad_rgb"
_resolved: dict[str, str] = {}          # per process: asked-for variant -> the one set
_ADDRESS = re.compile(r"^(tcp|tls|inproc|ucx|ws|wss)://[^\s/:]+(:\d+)?$")


@dataclass(frozen=True)
class Job:
    """One independent piece of work: ``fn(*args)``, ``fn`` a module-level function.

    ``key`` names the job (e.g. the CSV row it fills); results are returned in job order.
    """

    fn: Callable[..., Any]
    args: tuple = ()
    key: Hashable = None


@dataclass
class JobTiming:
    """Seconds a job took inside its worker (``seconds``), and from the start of its batch to
    its result arriving here (``total``)."""

    key: Hashable
    seconds: float
    total: float


def call_job(fn: Callable[..., Any], args: tuple, variant: str) -> tuple[Any, float]:
    """Run one job where it landed: (its result, the wall seconds it took there).

    Sets ``variant`` (and registers phonglab's plugins) when the process is in another one:
    a job may have switched it (the bench's variant comparison), and in a fresh process
    without the worker plugin it is not set yet.
    """
    import mitsuba as mi  # lazy: `phonglab --help` imports this module (for its options)

    if mi.variant() != _resolved.get(variant, variant):
        # register() returns the variant it could set (a fallback, with its warning, once).
        _resolved[variant] = register(variant)
    t0 = time.perf_counter()
    result = fn(*args)
    return result, time.perf_counter() - t0


def check_sendable(job: Job) -> None:
    """One sentence unless ``job`` can be pickled for a worker as Dask pickles it."""
    import cloudpickle  # lazy: a dependency of distributed, needed only where Dask runs

    try:
        cloudpickle.dumps((job.fn, job.args))
    except Exception as exc:
        raise PhonglabError(f"job {job.key!r} cannot be sent to a worker ({type(exc).__name__}: "
                            f"{exc}); pass what it needs as plain values (a scene's path or "
                            f"dict, not a loaded mi.Scene) and load it inside the job") from None


def check_local_workers(workers: int, cores: int | None = None,
                        memory: int | None = None) -> None:
    """One sentence unless ``workers`` local processes fit this machine: at most
    :data:`WORKERS_PER_CORE` per core, and :data:`WORKER_BYTES` each within the memory this
    process may allocate (checked before any process starts)."""
    cores = cores or os.cpu_count() or 1
    if workers > WORKERS_PER_CORE * cores:
        raise PhonglabError(f"--workers {workers} starts more than {WORKERS_PER_CORE} processes "
                            f"per core on this {cores}-core machine; give at most "
                            f"{WORKERS_PER_CORE * cores} (--workers {cores} uses every core), or "
                            f"spread them over machines with --scheduler")
    require_memory(workers * WORKER_BYTES, f"--workers {workers}",
                   lambda have: f"give at most {max(1, have // WORKER_BYTES)}",
                   why=f" ({WORKER_BYTES >> 20} MiB per worker process)", have=memory)


def check_address(address: str) -> str:
    """``address`` when it looks like a Dask scheduler address, else one sentence."""
    if not _ADDRESS.match(address or ""):
        raise PhonglabError(f"--scheduler {address!r} is not a Dask scheduler address; give "
                            f"tcp://HOST:PORT as printed by `dask scheduler`")
    return address


class CoreMeter:
    """``with CoreMeter() as m: ...``: ``m.free`` is how many cores the rest of the machine
    left idle during the block -- the cores less the busy time of every other process (the
    machine's busy CPU time less this process's, Dr.Jit's threads included) over the wall
    time --, ``m.used`` how many this process kept busy on average (its CPU time over the
    wall time: Dr.Jit's kernel threads run beside the Python thread), and ``m.seconds`` the
    block's wall time."""

    def __enter__(self) -> "CoreMeter":
        import psutil  # lazy: a dependency of distributed, read only by an automatic runner

        self._psutil = psutil
        self._process = psutil.Process()
        self._t0 = time.perf_counter()
        self._busy0 = self._busy()
        self._own0 = self._own()
        return self

    def _busy(self) -> float:
        t = self._psutil.cpu_times()
        return sum(t) - t.idle - getattr(t, "iowait", 0.0)

    def _own(self) -> float:
        t = self._process.cpu_times()
        return t.user + t.system

    def __exit__(self, *exc) -> None:
        self.seconds = time.perf_counter() - self._t0
        own = self._own() - self._own0
        others = (self._busy() - self._busy0) - own
        cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (
            os.cpu_count() or 1)
        wall = max(self.seconds, 1e-9)
        self.free = max(0, cores - round(max(0.0, others) / wall))
        self.used = own / wall


def auto_workers(jobs: int, meter: CoreMeter, noun: str = "jobs",
                 memory: int | None = None, kernel_share: float = 0.0,
                 job_seconds: float | None = None) -> dict:
    """How an automatic runner runs ``jobs`` remaining jobs after a first one measured by
    ``meter`` (each predicted to take ``job_seconds``, by default as long as the first): on
    n = min(jobs, free cores, the worker processes ``memory`` holds at :data:`WORKER_BYTES`
    each; default :func:`~phonglab.runtime.available_memory`) worker processes when n ≥ 2
    and the time they are predicted to save is at least :data:`AUTO_MIN_SECONDS`, else 1
    (here); with the ``reason`` in words, ``free_cores``, ``used_cores``, ``first_seconds``,
    ``kernel_share`` and ``predicted_saving_s``.

    The prediction.  What more processes parallelize is the time outside Dr.Jit's kernels
    (Python, numpy, tracing), not the kernels, which Dr.Jit already runs on every core; and
    n worker processes each keep one free core busy with their Python thread -- their
    kernel threads run in the background (:func:`phonglab.runtime.background_kernel_threads`),
    on cores nothing else wants -- so they take the jobs in ⌈jobs / n⌉ rounds, g = jobs /
    ⌈jobs / n⌉ times as fast as one (3 points on 2 processes: 2 rounds, 1.5; n is then the
    fewest processes those rounds need: 10 jobs on 8 free cores, 2 rounds of 5).  Of the
    serial remainder R = jobs · job_seconds they save R · (1 − ``kernel_share``) · (1 − 1/g),
    ``kernel_share`` the first job's share of kernel execution (its Dr.Jit kernel history).
    An upper bound: a worker also rebuilds what the serial process keeps across jobs (caches,
    traced kernels) and the cluster takes 1-3 s to start (:data:`AUTO_MIN_SECONDS` says by how
    much).  ``used``, the cores the first job kept busy here (its CPU time over its wall
    time, Dr.Jit's spinning thread included), is reported, no longer a divisor: until
    2026-12-07 the workers' spin took the other worker's core and g was min(n, free / used)
    (1.38 for a validate process's 1.45 cores), and the sweeps it spread gained less
    (roughplastic 98.2 -> 81.2 s on 2 processes then, 68.9 s with the workers' kernel threads
    in the background; principled 127.7 -> 110.1 -> 85.2 s).  ``path`` (kernel share 0.95)
    took 34-36 s here and 36-40 s on 2: predicted 1 s, it stays here."""
    first = meter.seconds if job_seconds is None else job_seconds
    serial, free, used = jobs * first, meter.free, meter.used
    have = available_memory() if memory is None else memory
    held = jobs if have is None else int(have // WORKER_BYTES)
    n = max(1, min(free, held, jobs))
    rounds = -(-max(jobs, 1) // n)              # the jobs as n processes take them
    n = -(-max(jobs, 1) // rounds)              # as few processes as those rounds need
    g = max(jobs, 1) / rounds
    saving = serial * (1.0 - min(1.0, max(0.0, kernel_share))) * (1.0 - 1.0 / g)
    if jobs < 2:
        n, reason = 1, f"one of the {noun} left"
    elif free < 2:
        n, reason = 1, (f"{jobs} {noun} predicted to take {serial:.0f} s here, but {free} "
                        f"{'core is' if free == 1 else 'cores are'} free: no room for a "
                        f"second process")
    elif held < 2:
        n, reason = 1, (f"{jobs} {noun} predicted to take {serial:.0f} s here, but the memory "
                        f"available holds {held} worker process{'es' if held != 1 else ''} "
                        f"of {WORKER_BYTES >> 20} MiB")
    elif saving < AUTO_MIN_SECONDS:
        reason = (f"{jobs} {noun} predicted to take {serial:.0f} s here ({kernel_share:.0%} "
                  f"in Dr.Jit's kernels, {used:.1f} cores busy): {n} processes on {free} free "
                  f"cores would save at most {saving:.1f} s, below the {AUTO_MIN_SECONDS:g} s "
                  f"a cluster's start pays for")
        n = 1
    else:
        reason = (f"{jobs} {noun} predicted to take {serial:.0f} s here ({kernel_share:.0%} "
                  f"in Dr.Jit's kernels, {used:.1f} cores busy), {free} cores free: {n} "
                  f"worker processes, predicted to save at most {saving:.0f} s")
    return {"workers": n, "reason": reason, "free_cores": free,
            "used_cores": round(used, 2), "first_seconds": round(meter.seconds, 3),
            "job_seconds": round(first, 3),
            "kernel_share": round(kernel_share, 3), "predicted_saving_s": round(saving, 1)}


@dataclass
class Runner:
    """Where jobs run: serially, on a LocalCluster of ``workers`` processes, or on ``scheduler``.

    Use as a context manager (the cluster starts on entry and is shut down on exit).
    ``auto``: serial, but a caller that measures its first job asks :func:`auto_workers`
    where the rest run (the module docstring's automatic runner).
    """

    workers: int = 1
    scheduler: str | None = None
    variant: str = DEFAULT_VARIANT
    progress: bool = True
    retries: int = RETRIES
    auto: bool = False
    timings: list[JobTiming] = field(default_factory=list)
    _client: Any = field(default=None, repr=False)
    _cluster: Any = field(default=None, repr=False)

    def __post_init__(self):
        if self.auto and (int(self.workers) != 1 or self.scheduler is not None):
            raise ValueError("an automatic Runner starts serial: no workers or scheduler")
        if int(self.workers) < 1:
            raise PhonglabError(f"--workers must be at least 1, got {self.workers}")
        if self.scheduler is None and int(self.workers) > 1:
            check_local_workers(int(self.workers))
        if self.scheduler is not None:
            check_address(self.scheduler)

    @property
    def serial(self) -> bool:
        return self.scheduler is None and int(self.workers) == 1

    @property
    def where(self) -> str:
        """Words for the record of a run: 'serial', 'LocalCluster(2)', 'tcp://...'."""
        if self.serial:
            return "serial"
        return self.scheduler or f"LocalCluster({self.workers} processes)"

    def __enter__(self) -> "Runner":
        if not self.serial:
            self._client, self._cluster = _connect(self.workers, self.scheduler, self.variant)
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        client, cluster, self._client, self._cluster = self._client, self._cluster, None, None
        if client is not None:
            client.close()
        if cluster is not None:
            cluster.close()

    def run(self, jobs: Sequence[Job], on_result: Callable[[Job, Any], None] | None = None,
            desc: str = "jobs") -> list[Any]:
        """Results of ``jobs`` in job order; ``on_result(job, result)`` as each one finishes."""
        jobs = list(jobs)
        results: list[Any] = [None] * len(jobs)
        bar = tqdm(total=len(jobs), desc=desc, unit="job", disable=not self.progress,
                   leave=False, dynamic_ncols=True)
        try:
            for i, (result, seconds, total) in self._stream(jobs):
                results[i] = result
                self.timings.append(JobTiming(jobs[i].key, seconds, total))
                if on_result is not None:
                    on_result(jobs[i], result)
                bar.update()
        finally:
            bar.close()
        return results

    def _stream(self, jobs: list[Job]) -> Iterator[tuple[int, tuple[Any, float, float]]]:
        """(index, (result, seconds in the job, seconds end to end)) in finishing order."""
        if self._client is None:
            if not self.serial:
                raise RuntimeError("Runner.run outside its `with` block")
            for i, job in enumerate(jobs):
                t0 = time.perf_counter()
                result, seconds = call_job(job.fn, job.args, self.variant)
                yield i, (result, seconds, time.perf_counter() - t0)
            return
        from distributed import as_completed  # lazy: only a distributed run needs Dask

        for job in jobs:          # every job can reach a worker, or none is sent
            check_sendable(job)
        t0 = time.perf_counter()
        futures = [self._client.submit(call_job, job.fn, job.args, self.variant, pure=False,
                                       retries=self.retries) for job in jobs]
        index = {future.key: i for i, future in enumerate(futures)}
        for future in as_completed(futures):
            result, seconds = future.result()
            yield index[future.key], (result, seconds, time.perf_counter() - t0)
            future.release()


def _connect(workers: int, scheduler: str | None, variant: str) -> tuple[Any, Any]:
    """(Client, LocalCluster or None), every worker prepared by the phonglab worker plugin."""
    import dask  # lazy, as distributed
    from distributed import Client, LocalCluster  # lazy: Dask costs ~1 s to import

    from .worker import PhonglabWorker  # imports distributed

    cluster = None
    if scheduler is None:
        # Ctrl-C reaches every process of the terminal's group: the embedded workers ignore it
        # (inherited here, and set again by the plugin in a worker a nanny restarts), so only
        # this process handles it and shuts the cluster down, without a traceback per worker.
        previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
        try:
            with dask.config.set(WORKER_ENVIRON):
                cluster = LocalCluster(n_workers=int(workers), threads_per_worker=1,
                                       processes=True, dashboard_address=":0",
                                       silence_logs=logging.CRITICAL)
        finally:
            signal.signal(signal.SIGINT, previous)
        threads = max(MIN_KERNEL_THREADS, (os.cpu_count() or 1) // int(workers))
        client = Client(cluster)
    else:
        threads = None
        try:
            client = Client(scheduler, timeout=CONNECT_TIMEOUT)
        except (OSError, TimeoutError) as exc:
            raise PhonglabError(f"cannot reach the Dask scheduler at {scheduler} within "
                                f"{CONNECT_TIMEOUT:g} s ({type(exc).__name__}); start one with "
                                f"`dask scheduler` (docs/cluster.md) or drop --scheduler to run "
                                f"here") from None
    try:
        if scheduler is not None:
            _wait_for_a_worker(client, scheduler)
        client.register_plugin(PhonglabWorker(variant, threads=threads,
                                              ignore_sigint=scheduler is None))
    except BaseException:
        client.close()
        if cluster is not None:
            cluster.close()
        raise
    return client, cluster


def _wait_for_a_worker(client, scheduler: str) -> None:
    """Jobs sent to a scheduler without workers would wait forever: one sentence instead."""
    try:
        client.wait_for_workers(1, timeout=CONNECT_TIMEOUT)
    except TimeoutError:
        raise PhonglabError(f"the Dask scheduler at {scheduler} has no workers after "
                            f"{CONNECT_TIMEOUT:g} s; start one on each machine with `dask worker "
                            f"{scheduler} --nthreads 1` (docs/cluster.md)") from None


def add_arguments(parser, auto: str | None = None) -> None:
    """``--workers`` and ``--scheduler`` on a subcommand's parser (bench, plan, validate).
    ``auto``: the words of an automatic default (``--workers`` absent: ``None``, an automatic
    :class:`Runner`), else the default is 1, serially here."""
    group = parser.add_mutually_exclusive_group()
    group.add_argument("--workers", type=int, default=None if auto else 1, metavar="N",
                       help="run the independent jobs on N local worker processes (a Dask "
                            "LocalCluster, one thread each; "
                            + (f"default: {auto})" if auto else "default 1: serially here)"))
    group.add_argument("--scheduler", default=None, metavar="tcp://HOST:PORT",
                       help="run the jobs on a running Dask cluster (docs/cluster.md); results "
                            "are identical to a serial run")


def runner_from_args(args, variant: str = DEFAULT_VARIANT) -> Runner:
    """The :class:`Runner` of ``--workers``/``--scheduler`` (checked before anything runs)."""
    auto = args.workers is None and args.scheduler is None
    return Runner(workers=1 if args.workers is None else args.workers,
                  scheduler=args.scheduler, variant=variant, auto=auto,
                  progress=not getattr(args, "no_progress", False))
