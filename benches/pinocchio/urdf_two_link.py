#!/usr/bin/env python3
"""Pinocchio reference for mstar's URDF import: models/urdf/two-link-arm.urdf.

Pinocchio (Carpentier et al., "The Pinocchio C++ library", SII 2019,
https://github.com/stack-of-tasks/pinocchio) reads the SAME URDF file with
its own parser (fixed base; the massless tool frame merged into the forearm,
as mstar merges it) and gives the joint accelerations by the articulated-body
algorithm, `pin.aba`, in the two joint angles. These are integrated with the
classical fourth-order Runge-Kutta scheme at h = 1e-5 s for 1 s, two cases:

* rest:  both joints at 0, at rest (the arm released with the upper arm
  horizontal: models/urdf/two-link-arm.urdf run as it is);
* start: shoulder 0.3 rad at 1 rad/s, elbow -0.5 rad at -2 rad/s
  (models/urdf/two-link-arm-start.toml, whose [[initial]] tables say so).

RK4's error at h = 1e-5 is of order (h/T)^4 with T ~ 0.3 s the fastest time
scale: ~1e-18 relative, below the 17 significant digits written. Each file
holds every 0.01 s: t, the joint angles and the global centre of mass of each
link (the positions mstar writes as u:<link>.x, .y, .z).

Usage (Pinocchio 4.1.0 from PyPI, `pip install pin`):
    python3 benches/pinocchio/urdf_two_link.py    # writes crates/cli/tests/data/urdf-two-link-{rest,start}.csv
"""

import os

import numpy as np
import pinocchio as pin

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
URDF = os.path.join(ROOT, "models", "urdf", "two-link-arm.urdf")
OUT = os.path.join(ROOT, "crates", "cli", "tests", "data")

H = 1e-5
T_END = 1.0
EVERY = 1000  # steps between rows: 0.01 s


def accel(model, data, q, v):
    """The joint accelerations, aba(q, v, tau = 0)."""
    return pin.aba(model, data, q, v, np.zeros(model.nv))


def angles(model, q):
    """The joint angles: the revolute shoulder's q, the continuous elbow's
    atan2(sin, cos) (Pinocchio keeps an unbounded joint as cos, sin)."""
    out = []
    for name in ("shoulder", "elbow"):
        joint = model.joints[model.getJointId(name)]
        qj = q[joint.idx_q : joint.idx_q + joint.nq]
        out.append(qj[0] if joint.nq == 1 else np.arctan2(qj[1], qj[0]))
    return out


def centres(model, data, q):
    """The global centre of mass of the upper arm and of the forearm."""
    pin.forwardKinematics(model, data, q)
    out = []
    for name in ("shoulder", "elbow"):
        j = model.getJointId(name)
        out.extend(data.oMi[j].act(model.inertias[j].lever))
    return out


def rk4_step(model, data, q, v):
    """One RK4 step on the configuration manifold: each stage's q is
    pin.integrate(q, c h q'), exact on the circle of the continuous joint
    (an abelian group), so the scheme keeps its fourth order."""
    a1 = accel(model, data, q, v)
    v2 = v + 0.5 * H * a1
    a2 = accel(model, data, pin.integrate(model, q, 0.5 * H * v), v2)
    v3 = v + 0.5 * H * a2
    a3 = accel(model, data, pin.integrate(model, q, 0.5 * H * v2), v3)
    v4 = v + H * a3
    a4 = accel(model, data, pin.integrate(model, q, H * v3), v4)
    q = pin.integrate(model, q, H / 6.0 * (v + 2.0 * v2 + 2.0 * v3 + v4))
    v = v + H / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4)
    return q, v


def run(model, angles0, v0, path):
    data = model.createData()
    q = pin.neutral(model)
    for name, angle in zip(("shoulder", "elbow"), angles0):
        joint = model.joints[model.getJointId(name)]
        if joint.nq == 1:
            q[joint.idx_q] = angle
        else:
            q[joint.idx_q : joint.idx_q + 2] = [np.cos(angle), np.sin(angle)]
    v = np.array(v0, dtype=float)
    rows = []
    steps = int(round(T_END / H))
    for k in range(steps + 1):
        if k % EVERY == 0:
            rows.append([k * H, *angles(model, q), *centres(model, data, q)])
        if k < steps:
            q, v = rk4_step(model, data, q, v)
    header = "t,shoulder,elbow,upper_arm.x,upper_arm.y,upper_arm.z,forearm.x,forearm.y,forearm.z"
    with open(path, "w") as f:
        f.write(header + "\n")
        for r in rows:
            f.write(",".join(repr(float(x)) for x in r) + "\n")


def main():
    model = pin.buildModelFromUrdf(URDF)
    assert model.nv == 2, "two joints: a revolute shoulder, a continuous elbow"
    assert list(model.gravity.linear) == [0.0, 0.0, -9.81]
    run(model, [0.0, 0.0], [0.0, 0.0], os.path.join(OUT, "urdf-two-link-rest.csv"))
    run(model, [0.3, -0.5], [1.0, -2.0], os.path.join(OUT, "urdf-two-link-start.csv"))


if __name__ == "__main__":
    main()
