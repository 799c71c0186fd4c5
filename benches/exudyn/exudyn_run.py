"""Shared by chain.py and spatial_chain.py: Exudyn's simulation settings for
the side-by-side runs (generalized-alpha at a fixed step, index 3, modified
Newton, quiet, no files, one thread) and one timed run of SolveSteps."""

import time

# Exudyn's internal solver timers (seconds, summed over the run) that are
# reported with --phases.  reactionForces is the constraint-force term
# (C_q^T lambda) of the residual, AERHS the constraint equations themselves.
PHASES = ['ODE2RHS', 'reactionForces', 'AERHS', 'totalJacobian', 'massMatrix',
          'factorization', 'newtonIncrement', 'integrationFormula']


def settings_for(exu, n, end_time, h, rho, tol, sparse_from_n):
    """Simulation settings: generalized-alpha, fixed h, quiet, no files."""
    s = exu.SimulationSettings()
    ti = s.timeIntegration
    ti.solverType = exu.DynamicSolverType.GeneralizedAlpha
    ti.startTime = 0.0
    ti.endTime = end_time
    ti.numberOfSteps = int(round(end_time / h))
    ti.verboseMode = 0
    ti.verboseModeFile = 0
    ti.stepInformation = 0

    ga = ti.generalizedAlpha
    ga.spectralRadius = rho
    ga.useNewmark = False            # true generalized-alpha, not Newmark
    ga.useIndex2Constraints = False  # index-3 (position-level) constraints, as in mstar;
    #                                  for Euler parameters this also puts their
    #                                  constraint at position level (e.e - 1 = 0)
    ga.computeInitialAccelerations = True  # consistent start, as mstar's default

    nw = ti.newton
    nw.relativeTolerance = tol
    nw.useModifiedNewton = True
    # absoluteTolerance keeps Exudyn's default (1e-10): it only matters when
    # the residual is already tiny at the start of a step.

    # No solution, sensor or restart files; no end-of-run statistics.
    sol = s.solution
    sol.file.write = False
    sol.sensors.active = False
    sol.restart.write = False
    sol.recordImagesInterval = -1
    s.show.computationTime = False
    s.show.statistics = False
    s.show.globalTimers = False

    # Linear solver: sparse LU for large chains.  reuseAnalyzedPattern keeps
    # the symbolic analysis between factorizations (the pattern never
    # changes for these models).
    if n >= sparse_from_n:
        s.linearSolver.solverType = exu.LinearSolverType.EigenSparse
        s.linearSolver.reuseAnalyzedPattern = True
    else:
        s.linearSolver.solverType = exu.LinearSolverType.EXUdense
    s.parallel.numberOfThreads = 1  # mstar is timed on one thread
    return s


def timed_solve(exu, mbs, s, n, phases=False):
    """Initialise, then time only SolveSteps of the assembled system `mbs`
    with settings `s`.  Returns a dict (wall time, steps, Newton iterations,
    Jacobians, rejected steps, final time, and with phases=True Exudyn's
    internal per-phase timers, which add some overhead).  The caller reads
    its outputs from `mbs` before finalize(mbs) is called on the result's
    'solver'."""
    solver = exu.MainSolverImplicitSecondOrder()
    if not solver.InitializeSolver(mbs, s):
        raise RuntimeError("InitializeSolver failed for N = %d" % n)
    if phases:
        solver.timer.Reset(True)  # zero all timers; True = keep them switched on
        solver.timer.useTimer = True
    t0 = time.perf_counter()
    ok = solver.SolveSteps(mbs, s)
    wall = time.perf_counter() - t0
    if not ok:
        raise RuntimeError("SolveSteps failed for N = %d: %s" % (n, solver.GetErrorString()))
    it = solver.it
    out = {
        'solver': solver,
        'wall': wall,
        # currentStepIndex is the index of the *next* step (it starts at 1),
        # so the number of completed steps is one less.
        'steps': it.currentStepIndex - 1,
        'nominal_steps': s.timeIntegration.numberOfSteps,
        'newton': it.newtonStepsCount,         # Newton iterations, whole run
        'jacobians': it.newtonJacobiCount,     # Jacobian evaluations = factorizations
        'rejected': it.rejectedModifiedNewtonSteps,
        't_final': it.currentTime,
    }
    if phases:
        out['phases'] = {name: getattr(solver.timer, name) for name in PHASES}
    return out
