#!/usr/bin/env python3
"""Exudyn counterpart of mstar's N-link bar-chain benchmark.

The model is the one of `mstar chain --kind bars` (crates/model/src/planar/chains.rs):

* N uniform slender bars, each m = 1 kg, l = 1 m, J = m l^2 / 12 about the
  centre of mass, moving in the x-y plane;
* bar k (k = 1..N) has its centre at (k - 0.5, 0) and lies along +x at t = 0,
  at rest;
* a revolute joint connects the left end of bar 1 to the ground at the origin,
  and the right end of bar k to the left end of bar k+1;
* gravity -9.81 in y.

In Exudyn this is built from its planar items, which are the cheapest way to
express a planar chain: every bar is a NodeRigidBody2D (coordinates x, y, phi)
with an ObjectRigidBody2D, every joint is an ObjectJointRevolute2D between two
MarkerBodyPosition markers (2 algebraic equations each), and gravity is a
LoadMassProportional on a MarkerBodyMass.  So Exudyn solves the same index-3
DAE as mstar: 3N coordinates, 2N constraints.

Solver: Exudyn's implicit generalized-alpha (index-3, the default variant)
with spectral radius 0.8, fixed step h = 1e-3, relative Newton tolerance
1e-8, modified Newton, sparse LU (Eigen SparseLU) for large N.  Nothing is
written to files, no graphics, no console output from the solver.

Only the stepping is timed: the model is built, assembled and the solver is
initialised (which includes Exudyn's consistent initial accelerations) before
the clock starts; the clock covers MainSolverImplicitSecondOrder.SolveSteps.

Usage:
    python3 benches/exudyn/chain.py                  # table for N = 10 ... 10000 (+100000)
    python3 benches/exudyn/chain.py --fast           # use Exudyn's exudynCPPfast module
    python3 benches/exudyn/chain.py --sizes 10 100 --repeats 1
    python3 benches/exudyn/chain.py --tip            # only the N = 10 tip at t = 1 s
"""

import argparse
import os
import sys

# ---------------------------------------------------------------------------
# Command line.  It is parsed before exudyn is imported because the choice of
# compiled module (regular or "fast", without range checks) has to be made
# before the first import.
# ---------------------------------------------------------------------------
parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
parser.add_argument("--sizes", type=int, nargs="+", default=[10, 100, 1000, 10000],
                    help="chain lengths N to time (default: 10 100 1000 10000; "
                         "100000 is added automatically if N = 10000 takes < --big-limit s)")
parser.add_argument("--repeats", type=int, default=3,
                    help="timed runs per size; the minimum is reported (default 3)")
parser.add_argument("--h", type=float, default=1e-3, help="step size, s (default 1e-3)")
parser.add_argument("--rho", type=float, default=0.8, help="spectral radius rho_inf (default 0.8)")
parser.add_argument("--tol", type=float, default=1e-8, help="Newton relative tolerance (default 1e-8)")
parser.add_argument("--fast", action="store_true",
                    help="load exudynCPPfast (no range checks, AVX2) instead of exudynCPP")
parser.add_argument("--tip", action="store_true",
                    help="only print the N = 10 tip position at t = 1 s and exit")
parser.add_argument("--max-load", type=float, default=1.2,
                    help="wait while the 1-minute load average is above this (default 1.2)")
parser.add_argument("--max-wait", type=float, default=300.0,
                    help="give up waiting for a quiet machine after this many s (default 300)")
parser.add_argument("--phases", action="store_true",
                    help="after the table, one extra (untimed-by-us) run per size with Exudyn's "
                         "internal solver timers on, printing where the time goes "
                         "(timers are compiled out of the --fast module)")
parser.add_argument("--big-limit", type=float, default=30.0,
                    help="run N = 100000 only if N = 10000 needs less than this many s "
                         "per 100 steps (default 30)")
args = parser.parse_args()

if args.fast:
    sys.exudynFast = True  # read by exudyn/__init__.py at import time

import exudyn as exu                       # noqa: E402  (import after the switch above)
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from quiet_machine import end_time_for, wait_for_quiet_machine  # noqa: E402  (benches/)
import exudyn_run  # noqa: E402  (this folder)
from exudyn.itemInterface import (         # noqa: E402
    LoadMassProportional, MarkerBodyMass, MarkerBodyPosition, NodeRigidBody2D,
    ObjectGround, ObjectJointRevolute2D, ObjectRigidBody2D,
)

GRAVITY = -9.81
MASS = 1.0
LENGTH = 1.0
INERTIA = MASS * LENGTH**2 / 12.0

# Above this many bars the sparse LU is used; below it Exudyn's own dense
# solver (EXUdense), which is what Exudyn recommends for small systems.  The
# choice only matters for speed; both give the same solution.
SPARSE_FROM_N = 30


def build_chain(n):
    """Create a SystemContainer with an assembled n-bar chain.

    Returns (SC, mbs, tip_node) where tip_node is the node of bar n, whose
    coordinates are the position of its centre of mass and its angle."""
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()

    # Ground and the hinge point on it (the origin).
    ground = mbs.AddObject(ObjectGround())
    previous_marker = mbs.AddMarker(MarkerBodyPosition(bodyNumber=ground,
                                                       localPosition=[0.0, 0.0, 0.0]))
    node = None
    for k in range(1, n + 1):
        # Node coordinates are (x, y, phi) of the centre of mass; the reference
        # configuration is the horizontal rest position, so the initial
        # displacements and velocities are all zero.
        node = mbs.AddNode(NodeRigidBody2D(referenceCoordinates=[(k - 0.5) * LENGTH, 0.0, 0.0],
                                           initialCoordinates=[0.0, 0.0, 0.0],
                                           initialVelocities=[0.0, 0.0, 0.0]))
        body = mbs.AddObject(ObjectRigidBody2D(nodeNumber=node, mass=MASS, inertia=INERTIA))

        # Gravity, as a load proportional to the body's mass.
        mass_marker = mbs.AddMarker(MarkerBodyMass(bodyNumber=body))
        mbs.AddLoad(LoadMassProportional(markerNumber=mass_marker, loadVector=[0.0, GRAVITY, 0.0]))

        # Joint at the left end of this bar to the previous bar's right end
        # (or to the ground for k = 1).  Marker positions are body-fixed,
        # relative to the centre of mass.
        left = mbs.AddMarker(MarkerBodyPosition(bodyNumber=body, localPosition=[-0.5 * LENGTH, 0.0, 0.0]))
        mbs.AddObject(ObjectJointRevolute2D(markerNumbers=[previous_marker, left]))
        previous_marker = mbs.AddMarker(MarkerBodyPosition(bodyNumber=body,
                                                           localPosition=[0.5 * LENGTH, 0.0, 0.0]))
    mbs.Assemble()
    return SC, mbs, node


def settings_for(n, end_time):
    """Simulation settings (exudyn_run.settings_for) at this script's options."""
    return exudyn_run.settings_for(exu, n, end_time, args.h, args.rho, args.tol, SPARSE_FROM_N)


def tip_position(mbs, node):
    """Current (x, y) of the tip bar's centre of mass."""
    p = mbs.GetNodeOutput(node, exu.OutputVariableType.Position)
    return float(p[0]), float(p[1])


PHASES = exudyn_run.PHASES


def solve_once(n, end_time, phases=False):
    """Build, initialise, then time only SolveSteps.  Returns a dict.

    With phases=True Exudyn's internal per-phase timers are switched on (this
    adds some overhead, so such a run is not used for the table)."""
    SC, mbs, tip_node = build_chain(n)
    s = settings_for(n, end_time)
    out = exudyn_run.timed_solve(exu, mbs, s, n, phases)
    out['tip'] = tip_position(mbs, tip_node)
    solver = out.pop('solver')
    solver.FinalizeSolver(mbs, s)
    del SC, mbs
    return out


def main():
    print("exudyn %s, module %s; h = %g, rho_inf = %g, Newton rel. tol = %g, modified Newton"
          % (exu.__version__, exu._compiledModuleName, args.h, args.rho, args.tol), flush=True)

    # Sanity check: tip of the 10-bar chain at t = 1 s.
    r = solve_once(10, 1.0)
    print("N = 10 tip (centre of bar 10) at t = %.6g s: x = %.9f m, y = %.9f m"
          % (r['t_final'], r['tip'][0], r['tip'][1]), flush=True)
    if args.tip:
        return

    sizes = list(args.sizes)
    rows = []
    i = 0
    while i < len(sizes):
        n = sizes[i]
        t_end = end_time_for(n)
        best = None
        for rep in range(args.repeats):
            load = wait_for_quiet_machine(args.max_load, args.max_wait)
            r = solve_once(n, t_end)
            print("  N = %6d run %d: %.4f s for %d steps (load %.2f)"
                  % (n, rep + 1, r['wall'], r['steps'], load), flush=True)
            if best is None or r['wall'] < best['wall']:
                best = r
        rows.append((n, best))
        # N = 100000 only if N = 10000 is cheap enough (per 100 steps).
        if (n == 10000 and 100000 not in sizes
                and best['wall'] / best['steps'] * 100 < args.big_limit):
            sizes.append(100000)
        i += 1

    print()
    print("exudyn %s (%s), generalized-alpha rho_inf = %g, h = %g, tol = %g, modified Newton"
          % (exu.__version__, exu._compiledModuleName, args.rho, args.h, args.tol))
    header = ("%8s %7s %12s %14s %10s %10s %8s %9s"
              % ("N", "steps", "us/step", "us/body/step", "Newton/st", "Jac/step", "rejected", "solver"))
    print(header)
    print("-" * len(header))
    for n, r in rows:
        us_step = r['wall'] / r['steps'] * 1e6
        solver_name = "sparse" if n >= SPARSE_FROM_N else "dense"
        print("%8d %7d %12.2f %14.4f %10.3f %10.4f %8d %9s"
              % (n, r['steps'], us_step, us_step / n, r['newton'] / r['steps'],
                 r['jacobians'] / r['steps'], r['rejected'], solver_name))

    if args.phases:
        print()
        print("Exudyn internal timers, us per step (one extra run per size, timers on):")
        print("%8s %10s " % ("N", "wall") + " ".join("%15s" % p for p in PHASES))
        for n, _ in rows:
            wait_for_quiet_machine(args.max_load, args.max_wait)
            r = solve_once(n, end_time_for(n), phases=True)
            per = lambda sec: sec / r['steps'] * 1e6
            print("%8d %10.1f " % (n, per(r['wall']))
                  + " ".join("%15.1f" % per(r['phases'][p]) for p in PHASES), flush=True)


if __name__ == '__main__':
    main()
