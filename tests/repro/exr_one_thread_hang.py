"""Mitsuba 3.9.1: with Dr.Jit's thread count at 1, reading or writing an OpenEXR file hangs.

src/core/bitmap.cpp (v3.9.1) hands OpenEXR's tasks to nanothread through ``EXRThreadPool``
(lines 955-978).  ``numThreads()`` is ``std::max(1, (int) pool_size())`` (line 958), so
OpenEXR always takes its threaded path: ``OutputFile::writePixels`` / ``InputFile::readPixels``
queue their line-buffer tasks and block on an IlmThread semaphore until each task reports.
``addTask`` (line 965) runs a task in the caller only when ``pool_size() == 0`` (line 972),
else ``task_release(t)`` leaves it to the pool's worker threads.  Since drjit-core's
``jit_llvm_set_thread_count(size)`` spawns ``size - 1`` workers (the calling thread "counts as
one of the threads"; include/drjit-core/jit.h) and nanothread's ``pool_size()`` counts the
caller too, ``dr.set_thread_count(1)`` leaves a pool with no worker at all while
``pool_size()`` reads 1: the task is queued for nobody and the caller waits on the semaphore
forever (a debugger shows the main thread in ``IlmThread::Semaphore::wait`` under
``Imf::OutputFile::writePixels`` and no nanothread worker).  At 2 threads both calls return.
What it costs: a process with one Dr.Jit thread (a worker process given ``cores // workers``
threads on a 2-core machine; any process on one core, where Dr.Jit's default is 1) hangs on
the first EXR texture it loads or image it writes.  phonglab gives every process it sets up
at least 2 threads (phonglab.runtime.MIN_KERNEL_THREADS, in ``phonglab.register``).

The check runs each case in a child process with a time limit (the hang never returns).

Run: python tests/repro/exr_one_thread_hang.py  -> exit 1 while the hang is present.
"""
import subprocess
import sys
import tempfile
import textwrap
from pathlib import Path

#: Python source run in a child: set the thread count, write and read an 8x8 EXR.
CHILD = textwrap.dedent('''
    import sys
    try:
        import phonglab.runtime
        phonglab.runtime.configure()
    except ImportError:
        pass
    import drjit as dr
    import mitsuba as mi
    import numpy as np
    mi.set_variant("llvm_ad_rgb")
    dr.set_thread_count(int(sys.argv[1]))
    mi.Bitmap(np.full((8, 8, 3), 0.4, dtype=np.float32)).write(sys.argv[2])
    print("written", flush=True)
    mi.Bitmap(sys.argv[2])
    print("read", flush=True)
''')
LIMIT = 20.0


def run(threads: int, path: Path) -> str:
    """What the child got through within LIMIT seconds: 'read', 'written' or 'nothing'."""
    try:
        done = subprocess.run([sys.executable, "-c", CHILD, str(threads), str(path)],
                              capture_output=True, text=True, timeout=LIMIT)
    except subprocess.TimeoutExpired as exc:
        out = exc.stdout.decode() if isinstance(exc.stdout, bytes) else (exc.stdout or "")
        return ("written" if "written" in out else "nothing") + f" (hung, killed after {LIMIT:g} s)"
    if done.returncode != 0:
        raise SystemExit(f"the child failed at {threads} threads: {done.stderr[-500:]}")
    return "read"


with tempfile.TemporaryDirectory() as tmp:
    results = {n: run(n, Path(tmp) / f"t{n}.exr") for n in (2, 1)}
for n, got in results.items():
    print(f"dr.set_thread_count({n}): EXR write + read -> {got}")
sys.exit(1 if results[1] != "read" and results[2] == "read" else 0)
