"""Ctrl-C anywhere: exit 130, one line, the files already written complete; Mitsuba's per-render
SIGINT handler never runs (phonglab.runtime.interrupts_routed)."""

from __future__ import annotations

import importlib.util
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from phonglab import cli
from phonglab.engine import exr


# --- Ctrl-C anywhere: exit 130, one line, the previous files intact -----------------------------

INTERRUPT_MESSAGE = "phonglab: interrupted; files already written are complete."


@pytest.mark.slow
@pytest.mark.parametrize("delay", [0.15, 0.2, 0.25, 0.3, 0.4, 0.5, 0.6, 0.7, 0.9, 1.5])
def test_ctrl_c_at_any_point_of_a_render_is_one_line(tmp_path, delay):
    """SIGINT at points from start-up to mid-render.  Not inside the first ~0.1 s (0.08 s on
    a quiet machine, so the first point is twice that): there the interpreter is still
    importing the console script's `phonglab.cli`, before any phonglab code can catch it,
    and Python prints its own traceback.  Anywhere later it ends as the one interrupt line
    (exit 130, the files intact), never as `SystemError: <built-in function __import__>
    returned a result with an exception set` (during the variant's set-up), 'could not load
    the scene: KeyboardInterrupt' (inside a plugin's constructor), a traceback (during the
    subcommand imports) or an abort (exit -6, an error handler importing Dr.Jit or the
    interpreter finalising a half-imported Dr.Jit: "PyThreadState_Get ... finalizing")."""
    out = tmp_path / "x.exr"
    assert cli.main(["render", "gray_direct", "--spp", "4", "-o", str(out)]) == 0
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
    exe = Path(sys.executable).with_name("phonglab")
    proc = subprocess.Popen([str(exe), "render", "cornell_phong", "--spp", "256", "-o", str(out)],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                            start_new_session=True)
    time.sleep(delay)
    os.killpg(proc.pid, signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    lines = [ln.strip() for ln in err.replace("\r", "\n").splitlines() if ln.strip()
             and not ln.strip().startswith("rendering")]
    if proc.returncode == 0:                 # it finished first: a complete new set
        assert exr.read(out)[1]["scene"].endswith("cornell_phong.xml")
        return
    assert proc.returncode == 130 and lines == [INTERRUPT_MESSAGE], (proc.returncode, err[-2000:])
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == before


def _load_repro(name: str):
    spec = importlib.util.spec_from_file_location(name, Path(__file__).parent / "repro" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


#: Seconds after which the child prints every thread's Python stack and exits 1 (a hang is
#: then a failing assertion showing where it waits, not a 120-s timeout without a trace).
HANG_DUMP_S = 60

CTRL_C_INSIDE_A_RENDER = _load_repro("sigint_handler_logs").FIRE_DURING_RENDER + """
import faulthandler, sys
faulthandler.dump_traceback_later(HANG_DUMP_S, exit=True)
# As in the console script, no thread exists before cli.main routes SIGINT: Dr.Jit's own
# threads, started by this import, must not take it either.
signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
import mitsuba as mi
signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})
from phonglab import cli
real = mi.render
def render(*args, **kwargs):            # Ctrl-C while Mitsuba's own C handler is installed
    if not getattr(render, "fired", False):
        render.fired = True
        fire_during_render()
    integrator = kwargs.get("integrator") or args[0].integrator()
    try:
        return real(*args, **kwargs)
    finally:                            # Mitsuba's handler cancels the integrator it guards
        stopped, interrupted = integrator.should_stop(), None
        while True:     # phonglab's routed Ctrl-C reaches Python when the render returns: it
            try:        # may land inside this print (seen in fresh clones), so print it whole
                print("cancelled by Mitsuba's handler:", stopped, flush=True)
                break
            except KeyboardInterrupt as exc:
                interrupted = exc
        if interrupted is not None:
            raise interrupted
mi.render = render
sys.exit(cli.main(["render", "cornell_phong", "--spp", "256", "-o", sys.argv[1]]))
""".replace("HANG_DUMP_S", str(HANG_DUMP_S))


def test_ctrl_c_inside_a_render_never_runs_mitsubas_signal_handler(tmp_path):
    """Mitsuba 3.9.1 installs a C SIGINT handler for each render (the lambda passed to
    `signal` at src/render/python/integrator_v.cpp:37) that logs ("Received interrupt
    signal, winding down..", line 38) from inside the handler: not async-signal-safe, so it
    can deadlock (the reproducer shows the Log call, not a hang), and a Ctrl-C in the instant
    before line 37 stores the previous handler kills the process with SIG_DFL (a first
    render).  phonglab takes SIGINT on a thread of its own
    (runtime.interrupts_routed): Mitsuba's handler never runs, the command says one line and
    exits 130.  Without the routing the handler runs and cancels the integrator (checked)."""
    out = tmp_path / "x.exr"
    proc = subprocess.run([sys.executable, "-c", CTRL_C_INSIDE_A_RENDER, str(out)],
                          capture_output=True, text=True, timeout=120,
                          start_new_session=True)
    both = proc.stdout + proc.stderr
    assert "cancelled by Mitsuba's handler: False" in proc.stdout, both[-2000:]
    assert "cancelled by Mitsuba's handler: True" not in proc.stdout, both[-2000:]
    lines = [ln.strip() for ln in proc.stderr.replace("\r", "\n").splitlines()
             if ln.strip() and not ln.strip().startswith("rendering")]
    assert proc.returncode == 130 and lines == [INTERRUPT_MESSAGE], (proc.returncode, both[-2000:])
    assert not out.exists()


@pytest.mark.slow
def test_the_sigint_reproducer_shows_mitsubas_handler():
    """tests/repro/sigint_handler_logs.py exits 1 while Mitsuba 3.9.1's render handler runs
    Log from signal context (the reason for runtime.interrupts_routed)."""
    script = Path(__file__).parent / "repro" / "sigint_handler_logs.py"
    done = subprocess.run([sys.executable, str(script)], capture_output=True, text=True,
                          timeout=300)
    assert done.returncode == 1, done.stdout + done.stderr


def test_routing_restores_the_signal_mask_and_handler():
    """After a command, in-process callers (notebooks, pytest) get Ctrl-C as before."""
    before = signal.pthread_sigmask(signal.SIG_BLOCK, set())
    assert cli.main(["doctor"]) in (0, 1)
    assert signal.pthread_sigmask(signal.SIG_BLOCK, set()) == before
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
    with pytest.raises(KeyboardInterrupt):
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(1)
