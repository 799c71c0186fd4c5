"""A run releases the GIL (other threads run meanwhile), and Ctrl-C (SIGINT)
stops it within a fraction of a second with KeyboardInterrupt, the samples so
far attached as `e.partial`."""

import os
import signal
import threading
import time

import pytest

import mstar
from mstar import planar


def chain(n: int) -> mstar.Model:
    """n slender 1 m bars of 1 kg hinged end to end, the first to the ground,
    released horizontally."""
    b = planar.Builder()
    previous = planar.ground(0.0, 0.0)
    for i in range(n):
        bar = b.rigid_body(f"bar{i}", mass=1.0, inertia=1 / 12, pose=(i + 0.5, 0.0, 0.0))
        b.revolute(f"hinge{i}", previous, bar.at(-0.5, 0.0))
        previous = bar.at(0.5, 0.0)
    return b.build()


@pytest.mark.skipif(not hasattr(signal, "SIGINT"), reason="needs SIGINT")
def test_ctrl_c_stops_a_long_run_and_keeps_its_samples():
    model = chain(50)
    counted = 0
    done = threading.Event()

    def count() -> None:
        nonlocal counted
        while not done.is_set():
            counted += 1
            time.sleep(0.001)

    def interrupt() -> None:
        time.sleep(0.5)
        os.kill(os.getpid(), signal.SIGINT)

    threads = [threading.Thread(target=count), threading.Thread(target=interrupt)]
    for t in threads:
        t.start()
    start = time.perf_counter()
    try:
        with pytest.raises(KeyboardInterrupt) as e:
            model.run(t_end=1e4, h=1e-3)  # hours of stepping
    finally:
        done.set()
        for t in threads:
            t.join()
    elapsed = time.perf_counter() - start
    assert elapsed < 3.0, elapsed
    # The GIL was released: the counter ran during the run.
    assert counted > 50, counted
    partial = e.value.partial
    assert isinstance(partial, mstar.Result)
    assert len(partial) > 10
    assert 0.0 < partial.t[-1] < 1e4
    assert partial.u.shape == (len(partial), 150)
    assert partial.stats.steps == len(partial) - 1
    # What was kept is the start of the uninterrupted run, bit for bit (but
    # for the last two steps of a run to that t_end, which share what remains
    # to land on it).
    short = model.run(t_end=float(partial.t[-1]) + 0.5, h=1e-3)
    k = len(partial)
    assert (short.u[:k] == partial.u).all() and (short.lam[:k] == partial.lam).all()
