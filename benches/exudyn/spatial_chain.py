#!/usr/bin/env python3
"""Exudyn counterpart of mstar's spatial bar-chain benchmark.

The model is mstar's "spatial bar chain":

* N solid cylinders, each m = 1 kg, l = 1 m, radius r = 0.02 m, uniform
  density.  Principal moments about the centre of mass: axial (the bar's own
  axis, global x at t = 0) J_xx = m r^2 / 2, transverse
  J_yy = J_zz = m (3 r^2 + l^2) / 12;
* bar k (k = 1..N) has its centre at (k - 0.5, 0, 0), orientation identity,
  at rest;
* a spherical joint connects the ground point (0, 0, 0) to the left end of
  bar 1 (local (-0.5, 0, 0)), and the right end of bar k (local (+0.5, 0, 0))
  to the left end of bar k+1: 3 algebraic equations each;
* gravity (0, 0, -9.81).

In Exudyn every bar is a NodeRigidBodyEP (7 coordinates: position of the
centre of mass and 4 Euler parameters, plus the node's Euler-parameter
constraint, one algebraic equation) with an ObjectRigidBody; every joint is an
ObjectJointSpherical between two MarkerBodyPosition markers (3 algebraic
equations); gravity is a LoadMassProportional on a MarkerBodyMass.  So the
DAE has 7N coordinates and 4N constraints (3N joint + N Euler-parameter).

Solver: Exudyn's implicit generalized-alpha (index-3, the default variant:
the joints and the Euler-parameter normalisation are both enforced at
position level) with spectral radius 0.8, fixed step h = 1e-3, relative
Newton tolerance 1e-8, modified Newton, dense LU for N < 30 and sparse LU
(Eigen SparseLU) above.  Nothing is written to files, no graphics, no console
output from the solver.

Only the stepping is timed: the model is built, assembled and the solver is
initialised (which includes Exudyn's consistent initial accelerations) before
the clock starts; the clock covers MainSolverImplicitSecondOrder.SolveSteps.

Usage:
    python3 benches/exudyn/spatial_chain.py                  # N = 10, 100, 1000 (+10000)
    python3 benches/exudyn/spatial_chain.py --fast           # Exudyn's exudynCPPfast module
    python3 benches/exudyn/spatial_chain.py --sizes 10 100 --repeats 1
    python3 benches/exudyn/spatial_chain.py --tip            # only "tip x y z" (N = 10, t = 1 s)
    python3 benches/exudyn/spatial_chain.py --json           # JSON lines on stdout, rest on stderr
    python3 benches/exudyn/spatial_chain.py --selfcheck      # N = 1 against a scalar RK4 pendulum
    python3 benches/exudyn/spatial_chain.py --sizes 1000 --mstar target/debug/mstar
        # side by side: after each size's Exudyn runs, the same chain (same N,
        # h, rho_inf, tolerance, end time) through `mstar chain --kind
        # spatial-bars` on one thread, best of --repeats, and the ratio
"""

import argparse
import contextlib
import json
import math
import os
import sys

# ---------------------------------------------------------------------------
# Command line.  It is parsed before exudyn is imported because the choice of
# compiled module (regular or "fast", without range checks) has to be made
# before the first import.
# ---------------------------------------------------------------------------
parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
parser.add_argument("--sizes", type=int, nargs="+", default=[10, 100, 1000],
                    help="chain lengths N to time (default: 10 100 1000; "
                         "10000 is added automatically if N = 1000 takes < --big-limit s per run)")
parser.add_argument("--repeats", type=int, default=3,
                    help="timed runs per size; the minimum is reported (default 3)")
parser.add_argument("--h", type=float, default=1e-3, help="step size, s (default 1e-3)")
parser.add_argument("--rho", type=float, default=0.8, help="spectral radius rho_inf (default 0.8)")
parser.add_argument("--tol", type=float, default=1e-8, help="Newton relative tolerance (default 1e-8)")
parser.add_argument("--fast", action="store_true",
                    help="load exudynCPPfast (no range checks, AVX2) instead of exudynCPP")
parser.add_argument("--tip", action="store_true",
                    help="only print 'tip x y z', the centre of bar 10 of the N = 10 chain "
                         "at t = 1 s, and exit")
parser.add_argument("--json", action="store_true",
                    help="print one JSON object per size on stdout (keys n, steps, us_per_step, "
                         "us_per_body_step, newton_per_step); everything else goes to stderr")
parser.add_argument("--selfcheck", action="store_true",
                    help="only the physics check: N = 1 (a bar on a spherical joint swinging in "
                         "the x-z plane) against a scalar RK4 of the pendulum equation, at t = 0.5 s")
parser.add_argument("--max-load", type=float, default=1.2,
                    help="wait while the 1-minute load average is above this (default 1.2)")
parser.add_argument("--max-wait", type=float, default=300.0,
                    help="give up waiting for a quiet machine after this many s (default 300)")
parser.add_argument("--phases", action="store_true",
                    help="after the table, one extra (untimed-by-us) run per size with Exudyn's "
                         "internal solver timers on, printing where the time goes "
                         "(timers are compiled out of the --fast module)")
parser.add_argument("--sparse-from", type=int, default=30,
                    help="use EigenSparse from this N on, Exudyn's dense solver below "
                         "(default 30, as chain.py)")
parser.add_argument("--big-limit", type=float, default=60.0,
                    help="run N = 10000 only if one run of N = 1000 (100 steps) takes less "
                         "than this many s (default 60)")
parser.add_argument("--mstar", metavar="PATH",
                    help="also run the mstar binary at PATH on every size (mstar chain --kind "
                         "spatial-bars, same N, h, rho_inf, tol and end time, RAYON_NUM_THREADS=1, "
                         "full Newton as mstar chain's default) and print the time ratio "
                         "Exudyn / mstar")
args = parser.parse_args()

if args.fast:
    sys.exudynFast = True  # read by exudyn/__init__.py at import time

# exudyn's __init__ prints a line on stdout when the fast module is loaded;
# with --json stdout is reserved for the JSON lines, so send it to stderr.
with contextlib.redirect_stdout(sys.stderr if args.json else sys.stdout):
    import exudyn as exu                   # noqa: E402  (import after the switch above)
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from quiet_machine import end_time_for, wait_for_quiet_machine  # noqa: E402  (benches/)
import exudyn_run  # noqa: E402  (this folder)
from exudyn.itemInterface import (         # noqa: E402
    LoadMassProportional, MarkerBodyMass, MarkerBodyPosition, NodeRigidBodyEP,
    ObjectGround, ObjectJointSpherical, ObjectRigidBody,
)

# With --json, stdout carries only the JSON lines; all human-readable output
# (progress, the markdown table, the tip) goes to stderr.
OUT = sys.stderr if args.json else sys.stdout


def say(*a):
    print(*a, file=OUT, flush=True)


def wait_quiet():
    """wait_for_quiet_machine (benches/quiet_machine.py), with its messages
    sent to OUT so that --json keeps stdout clean."""
    with contextlib.redirect_stdout(OUT):
        return wait_for_quiet_machine(args.max_load, args.max_wait)


GRAVITY = -9.81          # z component of gravity, m/s^2
MASS = 1.0               # kg
LENGTH = 1.0             # m
RADIUS = 0.02            # m
J_AXIAL = MASS * RADIUS**2 / 2.0                            # about the bar axis (body x)
J_TRANSVERSE = MASS * (3.0 * RADIUS**2 + LENGTH**2) / 12.0  # about body y and z

# From this many bars on the sparse LU is used; below it Exudyn's own dense
# solver (EXUdense), which is what Exudyn recommends for small systems (the
# same switch as chain.py; --sparse-from changes it).  The choice only
# matters for speed; both give the same solution.
SPARSE_FROM_N = args.sparse_from


def build_chain(n):
    """Create a SystemContainer with an assembled n-bar spatial chain.

    Returns (SC, mbs, tip_node) where tip_node is the node of bar n, whose
    position is the centre of mass of that bar."""
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()

    # Ground and the joint point on it (the origin).
    ground = mbs.AddObject(ObjectGround())
    previous_marker = mbs.AddMarker(MarkerBodyPosition(bodyNumber=ground,
                                                       localPosition=[0.0, 0.0, 0.0]))
    # Inertia tensor about the centre of mass in body axes, Exudyn's order
    # [J_xx, J_yy, J_zz, J_yz, J_xz, J_xy].  The node sits at the centre of
    # mass (centerOfMass = [0,0,0], Exudyn's cheaper code path).
    inertia = [J_AXIAL, J_TRANSVERSE, J_TRANSVERSE, 0.0, 0.0, 0.0]
    node = None
    for k in range(1, n + 1):
        # Node coordinates are (x, y, z) of the centre of mass and the Euler
        # parameters (e0, e1, e2, e3).  The reference configuration is the
        # horizontal rest position with identity orientation (e0 = 1), so the
        # initial displacements and velocities are all zero.
        node = mbs.AddNode(NodeRigidBodyEP(
            referenceCoordinates=[(k - 0.5) * LENGTH, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0],
            initialCoordinates=[0.0] * 7,
            initialVelocities=[0.0] * 7,
            addConstraintEquation=True))  # the node adds e.e - 1 = 0 itself
        body = mbs.AddObject(ObjectRigidBody(nodeNumber=node, mass=MASS, inertia=inertia))

        # Gravity, as a load proportional to the body's mass.
        mass_marker = mbs.AddMarker(MarkerBodyMass(bodyNumber=body))
        mbs.AddLoad(LoadMassProportional(markerNumber=mass_marker,
                                         loadVector=[0.0, 0.0, GRAVITY]))

        # Spherical joint at the left end of this bar to the previous bar's
        # right end (or to the ground for k = 1).  Marker positions are
        # body-fixed, relative to the centre of mass.  A position marker is
        # all a spherical joint needs (no rotation coupling).
        left = mbs.AddMarker(MarkerBodyPosition(bodyNumber=body,
                                                localPosition=[-0.5 * LENGTH, 0.0, 0.0]))
        mbs.AddObject(ObjectJointSpherical(markerNumbers=[previous_marker, left],
                                           constrainedAxes=[1, 1, 1]))
        previous_marker = mbs.AddMarker(MarkerBodyPosition(bodyNumber=body,
                                                           localPosition=[0.5 * LENGTH, 0.0, 0.0]))
    mbs.Assemble()
    return SC, mbs, node


def settings_for(n, end_time, h=None):
    """Simulation settings (exudyn_run.settings_for) at this script's options."""
    h = args.h if h is None else h
    return exudyn_run.settings_for(exu, n, end_time, h, args.rho, args.tol, SPARSE_FROM_N)


def node_position(mbs, node):
    """Current (x, y, z) of a bar's centre of mass."""
    p = mbs.GetNodeOutput(node, exu.OutputVariableType.Position)
    return float(p[0]), float(p[1]), float(p[2])


def node_axis(mbs, node):
    """Current direction of the bar's own axis (body x) in global coordinates:
    the first column of the rotation matrix.  Exudyn returns the matrix as 9
    numbers, row by row."""
    a = mbs.GetNodeOutput(node, exu.OutputVariableType.RotationMatrix)
    return float(a[0]), float(a[3]), float(a[6])


PHASES = exudyn_run.PHASES


def solve_once(n, end_time, phases=False, h=None):
    """Build, initialise, then time only SolveSteps.  Returns a dict.

    With phases=True Exudyn's internal per-phase timers are switched on (this
    adds some overhead, so such a run is not used for the table)."""
    SC, mbs, tip_node = build_chain(n)
    s = settings_for(n, end_time, h)
    out = exudyn_run.timed_solve(exu, mbs, s, n, phases)
    out['tip'] = node_position(mbs, tip_node)
    out['tip_axis'] = node_axis(mbs, tip_node)
    solver = out.pop('solver')
    solver.FinalizeSolver(mbs, s)
    del SC, mbs
    return out


# ---------------------------------------------------------------------------
# Physics check (--selfcheck).  One bar on a spherical joint at the origin,
# released horizontally along +x, swings in the x-z plane as a physical
# pendulum about the y axis.  With theta the angle of the bar below the +x
# axis (theta = 0 at t = 0, growing as the bar falls), the moment of gravity
# about the pivot gives
#     J_pivot theta'' = -m GRAVITY (l/2) cos(theta),  GRAVITY = -9.81,
#     J_pivot = J_zz + m (l/2)^2,
# i.e. theta'' = +9.81 * 0.5 * cos(theta) / J_pivot > 0 at the start.
# ---------------------------------------------------------------------------
def pendulum_rk4(t_end, h):
    """Classical RK4 of the scalar pendulum equation above; returns theta(t_end)."""
    j_pivot = J_TRANSVERSE + MASS * (0.5 * LENGTH)**2
    c = -MASS * GRAVITY * 0.5 * LENGTH / j_pivot

    def f(th, om):
        return om, c * math.cos(th)

    th, om = 0.0, 0.0
    steps = int(round(t_end / h))
    for _ in range(steps):
        k1 = f(th, om)
        k2 = f(th + 0.5 * h * k1[0], om + 0.5 * h * k1[1])
        k3 = f(th + 0.5 * h * k2[0], om + 0.5 * h * k2[1])
        k4 = f(th + h * k3[0], om + h * k3[1])
        th += h / 6.0 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0])
        om += h / 6.0 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1])
    return th


def selfcheck():
    t_end = 0.5
    # RK4 at h = 1e-5 and 2e-5: the difference estimates its own error
    # (fourth order, so ~1e-15 rad at these steps).
    ref = pendulum_rk4(t_end, 1e-5)
    ref2 = pendulum_rk4(t_end, 2e-5)
    say("selfcheck: N = 1, t = %g s, theta below +x (rad)" % t_end)
    say("  RK4 reference (h = 1e-5):           theta = %.12f  (vs h = 2e-5: %.1e)"
        % (ref, ref - ref2))
    # Exudyn at the requested h and at h/2, h/4 to show the convergence order.
    worst = 0.0
    for div in (1, 2, 4):
        h = args.h / div
        r = solve_once(1, t_end, h=h)
        x, y, z = r['tip']
        ax, ay, az = r['tip_axis']
        th_pos = math.atan2(-z, x)     # from the centre of mass
        th_rot = math.atan2(-az, ax)   # from the body x axis (rotation matrix)
        d = th_rot - ref
        if div == 1:
            worst = d
        say("  Exudyn h = %-8g steps %5d:  theta(axis) = %.12f  theta(centre) = %.12f  "
            "diff(axis - RK4) = %+.3e  |y| = %.1e  |centre| - 0.5 = %+.1e"
            % (h, r['steps'], th_rot, th_pos, d, abs(y), math.hypot(x, z) - 0.5 * LENGTH))
    say("selfcheck difference at h = %g: %+.3e rad" % (args.h, worst))
    return worst


def run_mstar(n, t_end):
    """One run of `mstar chain --kind spatial-bars` on the settings of this
    script; returns its µs/step, Newton iterations/step and tip (x, y, z)."""
    import re
    import subprocess
    cmd = [args.mstar, "chain", "--kind", "spatial-bars", "--links", str(n),
           "--t-end", repr(t_end), "--h", repr(args.h), "--rho", repr(args.rho),
           "--tol", repr(args.tol)]
    env = dict(os.environ, RAYON_NUM_THREADS="1")
    out = subprocess.run(cmd, env=env, check=True, capture_output=True, text=True).stdout
    step = re.search(r"time per step: ([0-9.]+) µs", out)
    newton = re.search(r"Newton iterations: \d+ \(([0-9.]+) per step", out)
    tip = re.search(r"x = (\S+) m, y = (\S+) m, z = (\S+) m", out)
    if not (step and newton and tip):
        raise RuntimeError("unexpected output of %s:\n%s" % (" ".join(cmd), out))
    return {'us_per_step': float(step.group(1)), 'newton': float(newton.group(1)),
            'tip': tuple(float(tip.group(k)) for k in (1, 2, 3)), 'command': " ".join(cmd)}


def best_mstar(n, t_end):
    """The fastest of --repeats runs of mstar at size n."""
    best = None
    for _ in range(args.repeats):
        wait_quiet()
        r = run_mstar(n, t_end)
        if best is None or r['us_per_step'] < best['us_per_step']:
            best = r
    say("  N = %6d mstar: %.1f µs/step, %.2f Newton it./step (%s)"
        % (n, best['us_per_step'], best['newton'], best['command']))
    return best


def side_by_side_table(rows, mstar_rows):
    """Exudyn and mstar per body-step on the same chains, and the ratio."""
    lines = ["| N | Exudyn µs/body/step | mstar µs/body/step | Exudyn / mstar | tip x (Exudyn) | tip x (mstar) |",
             "|---:|---:|---:|---:|---:|---:|"]
    for (n, r), m in zip(rows, mstar_rows):
        exu_us = r['wall'] / r['steps'] * 1e6 / n
        ms_us = m['us_per_step'] / n
        lines.append("| %d | %.3f | %.3f | %.1f | %.9f | %.9f |"
                     % (n, exu_us, ms_us, exu_us / ms_us, r['tip'][0], m['tip'][0]))
    return "\n".join(lines)


def markdown_table(rows):
    lines = ["| N | steps | µs/step | µs/body/step | Newton/step | Jac/step | rejected | linear solver |",
             "|---:|---:|---:|---:|---:|---:|---:|---|"]
    for n, r in rows:
        us_step = r['wall'] / r['steps'] * 1e6
        lines.append("| %d | %d | %.1f | %.2f | %.2f | %.3f | %d | %s |"
                     % (n, r['steps'], us_step, us_step / n, r['newton'] / r['steps'],
                        r['jacobians'] / r['steps'], r['rejected'],
                        "sparse" if n >= SPARSE_FROM_N else "dense"))
    return "\n".join(lines)


def main():
    header = ("exudyn %s, module %s; spatial bar chain (NodeRigidBodyEP + ObjectJointSpherical); "
              "h = %g, rho_inf = %g, Newton rel. tol = %g, modified Newton"
              % (exu.__version__, exu._compiledModuleName, args.h, args.rho, args.tol))

    if args.selfcheck:
        say(header)
        selfcheck()
        return

    # Sanity check: centre of bar 10 of the 10-bar chain at t = 1 s.
    r = solve_once(10, 1.0)
    if args.tip:
        # "tip x y z" on stdout, whatever --json says, for the xtask.
        print("tip %.9f %.9f %.9f" % r['tip'], flush=True)
        return
    say(header)
    say("N = 10 tip (centre of bar 10) at t = %.6g s: x = %.9f m, y = %.9f m, z = %.9f m"
        % ((r['t_final'],) + r['tip']))

    sizes = list(args.sizes)
    rows, mstar_rows = [], []
    i = 0
    while i < len(sizes):
        n = sizes[i]
        t_end = end_time_for(n)
        best = None
        for rep in range(args.repeats):
            load = wait_quiet()
            r = solve_once(n, t_end)
            say("  N = %6d run %d: %.4f s for %d steps (load %.2f)"
                % (n, rep + 1, r['wall'], r['steps'], load))
            if r['steps'] != r['nominal_steps']:
                say("    (note: %d steps instead of the nominal %d)" % (r['steps'], r['nominal_steps']))
            if best is None or r['wall'] < best['wall']:
                best = r
        rows.append((n, best))
        if args.mstar:
            mstar_rows.append(best_mstar(n, t_end))
        if args.json:
            us_step = best['wall'] / best['steps'] * 1e6
            print(json.dumps({'n': n, 'steps': best['steps'], 'us_per_step': us_step,
                              'us_per_body_step': us_step / n,
                              'newton_per_step': best['newton'] / best['steps']}),
                  flush=True)
        # N = 10000 only if a run of N = 1000 (100 steps) is cheap enough.
        if n == 1000 and 10000 not in sizes and best['wall'] < args.big_limit:
            sizes.append(10000)
        i += 1

    say()
    say("exudyn %s (%s), generalized-alpha rho_inf = %g, h = %g, tol = %g, modified Newton"
        % (exu.__version__, exu._compiledModuleName, args.rho, args.h, args.tol))
    say()
    say(markdown_table(rows))
    if args.mstar:
        say()
        say("side by side (same N, h, rho_inf, tol, end time; one thread each; best of %d):"
            % args.repeats)
        say()
        say(side_by_side_table(rows, mstar_rows))

    if args.phases:
        say()
        say("Exudyn internal timers, us per step (one extra run per size, timers on):")
        say("%8s %10s " % ("N", "wall") + " ".join("%15s" % p for p in PHASES))
        for n, _ in rows:
            wait_quiet()
            r = solve_once(n, end_time_for(n), phases=True)
            per = lambda sec: sec / r['steps'] * 1e6  # noqa: E731
            say("%8d %10.1f " % (n, per(r['wall']))
                + " ".join("%15.1f" % per(r['phases'][p]) for p in PHASES))


if __name__ == '__main__':
    main()
