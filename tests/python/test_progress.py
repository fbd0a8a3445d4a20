"""Progress, interruption and threads: progress= sees every stage; an exception from it, or
Ctrl-C (SIGINT), stops the run with that exception; the GIL is released while dsreg works."""

import os
import signal
import sys
import threading
import time

import numpy as np
import pytest

import dsreg
from helpers import ellipsoid

MASK = ellipsoid((40, 36, 34), (16.2, 13.1, 12.4))


def test_progress_sees_every_stage():
    events = []
    dsreg.regularize(MASK, progress=lambda stage, fraction: events.append((stage, fraction)))
    stages = ["read", "surface", "normals", "regularize", "validity"]
    assert events == [(stage, fraction) for stage in stages for fraction in (0.0, 1.0)]
    events.clear()
    dsreg.regularize(None, shape="sphere1", h=0.2, normals="at", progress=lambda s, f: events.append((s, f)))
    # stage starts and ends (the repair inside "validity" reports rounds of unknown fraction, -1)
    ends = [stage for stage, fraction in events if fraction in (0.0, 1.0)]
    assert ends[::2] == ["digitize", "surface", "normals", "at", "regularize", "validity"]
    assert ends[1::2] == ends[::2]


class Stop(Exception):
    pass


@pytest.mark.parametrize("exception", [Stop, KeyboardInterrupt])
def test_an_exception_from_progress_stops_the_run(exception):
    seen = []

    def progress(stage, fraction):
        seen.append(stage)
        if stage == "normals":
            raise exception("stop here")

    with pytest.raises(exception, match="stop here"):
        dsreg.regularize(MASK, progress=progress)
    assert seen == ["read", "read", "surface", "surface", "normals"]  # nothing after the exception
    assert dsreg.regularize(MASK).report["counts"]["surfels"] > 0  # and the module still works


@pytest.mark.skipif(threading.current_thread() is not threading.main_thread(), reason="signals go to the main thread")
def test_sigint_raises_keyboard_interrupt():
    """SIGINT while dsreg works: KeyboardInterrupt at the next stage boundary, before the run ends.
    The progress function is a C method (dict.__setitem__), which runs no Python code: Python
    itself cannot notice the signal until the call returns, so only dsreg's own check can stop
    the run early."""
    events = {}
    timer = threading.Timer(0.05, os.kill, (os.getpid(), signal.SIGINT))
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            dsreg.regularize(None, shape="goursat", h=0.15, progress=events.__setitem__)
    finally:
        timer.cancel()
    assert events.get("validity") != 1.0, events  # the last stage never ended


def test_the_gil_is_released():
    """A Python thread that only needs the GIL (it sleeps in between) advances while regularize
    runs; with the switch interval raised to 60 s, it could not if regularize held the GIL."""
    ticks = [0]
    running = threading.Event()
    stop = threading.Event()

    def count():
        running.set()
        while not stop.is_set():
            ticks[0] += 1
            time.sleep(0.001)

    thread = threading.Thread(target=count)
    interval = sys.getswitchinterval()
    sys.setswitchinterval(60)
    try:
        thread.start()
        running.wait()
        inside = {}

        def progress(stage, fraction):
            inside[(stage, fraction)] = ticks[0]

        dsreg.regularize(None, shape="goursat", h=0.25, progress=progress)
    finally:
        stop.set()
        thread.join()
        sys.setswitchinterval(interval)
    # Ticks counted between the start and the end of the stages, while the main thread was in C++.
    assert inside[("regularize", 1.0)] - inside[("digitize", 0.0)] >= 2, inside


def test_regularize_in_threads():
    """Two threads regularize at once (each releases the GIL): both get the single-threaded result."""
    expected = dsreg.regularize(MASK).vertices
    results = [None, None]

    def run(n):
        results[n] = dsreg.regularize(MASK).vertices

    threads = [threading.Thread(target=run, args=(n,)) for n in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for result in results:
        np.testing.assert_allclose(result, expected, rtol=0, atol=1e-9)


@pytest.mark.parametrize("policy, shown", [(None, "PASSIVE"), ("active", "ACTIVE")])
def test_openmp_waits_passively_unless_told_otherwise(policy, shown):
    """import dsreg loads OpenMP with OMP_WAIT_POLICY=passive, as the dsreg command runs, unless
    the user chose a policy; the variable is not left in the environment (OpenMP's own
    OMP_DISPLAY_ENV shows the policy it runs with)."""
    import subprocess

    env = {k: v for k, v in os.environ.items() if k != "OMP_WAIT_POLICY"}
    env["OMP_DISPLAY_ENV"] = "TRUE"
    if policy:
        env["OMP_WAIT_POLICY"] = policy
    code = "import os, dsreg; print(os.environ.get('OMP_WAIT_POLICY'))"
    result = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    assert f"OMP_WAIT_POLICY = '{shown}'" in result.stderr
    assert result.stdout.strip() == str(policy)
