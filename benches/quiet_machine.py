"""Shared by the side-by-side benchmark scripts (benches/exudyn, benches/mujoco):
wait for a quiet machine before a timed run, and the chain lengths' end times."""

import time


def wait_for_quiet_machine(max_load, max_wait):
    """Sleep, 20 s at a time, while the 1-minute load average is above
    max_load, for at most max_wait s; returns the last load average."""
    waited = 0.0
    while True:
        with open("/proc/loadavg") as f:
            load1 = float(f.read().split()[0])
        if load1 <= max_load:
            return load1
        if waited >= max_wait:
            print("  (load %.2f still above %.2f after %.0f s; running anyway)"
                  % (load1, max_load, waited), flush=True)
            return load1
        print("  (load %.2f > %.2f, waiting 20 s)" % (load1, max_load), flush=True)
        time.sleep(20)
        waited += 20


def end_time_for(n):
    """1 s (1000 steps) for small chains, 0.1 s (100 steps) for N >= 1000."""
    return 1.0 if n < 1000 else 0.1
