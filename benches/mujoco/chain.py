#!/usr/bin/env python3
"""MuJoCo counterpart of mstar's N-link bar-chain benchmark.

The model is the one of `mstar chain --kind bars` (crates/model/src/planar/chains.rs):

* N uniform slender bars, each m = 1 kg, l = 1 m, J = m l^2 / 12 about the
  centre of mass for rotation in the x-y plane;
* bar k (k = 1..N) lies along +x from (k - 1, 0) to (k, 0) at t = 0, at rest;
* a revolute joint (MuJoCo hinge about z) connects the left end of bar 1 to
  the ground at the origin, and the right end of bar k to the left end of
  bar k+1;
* gravity -9.81 in y.

MuJoCo works in minimal coordinates: the N hinge angles, a kinematic tree
N bodies deep whose joint-space mass matrix is dense (every hinge carries all
bars outboard of it).  The chain is built with the MjSpec API (an MJCF file
would nest N <body> elements).  No geoms (so no collision detection), no
actuators, no constraints; mass and inertia are given explicitly.  The other
two principal moments of a bar (about its own axis, 1e-6 kg m^2, and about
y, J) only have to satisfy MuJoCo's inertia checks: a hinge about z never
moves them.

Only mj_step is timed, over all steps in one call (mj_step(m, d, nstep)):
the model is compiled and mj_forward has run before the clock starts.

Usage:
    python3 benches/mujoco/chain.py                    # N = 10, 100, 1000; implicit and implicitfast
    python3 benches/mujoco/chain.py --sizes 10 100 --repeats 1
    python3 benches/mujoco/chain.py --tip              # N = 10 tip at t = 1 s for every integrator
"""

import argparse
import os
import sys
import time

import mujoco

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from quiet_machine import end_time_for, wait_for_quiet_machine  # noqa: E402  (benches/)

parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
parser.add_argument("--sizes", type=int, nargs="+", default=[10, 100, 1000],
                    help="chain lengths N to time (default: 10 100 1000)")
parser.add_argument("--integrators", nargs="+", default=["implicit", "implicitfast"],
                    choices=["euler", "rk4", "implicit", "implicitfast"],
                    help="MuJoCo integrators to time (default: implicit implicitfast)")
parser.add_argument("--repeats", type=int, default=3,
                    help="timed runs per size; the minimum is reported (default 3)")
parser.add_argument("--h", type=float, default=1e-3, help="step size, s (default 1e-3)")
parser.add_argument("--tip", action="store_true",
                    help="only print the N = 10 tip position at t = 1 s for each integrator")
parser.add_argument("--max-load", type=float, default=1.2,
                    help="wait while the 1-minute load average is above this (default 1.2)")
parser.add_argument("--max-wait", type=float, default=300.0,
                    help="give up waiting for a quiet machine after this many s (default 300)")
args = parser.parse_args()

GRAVITY = -9.81
MASS = 1.0
LENGTH = 1.0
INERTIA = MASS * LENGTH**2 / 12.0
INTEGRATORS = {
    "euler": mujoco.mjtIntegrator.mjINT_EULER,
    "rk4": mujoco.mjtIntegrator.mjINT_RK4,
    "implicit": mujoco.mjtIntegrator.mjINT_IMPLICIT,
    "implicitfast": mujoco.mjtIntegrator.mjINT_IMPLICITFAST,
}


def build_chain(n, integrator):
    """Compile an n-bar chain; returns (model, data)."""
    spec = mujoco.MjSpec()
    spec.option.gravity = [0.0, GRAVITY, 0.0]
    spec.option.timestep = args.h
    spec.option.integrator = INTEGRATORS[integrator]
    # The implicit integrators work on dense nv x nv matrices in MuJoCo's
    # arena: room for forty of them (the default arena is too small at N = 1000).
    spec.memory = max(spec.memory, 40 * 8 * n * n + (64 << 20))
    parent = spec.worldbody
    for k in range(1, n + 1):
        # Body frame at the bar's left end (the hinge), x along the bar.
        body = parent.add_body(name="link%d" % k, pos=[0.0 if k == 1 else LENGTH, 0.0, 0.0])
        body.explicitinertial = True
        body.mass = MASS
        body.ipos = [0.5 * LENGTH, 0.0, 0.0]
        body.inertia = [1e-6, INERTIA, INERTIA]
        body.add_joint(type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0.0, 0.0, 1.0])
        parent = body
    model = spec.compile()
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    return model, data


def tip(data, n):
    """(x, y) of the centre of bar n."""
    p = data.xipos[n]
    return float(p[0]), float(p[1])


def solve_once(n, integrator, end_time):
    model, data = build_chain(n, integrator)
    steps = int(round(end_time / args.h))
    t0 = time.perf_counter()
    mujoco.mj_step(model, data, nstep=steps)
    wall = time.perf_counter() - t0
    return {"wall": wall, "steps": steps, "t": data.time, "tip": tip(data, n)}


def main():
    print("mujoco %s; h = %g; one thread" % (mujoco.__version__, args.h), flush=True)
    for integrator in (INTEGRATORS if args.tip else args.integrators):
        r = solve_once(10, integrator, 1.0)
        print("N = 10 tip (centre of bar 10) at t = %.6g s, %s: x = %.9f m, y = %.9f m"
              % (r["t"], integrator, r["tip"][0], r["tip"][1]), flush=True)
    if args.tip:
        return
    rows = []
    for integrator in args.integrators:
        for n in args.sizes:
            best = None
            for rep in range(args.repeats):
                load = wait_for_quiet_machine(args.max_load, args.max_wait)
                r = solve_once(n, integrator, end_time_for(n))
                print("  %s N = %5d run %d: %.4f s for %d steps (load %.2f)"
                      % (integrator, n, rep + 1, r["wall"], r["steps"], load), flush=True)
                if best is None or r["wall"] < best["wall"]:
                    best = r
            rows.append((integrator, n, best))
    print()
    header = "%13s %7s %7s %12s %14s" % ("integrator", "N", "steps", "us/step", "us/body/step")
    print(header)
    print("-" * len(header))
    for integrator, n, r in rows:
        us = r["wall"] / r["steps"] * 1e6
        print("%13s %7d %7d %12.2f %14.4f" % (integrator, n, r["steps"], us, us / n))


if __name__ == "__main__":
    main()
