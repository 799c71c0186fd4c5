//! Running and checking model files (`docs/model-format.md`): the integrator
//! configuration of a file's `[simulation]`, and what `mstar check` reports
//! before a run (degrees of freedom, redundant constraints by name, how far
//! the initial state is from the constraints).

use mstar_file::Mechanism;
use mstar_file::{ErrorControlChoice, IntegratorChoice, NewtonChoice, RedundantChoice, Simulation};
use mstar_kkt::{Backend, MaxAbs, argmax_abs, max_abs};
use mstar_model::planar::PlanarSystem;
use mstar_model::spatial::SpatialSystem;
use mstar_model::{RowSubset, System};
use mstar_newmark::{
    Config, IntegrationError, Integrator, Newton, Observer, RunStats, Scheme, StepMode,
};

use crate::redundant::{Expanded, Rows};

/// The defaults of `[simulation]` (`docs/model-format.md`).
pub mod defaults {
    /// `t_end`, s.
    pub const T_END: f64 = 1.0;
    /// `h`, s.
    pub const H: f64 = 1e-3;
    /// `rho` (generalized-α).
    pub const RHO: f64 = 0.9;
    /// `rho` with `error_control = "adaptive"`: each change of the step size
    /// excites generalized-α's period-2 mode, which ρ∞ = 0.9 damps slowly
    /// (`docs/work-precision.md`).
    pub const RHO_ADAPTIVE: f64 = 0.5;
    /// `alpha` (HHT).
    pub const ALPHA: f64 = -0.1;
    /// `beta`, `gamma` (Newmark: the paper's trapezoidal rule).
    pub const BETA: f64 = 0.25;
    /// See [`BETA`].
    pub const GAMMA: f64 = 0.5;
}

/// The integrator configuration and end time of a model file's
/// `[simulation]`, its defaults applied.
///
/// # Errors
/// [`SettingsError`] for a KKT solver name that no backend has, or settings
/// the integrator refuses.
pub fn config(sim: &Simulation) -> Result<(Config, f64), SettingsError> {
    let mut c = Config {
        h: sim.h.unwrap_or(defaults::H),
        h_min: sim.h_min,
        ..Config::default()
    };
    c.error.mode = match sim.error_control.unwrap_or_default() {
        ErrorControlChoice::Monitor => StepMode::Monitor,
        ErrorControlChoice::Strict => StepMode::Strict,
        ErrorControlChoice::Adaptive => StepMode::Adaptive,
    };
    c.error.rtol = sim.rtol.unwrap_or(c.error.rtol);
    c.error.atol = sim.atol.unwrap_or(c.error.atol);
    c.error.h_max = sim.h_max;
    let rho = if c.error.mode == StepMode::Adaptive {
        defaults::RHO_ADAPTIVE
    } else {
        defaults::RHO
    };
    c.scheme = match sim.integrator.unwrap_or(IntegratorChoice::GeneralizedAlpha) {
        IntegratorChoice::GeneralizedAlpha => Scheme::GeneralizedAlpha {
            rho_inf: sim.rho.unwrap_or(rho),
        },
        IntegratorChoice::Hht => Scheme::Hht {
            alpha: sim.alpha.unwrap_or(defaults::ALPHA),
        },
        IntegratorChoice::Newmark => Scheme::Newmark {
            beta: sim.beta.unwrap_or(defaults::BETA),
            gamma: sim.gamma.unwrap_or(defaults::GAMMA),
        },
    };
    if let Some(tol) = sim.tol {
        c.tol = tol;
    }
    if let Some(k) = sim.max_iterations {
        c.max_iterations = k;
    }
    c.newton = match sim.newton {
        Some(NewtonChoice::Full) => Newton::Full,
        Some(NewtonChoice::Modified) => Newton::MODIFIED,
        Some(NewtonChoice::PerStep) => Newton::PER_STEP,
        _ => Newton::Automatic,
    };
    if let Some(name) = &sim.kkt {
        c.kkt.backend = Backend::named(name).ok_or_else(|| SettingsError::UnknownKkt {
            name: name.clone(),
            known: mstar_kkt::backends()
                .iter()
                .map(|r| r.backend.name())
                .collect(),
        })?;
    }
    c.validate().map_err(SettingsError::Refused)?;
    Ok((c, sim.t_end.unwrap_or(defaults::T_END)))
}

/// What is wrong with a model's `[simulation]` settings.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SettingsError {
    /// `kkt` names no registered backend.
    #[error("[simulation] kkt: no KKT solver is called '{name}'; the solvers are: auto, {}", .known.join(", "))]
    UnknownKkt {
        /// The name given.
        name: String,
        /// The registered backends' names.
        known: Vec<&'static str>,
    },
    /// The integrator refuses the settings (a value out of range).
    #[error("{0}")]
    Refused(IntegrationError),
    /// `redundant = "minimum-norm"` on a model too large for the dense
    /// minimum-norm multipliers.
    #[error("[simulation] redundant = \"minimum-norm\" computes the multipliers densely, for n·m up to {limit}, and this model has n·m = {nm}: remove its redundant constraints ({}) and the setting", .joints.join(", "))]
    MinimumNormTooLarge {
        /// The largest `n · m` it takes.
        limit: usize,
        /// This model's `n · m`.
        nm: usize,
        /// The joints of the redundant rows.
        joints: Vec<String>,
    },
}

/// Why a model file does not run.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RunError {
    /// `[simulation]` asks for something that does not exist or does not fit.
    #[error(transparent)]
    Settings(#[from] SettingsError),
    /// Redundant constraints in a model that does not ask for minimum-norm
    /// multipliers: the joints, by name.
    #[error(
        "the constraints of {} are redundant (their equations are linearly dependent at the start): if they repeat what the other joints impose in every position (a third crank on a parallelogram), remove or loosen one, or set [simulation] redundant = \"minimum-norm\" (on the command line: --set simulation.redundant=minimum-norm) to run with minimum-norm multipliers; if the start is a singular position of the mechanism (a parallelogram lying flat), start it away from there",
        .0.join(", ")
    )]
    Redundant(Vec<String>),
    /// Redundant constraints in a model too large for minimum-norm
    /// multipliers (n·m above [`crate::redundant::DENSE_LIMIT`]): the joints,
    /// by name, and no advice that would be refused.
    #[error(
        "the constraints of {} are redundant (their equations are linearly dependent at the start): if they repeat what the other joints impose in every position, remove or loosen one (a model this large, n·m above 4e6, cannot run with minimum-norm multipliers); if the start is a singular position of the mechanism, start it away from there",
        .0.join(", ")
    )]
    RedundantLarge(Vec<String>),
    /// Redundant rows that are all drivers': a driver prescribing a motion
    /// the joints and the other drivers already fix at the start (a driven
    /// crank angle and a held slider position). Such a driver contradicts
    /// them as soon as they move, so minimum-norm multipliers (which would
    /// run until it stops holding) are not offered.
    #[error(
        "the drivers {} prescribe what the joints and the other drivers already fix at the start (their equations are linearly dependent on the others'): such a driver contradicts them as soon as the mechanism moves; remove it, or drive another coordinate",
        .0.join(", ")
    )]
    RedundantDrivers(Vec<String>),
    /// Dependent rows at an initial pose that violates a constraint by more
    /// than [`FAR_POSE`]: the dependence may be the pose's (a crank and a
    /// rod stretched in line towards a point they cannot reach), so the
    /// violation comes first, then what to do if the pose is right.
    #[error(
        "the initial pose violates '{owner}' by {violation:.3e} (row {row}), and at that pose the constraints of {} are linearly dependent on the others: the joints cannot all hold in the pose given. Fix the initial pose of the bodies that '{owner}' joins ({pose_keys}) or the points of '{owner}' so that it holds at t = 0 (mstar check shows the violation); {}",
        .joints.join(", "),
        redundant_advice(*.large)
    )]
    RedundantAtViolatedPose {
        /// The joints of the dependent rows.
        joints: Vec<String>,
        /// The element of the most violated row.
        owner: String,
        /// That row's name.
        row: String,
        /// `|Φ|` there, m or rad.
        violation: f64,
        /// Above the size minimum-norm multipliers take (their advice left out).
        large: bool,
        /// The keys of the model's format that give the pose
        /// ([`ModelLookup::pose_keys`]).
        pose_keys: &'static str,
    },
    /// Rows left out of a minimum-norm solve that the others do not imply:
    /// the joints contradict each other.
    #[error(
        "the constraints of {} contradict the others: after the start they are still violated by {violation:.3e}; a redundant joint must repeat what the others impose (check its points)",
        .joints.join(", ")
    )]
    Contradicting {
        /// The joints of the violated rows.
        joints: Vec<String>,
        /// The largest violation, m or rad.
        violation: f64,
    },
    /// A row left out of a minimum-norm solve stopped holding during the run:
    /// the redundancy found at the start changed along the motion.
    #[error(
        "the constraints of {} stopped holding at t = {} s (violated by {violation:.3e}): they were redundant at the start but are not along the motion (a mechanism passing a singular position), so minimum-norm multipliers cannot run it; remove the redundancy from the model",
        .joints.join(", "),
        mstar_newmark::Short(*.t)
    )]
    RedundancyChanged {
        /// The joints.
        joints: Vec<String>,
        /// When, s.
        t: f64,
        /// By how much, m or rad.
        violation: f64,
    },
    /// The start or a step failed.
    #[error(transparent)]
    Integration(#[from] IntegrationError),
    /// The caller asked the run to stop ([`simulate_until`]) before it
    /// reached its end.
    #[error("stopped at t = {} s", mstar_newmark::Short(*.t))]
    Stopped {
        /// How far it got, s.
        t: f64,
    },
}

/// The constraint rows to solve on: `None` for all of them, or (in
/// [`Rows::kept`]) the independent rows when the model has redundant
/// constraints and asks for minimum-norm multipliers (`crate::redundant`).
///
/// # Errors
/// [`RunError::Redundant`] when it has redundant constraints and does not.
pub fn solve_rows<S: ModelLookup + ?Sized>(
    sys: &S,
    u0: &[f64],
    choice: RedundantChoice,
) -> Result<Option<Rows>, RunError> {
    // Not sorted out (past the sparse elimination's budget): all rows, as
    // the KKT factorization then finds out whether they are independent.
    let Ok(rows) = crate::redundant::rows(sys, 0.0, u0) else {
        return Ok(None);
    };
    match (rows.dependent.is_empty(), choice) {
        (true, _) => Ok(None),
        (false, RedundantChoice::MinimumNorm) => {
            minimum_norm_fits(sys, &rows)?;
            Ok(Some(rows))
        }
        (false, RedundantChoice::Refuse) => Err(RunError::redundant_at(
            owners(sys, &rows.dependent),
            sys,
            u0,
        )),
    }
}

/// An initial violation beyond which dependent rows at the pose may be the
/// pose's, not the model's, m or rad (the command line's note on a start
/// far from a joint uses the same).
pub const FAR_POSE: f64 = 1e-6;

/// What to do when the pose is right and the rows really depend on each
/// other: the advice of [`RunError::Redundant`], without minimum-norm
/// multipliers above their size (`large`).
fn redundant_advice(large: bool) -> &'static str {
    if large {
        "if the pose is right and the joints repeat what the others impose in every position, remove or loosen one (a model this large, n·m above 4e6, cannot run with minimum-norm multipliers)"
    } else {
        "if the pose is right and the joints repeat what the others impose in every position (a third crank on a parallelogram), remove or loosen one, or set [simulation] redundant = \"minimum-norm\" (on the command line: --set simulation.redundant=minimum-norm)"
    }
}

impl RunError {
    /// [`RunError::redundant`] for the dependent rows of `joints` found at
    /// `sys`'s initial pose `u0`, or [`RunError::RedundantAtViolatedPose`]
    /// when that pose violates a constraint by more than [`FAR_POSE`].
    #[must_use]
    pub fn redundant_at<S: ModelLookup + ?Sized>(joints: Vec<String>, sys: &S, u0: &[f64]) -> Self {
        let (n, m) = (sys.n_coords(), sys.n_constraints());
        let mut phi = vec![0.0; m];
        sys.phi_into(0.0, u0, &mut phi);
        match violation(sys, &phi) {
            Some((owner, row, value)) if value.abs() > FAR_POSE => Self::RedundantAtViolatedPose {
                joints,
                owner,
                row,
                violation: value.abs(),
                large: n * m > crate::redundant::DENSE_LIMIT,
                pose_keys: sys.pose_keys(),
            },
            _ if joints.iter().all(|j| sys.is_driver(j) == Some(true)) => {
                Self::RedundantDrivers(joints)
            }
            _ => Self::redundant(joints, n, m),
        }
    }

    /// The error of redundant constraints (`joints`) in a model of `n`
    /// coordinates and `m` constraints: [`RunError::Redundant`], or above
    /// the size minimum-norm multipliers take, [`RunError::RedundantLarge`]
    /// (whose advice does not offer them).
    #[must_use]
    pub fn redundant(joints: Vec<String>, n: usize, m: usize) -> Self {
        if n * m > crate::redundant::DENSE_LIMIT {
            Self::RedundantLarge(joints)
        } else {
            Self::Redundant(joints)
        }
    }
}

/// Minimum-norm multipliers take a dense pseudo-inverse of `Bᵀ`
/// ([`crate::redundant::MinimumNorm`]): up to `n · m` =
/// [`crate::redundant::DENSE_LIMIT`].
///
/// # Errors
/// [`RunError::Settings`] for a larger model, naming its redundant joints.
fn minimum_norm_fits<S: ModelLookup + ?Sized>(sys: &S, rows: &Rows) -> Result<(), RunError> {
    let (n, m) = (sys.n_coords(), sys.n_constraints());
    if n * m <= crate::redundant::DENSE_LIMIT {
        return Ok(());
    }
    Err(RunError::Settings(SettingsError::MinimumNormTooLarge {
        limit: crate::redundant::DENSE_LIMIT,
        nm: n * m,
        joints: owners(sys, &rows.dependent),
    }))
}

/// Checks that the rows left out of a minimum-norm solve hold at the start
/// state `u` (the projection only enforced the kept ones): within
/// `1e-8 max(1, ‖u‖∞)`.
///
/// # Errors
/// [`RunError::Contradicting`] with the joints of the violated rows.
pub fn left_out_rows_hold<S: ModelLookup + ?Sized>(
    sys: &S,
    rows: &Rows,
    u: &[f64],
) -> Result<(), RunError> {
    let mut phi = vec![0.0; sys.n_constraints()];
    sys.phi_into(0.0, u, &mut phi);
    let scale = u.iter().fold(1.0f64, |m, x| m.max(x.abs()));
    let bad: Vec<usize> = rows
        .dependent
        .iter()
        .copied()
        .filter(|&r| phi[r].abs() > 1e-8 * scale || phi[r].is_nan())
        .collect();
    if bad.is_empty() {
        return Ok(());
    }
    let violation = bad.iter().map(|&r| phi[r].abs()).fold(0.0, f64::max);
    Err(RunError::Contradicting {
        joints: owners(sys, &bad),
        violation,
    })
}

/// The error for rows that stopped holding.
#[must_use]
pub fn redundancy_changed<S: ModelLookup + ?Sized>(
    sys: &S,
    d: crate::redundant::Drift,
) -> RunError {
    RunError::RedundancyChanged {
        joints: owners(sys, &[d.row]),
        t: d.t,
        violation: d.violation,
    }
}

/// Runs a model from its initial state to `[simulation] t_end` with its
/// settings (defaults as documented), every sample to `observer` — with the
/// multipliers of all rows, minimum-norm ones when the model asks for them.
///
/// # Errors
/// [`RunError`]: bad settings, refused redundant constraints, a start or a
/// step that fails (the samples before it have been observed).
pub fn simulate<S: ModelLookup + ?Sized>(
    sys: &S,
    sim: &Simulation,
    observer: &mut dyn Observer,
) -> Result<RunStats, RunError> {
    simulate_until(sys, sim, observer, &mut || false)
}

/// [`simulate`], asking `stop` before every step whether to stop there (a
/// front end's Ctrl-C); the steps are those of [`simulate`], bit for bit.
///
/// # Errors
/// As [`simulate`], and [`RunError::Stopped`] when `stop` said so (every
/// sample before has been observed).
pub fn simulate_until<S: ModelLookup + ?Sized>(
    sys: &S,
    sim: &Simulation,
    observer: &mut dyn Observer,
    stop: &mut dyn FnMut() -> bool,
) -> Result<RunStats, RunError> {
    simulate_noting(sys, sim, observer, stop, &mut Vec::new())
}

/// [`simulate_until`], with the start's notes about the state given
/// ([`far_start_note`], [`projection_notes`]: what `mstar run` prints
/// before its first step) pushed to `notes`.
///
/// # Errors
/// As [`simulate_until`].
pub fn simulate_noting<S: ModelLookup + ?Sized>(
    sys: &S,
    sim: &Simulation,
    observer: &mut dyn Observer,
    stop: &mut dyn FnMut() -> bool,
    notes: &mut Vec<String>,
) -> Result<RunStats, RunError> {
    let (config, t_end) = config(sim)?;
    let (u0, v0) = (sys.initial_position(), sys.initial_velocity());
    let rows = solve_rows(sys, &u0, sim.redundant.unwrap_or_default())?;
    notes.extend(far_start_note(sys));
    match rows {
        Some(rows) => {
            let subset = RowSubset::new(sys, rows.kept.clone());
            let mut integ = Integrator::new(&subset, config, 0.0, &u0, &v0)?;
            notes.extend(projection_notes(sys, integ.start_report(), &u0, &v0));
            left_out_rows_hold(sys, &rows, integ.view().u)?;
            let mut expanded = Expanded::new(&subset, observer);
            let stats = drive(&mut integ, t_end, &mut expanded, stop)?;
            match expanded.drifted() {
                Some(d) => Err(redundancy_changed(sys, d)),
                None => Ok(stats),
            }
        }
        None => {
            let mut integ = Integrator::new(sys, config, 0.0, &u0, &v0)?;
            notes.extend(projection_notes(sys, integ.start_report(), &u0, &v0));
            drive(&mut integ, t_end, observer, stop)
        }
    }
}

/// An initial violation worth a note, m or rad.
const FAR_NOTE: f64 = 1e-6;

/// The note of an initial pose far from a joint (by more than `1e-6`), which
/// the start moves onto the constraints: `note: the initial pose violates
/// '…' by … (row …); …`.
#[must_use]
pub fn far_start_note<S: ModelLookup + ?Sized>(sys: &S) -> Option<String> {
    let (owner, row, value) = initial_violation(sys)?;
    (value > FAR_NOTE).then(|| {
        format!(
            "note: the initial pose violates '{owner}' by {value:.3e} (row {row}); the start moves the coordinates onto the constraints (mstar check shows what it moves)"
        )
    })
}

/// The warnings of a start whose projection changed a given (non-zero)
/// position or velocity by more than round-off (`1e-9` of their scale):
/// the state integrated is not the one written, and the projection, the
/// smallest change in the coordinates' Euclidean norm, weighs metres,
/// radians and Euler parameters alike, so a given angular velocity is
/// shared with the centre of mass's velocity (docs/model-format.md).
/// Values left at zero (not given) are filled in without a warning.
#[must_use]
pub fn projection_notes<S: System + ?Sized>(
    sys: &S,
    report: &mstar_newmark::StartReport,
    u0: &[f64],
    v0: &[f64],
) -> Vec<String> {
    let mut notes = Vec::new();
    for (level, change, given) in [
        ("positions", &report.position_correction, u0),
        ("velocities", &report.velocity_correction, v0),
    ] {
        let scale = max_abs(given).max(1.0);
        let of_given: Vec<f64> = change
            .iter()
            .zip(given)
            .map(|(&d, &x)| if x == 0.0 { 0.0 } else { d })
            .collect();
        let (i, by) = argmax_abs(&of_given);
        if by.abs() > 1e-9 * scale {
            let name = sys.coord_name(i);
            // An Euler-parameter rate: the angular velocity of a body whose
            // centre must move with it (docs/model-format.md).
            let turning = level == "velocities"
                && name
                    .rsplit_once('.')
                    .is_some_and(|(_, c)| matches!(c, "e0" | "e1" | "e2" | "e3"));
            let hint = if turning {
                "; a body turning about a joint keeps its angular velocity when its centre's \
                 velocity ω × r is given as well"
            } else {
                ""
            };
            notes.push(format!(
                "warning: the start changed the given {level} to satisfy the joints: '{name}' \
                 from {} to {} (the largest change), the smallest change in the coordinates' \
                 Euclidean norm (every coordinate weighted alike); give {level} that satisfy the \
                 joints to have them kept (mstar check lists what it moves){hint}",
                mstar_newmark::Short(given[i]),
                mstar_newmark::Short(given[i] + change[i])
            ));
        }
    }
    notes
}

/// Integrates to `t_end` as [`Integrator::run`] does, the initial state and
/// every accepted step to `observer`, asking `stop` before every step.
fn drive<S: System + ?Sized>(
    integ: &mut Integrator<'_, S>,
    t_end: f64,
    observer: &mut dyn Observer,
    stop: &mut dyn FnMut() -> bool,
) -> Result<RunStats, RunError> {
    if !t_end.is_finite() {
        // The integrator's error for it.
        return Ok(integ.run(t_end, observer)?);
    }
    observer.observe(&integ.view());
    while !integ.reached(t_end) {
        if stop() {
            return Err(RunError::Stopped { t: integ.time() });
        }
        integ.step(t_end)?;
        observer.observe(&integ.view());
    }
    Ok(integ.stats())
}

/// An error as the command line prints it after `error: `: its message and
/// those of its sources, joined by `: `, each left out when the line already
/// holds it.
#[must_use]
pub fn error_message(e: &(dyn std::error::Error + 'static)) -> String {
    let mut line = String::new();
    for cause in std::iter::successors(Some(e), |e| e.source()) {
        let text = cause.to_string();
        if line.contains(&text) {
            continue;
        }
        if !line.is_empty() {
            line.push_str(": ");
        }
        line.push_str(&text);
    }
    line
}

/// What `mstar check` finds out about a model before running it.
#[derive(Clone, Debug, PartialEq)]
pub struct CheckReport {
    /// Coordinates `n`.
    pub coordinates: usize,
    /// Constraint equations `m`.
    pub constraints: usize,
    /// `rank B` at the initial pose (`None` when it was not computed: see
    /// [`not_computed`](Self::not_computed)).
    pub rank: Option<usize>,
    /// Why the rank and the redundant constraints were not computed, if
    /// they were not (the sparse elimination's fill-in past its budget,
    /// [`crate::redundant::NotComputed`]).
    pub not_computed: Option<String>,
    /// The joints and drivers with a constraint row that depends on the rows
    /// before it, by name, in file order (empty also when not computed).
    pub redundant: Vec<String>,
    /// Whether the model runs with minimum-norm multipliers (it has redundant
    /// constraints and asks for them).
    pub minimum_norm: bool,
    /// The most violated constraint row at the initial pose, by owner and
    /// row name, with `|Φ|`.
    pub position_violation: Option<(String, String, f64)>,
    /// The same for the velocity constraint `B u̇ + Φ_t`.
    pub velocity_violation: Option<(String, String, f64)>,
    /// What the initial projection moves most: coordinate and amount, for
    /// positions and velocities (`None` when the start fails).
    pub projection: Option<[(String, f64); 2]>,
    /// Why the model cannot start, if it cannot.
    pub start_error: Option<String>,
    /// Whether `start_error` is the integrator's refusal of its
    /// configuration (a KKT solver that does not fit the model,
    /// [`IntegrationError::Config`]), which a caller can place at the
    /// file's `[simulation] kkt`.
    pub start_refuses_config: bool,
    /// The first [`ROWS_LISTED`] constraint rows by name (the CSV's
    /// `lambda:<row>` columns).
    pub rows: Vec<String>,
}

/// How many constraint rows a [`CheckReport`] names.
pub const ROWS_LISTED: usize = 40;

/// Checks `sys` at its initial state with the integrator configuration
/// `config`, redundant constraints handled as `redundant` says.
#[must_use]
pub fn check<S: ModelLookup + ?Sized>(
    sys: &S,
    config: &Config,
    redundant: RedundantChoice,
) -> CheckReport {
    let (n, m) = (sys.n_coords(), sys.n_constraints());
    let (u0, v0) = (sys.initial_position(), sys.initial_velocity());
    let rows = crate::redundant::rows(sys, 0.0, &u0);
    let dependent = rows.as_ref().map_or(&[][..], |r| &r.dependent[..]);
    let minimum_norm = redundant == RedundantChoice::MinimumNorm && !dependent.is_empty();
    let (phi, w) = initial_violations(sys, &u0, &v0);
    let start = match &rows {
        Ok(rows) if minimum_norm => minimum_norm_fits(sys, rows)
            .map_err(|e| StartFailure::from(e.to_string()))
            .and_then(|()| {
                let subset = RowSubset::new(sys, rows.kept.clone());
                let (moved, u) = start_report(&subset, config, &u0, &v0)?;
                left_out_rows_hold(sys, rows, &u).map_err(|e| e.to_string())?;
                Ok((moved, u))
            }),
        // Without minimum-norm multipliers the KKT matrix is singular: the
        // solver's pivot would name a row of the dependent set that need
        // not be the redundant joint.
        Ok(rows) if !rows.dependent.is_empty() => Err(StartFailure::from(format!(
            "at start-up (t = 0): the KKT matrix is singular with the redundant constraints of \
             {}: their multipliers are undetermined",
            owners(sys, &rows.dependent).join(", ")
        ))),
        _ => start_report(sys, config, &u0, &v0),
    };
    let (projection, start_error, start_refuses_config) = match start {
        Ok((p, _)) => (Some(p), None, false),
        Err(e) => (None, Some(e.why), e.config),
    };
    CheckReport {
        coordinates: n,
        constraints: m,
        rank: rows.as_ref().ok().map(|r| r.rank),
        not_computed: rows.as_ref().err().map(ToString::to_string),
        redundant: owners(sys, dependent),
        minimum_norm,
        position_violation: violation(sys, &phi),
        velocity_violation: violation(sys, &w),
        projection,
        start_error,
        start_refuses_config,
        rows: (0..m.min(ROWS_LISTED))
            .map(|k| sys.constraint_name(k))
            .collect(),
    }
}

/// The joints and drivers that own `rows`, each once, in order.
#[must_use]
pub fn owners<S: ModelLookup + ?Sized>(sys: &S, rows: &[usize]) -> Vec<String> {
    let mut seen = std::collections::HashSet::new();
    let mut names: Vec<String> = Vec::new();
    for &row in rows {
        let owner = sys.constraint_owner(row).unwrap_or("?");
        if seen.insert(owner) {
            names.push(owner.to_string());
        }
    }
    names
}

/// The most violated constraint row at the initial pose, by owner and row
/// name, with `|Φ|` (`None` when every row holds exactly).
#[must_use]
pub fn initial_violation<S: ModelLookup + ?Sized>(sys: &S) -> Option<(String, String, f64)> {
    let (u0, v0) = (sys.initial_position(), sys.initial_velocity());
    violation(sys, &initial_violations(sys, &u0, &v0).0)
}

/// `Φ` and `B u̇ + Φ_t` at the initial state.
fn initial_violations<S: ModelLookup + ?Sized>(
    sys: &S,
    u0: &[f64],
    v0: &[f64],
) -> (Vec<f64>, Vec<f64>) {
    let m = sys.n_constraints();
    let mut phi = vec![0.0; m];
    sys.phi_into(0.0, u0, &mut phi);
    let mut w = vec![0.0; m];
    sys.phi_t_into(0.0, u0, &mut w);
    let p = sys.b_pattern();
    let mut b = vec![0.0; p.len()];
    sys.b_into(0.0, u0, &mut b);
    p.mul_add(&b, v0, &mut w);
    (phi, w)
}

/// The coordinate the start moves most and by how much: positions, velocities.
type Moved = [(String, f64); 2];

/// Why a start failed, and whether it is the configuration's refusal
/// ([`CheckReport::start_refuses_config`]).
struct StartFailure {
    why: String,
    config: bool,
}

impl From<String> for StartFailure {
    fn from(why: String) -> Self {
        Self { why, config: false }
    }
}

/// What the initial projection moves most (position, velocity) and the
/// start state's coordinates, or why the start fails.
fn start_report<S: System + ?Sized>(
    sys: &S,
    config: &Config,
    u0: &[f64],
    v0: &[f64],
) -> Result<(Moved, Vec<f64>), StartFailure> {
    let integ = Integrator::new(sys, config.clone(), 0.0, u0, v0).map_err(|e| StartFailure {
        config: matches!(e, IntegrationError::Config(_)),
        why: e.to_string(),
    })?;
    let report = integ.start_report();
    let largest = |d: &[f64]| {
        let (i, x) = argmax_abs(d);
        (sys.coord_name(i), x)
    };
    let moved = [
        largest(&report.position_correction),
        largest(&report.velocity_correction),
    ];
    Ok((moved, integ.view().u.to_vec()))
}

impl CheckReport {
    /// Whether the model can run as written: no redundant constraint (or
    /// minimum-norm multipliers asked for), and a start; `false` when the
    /// redundant constraints were not computed (unknown is not "none").
    #[must_use]
    pub fn can_run(&self) -> bool {
        self.not_computed.is_none()
            && (self.redundant.is_empty() || self.minimum_norm)
            && self.start_error.is_none()
    }

    /// The degrees of freedom `n − rank B`, when the rank is known.
    #[must_use]
    pub fn degrees_of_freedom(&self) -> Option<usize> {
        self.rank.map(|r| self.coordinates - r)
    }
}

impl std::fmt::Display for CheckReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(f, "coordinates: {}", self.coordinates)?;
        writeln!(f, "constraints: {}", self.constraints)?;
        let not_computed = |why: &str| format!("not computed ({why})");
        match (self.degrees_of_freedom(), &self.not_computed) {
            (Some(dof), _) => writeln!(f, "degrees of freedom: {dof}")?,
            (None, why) => writeln!(
                f,
                "degrees of freedom: {}",
                not_computed(why.as_deref().unwrap_or("unknown"))
            )?,
        }
        let redundant = match (self.redundant.is_empty(), self.minimum_norm) {
            (true, _) if self.rank.is_none() => {
                not_computed(self.not_computed.as_deref().unwrap_or("unknown"))
            }
            (true, _) => "none".to_string(),
            (false, false) => self.redundant.join(", "),
            (false, true) => format!(
                "{} (left out of the solve: minimum-norm multipliers)",
                self.redundant.join(", ")
            ),
        };
        writeln!(f, "redundant constraints: {redundant}")?;
        for (level, v) in [
            ("position", &self.position_violation),
            ("velocity", &self.velocity_violation),
        ] {
            match v {
                Some((owner, row, value)) => writeln!(
                    f,
                    "initial {level} violation: {value:.3e} at '{owner}' (row {row})"
                )?,
                None => writeln!(f, "initial {level} violation: none")?,
            }
        }
        match (&self.projection, &self.start_error) {
            (Some(moved), _) => {
                for (level, (name, by)) in ["position", "velocity"].iter().zip(moved) {
                    if *by == 0.0 {
                        writeln!(f, "initial projection: no {level} moves")?;
                    } else {
                        writeln!(
                            f,
                            "initial projection: moves {level} '{name}' by {by:.3e} (the most)"
                        )?;
                    }
                }
            }
            (None, Some(e)) => writeln!(f, "start: fails: {e}")?,
            (None, None) => {}
        }
        self.fmt_rows(f)
    }
}

impl CheckReport {
    /// The line naming the constraint rows (the first [`ROWS_LISTED`]).
    fn fmt_rows(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let mut listed = self.rows.join(", ");
        if self.constraints > self.rows.len() {
            listed.push_str(&format!(
                ", … ({} in all: the header of `mstar run --out` has every one)",
                self.constraints
            ));
        }
        if listed.is_empty() {
            listed = "none".into();
        }
        writeln!(f, "constraint rows (CSV columns lambda:<row>): {listed}")
    }
}

/// The largest `|xᵢ|` by owner and row name, `None` when all are zero.
fn violation<S: ModelLookup + ?Sized>(sys: &S, x: &[f64]) -> Option<(String, String, f64)> {
    let mut m = MaxAbs::new();
    x.iter().for_each(|&v| m.push(v));
    if m.value() == 0.0 {
        return None;
    }
    let (i, value) = argmax_abs(x);
    Some((
        sys.constraint_owner(i).unwrap_or("?").to_string(),
        sys.constraint_name(i),
        value,
    ))
}

/// What running and checking a model needs of it beyond [`System`]: its
/// initial state, and its joints and drivers by name with their rows and
/// reactions. Implemented for planar and spatial models.
pub trait ModelLookup: System + mstar_model::sensor::Frames {
    /// Initial coordinates `u₀`, as the model file gives them.
    fn initial_position(&self) -> Vec<f64>;
    /// Initial velocities `u̇₀`.
    fn initial_velocity(&self) -> Vec<f64>;
    /// The joint, driver (or, for a spatial model, body: its normalization
    /// row) whose constraint row `row` is.
    fn constraint_owner(&self, row: usize) -> Option<&str>;
    /// The joints and drivers, in file order.
    fn joint_names(&self) -> Vec<&str>;
    /// Whether the joint `name` is a driver (`None`: no such joint).
    fn is_driver(&self, name: &str) -> Option<bool>;
    /// The constraint rows of the joint or driver `name`.
    fn joint_rows(&self, name: &str) -> Option<std::ops::Range<usize>>;
    /// The suffixes of a joint's reaction columns: `fx, fy, tau` (planar) or
    /// `fx, fy, fz, tx, ty, tz` (spatial).
    fn reaction_components(&self) -> &'static [&'static str];
    /// Appends the reaction of the `joint`-th joint or driver at the state
    /// `(t, u, λ)`, one value per [`reaction_components`](Self::reaction_components)
    /// (NaN when it has none).
    fn reaction_into(&self, joint: usize, t: f64, u: &[f64], lambda: &[f64], out: &mut Vec<f64>);
    /// The keys that place the bodies, for hints: what to edit when the
    /// initial pose is off.
    fn pose_keys(&self) -> &'static str;
}

/// The [`ModelLookup`] methods that planar and spatial systems have as
/// inherent methods of the same names and meanings.
macro_rules! forward_lookup {
    () => {
        fn initial_position(&self) -> Vec<f64> {
            Self::initial_position(self)
        }
        fn initial_velocity(&self) -> Vec<f64> {
            Self::initial_velocity(self)
        }
        fn constraint_owner(&self, row: usize) -> Option<&str> {
            Self::constraint_owner(self, row)
        }
        fn joint_names(&self) -> Vec<&str> {
            Self::joint_names(self).collect()
        }
        fn is_driver(&self, name: &str) -> Option<bool> {
            Self::is_driver(self, name)
        }
        fn joint_rows(&self, name: &str) -> Option<std::ops::Range<usize>> {
            Self::joint_rows(self, name)
        }
    };
}

impl ModelLookup for PlanarSystem {
    forward_lookup!();
    fn reaction_components(&self) -> &'static [&'static str] {
        &["fx", "fy", "tau"]
    }
    fn reaction_into(&self, joint: usize, t: f64, u: &[f64], lambda: &[f64], out: &mut Vec<f64>) {
        match self.reaction_at(joint, t, u, lambda) {
            Some(r) => out.extend([r.force[0], r.force[1], r.moment]),
            None => out.extend([f64::NAN; 3]),
        }
    }
    fn pose_keys(&self) -> &'static str {
        "[[body]] pose, [[point_mass]] position"
    }
}

impl ModelLookup for SpatialSystem {
    forward_lookup!();
    fn reaction_components(&self) -> &'static [&'static str] {
        &["fx", "fy", "fz", "tx", "ty", "tz"]
    }
    fn reaction_into(&self, joint: usize, t: f64, u: &[f64], lambda: &[f64], out: &mut Vec<f64>) {
        let reaction = Self::joint_names(self)
            .nth(joint)
            .and_then(|name| self.reaction(name, t, u, lambda));
        match reaction {
            Some(r) => out.extend(r.force.into_iter().chain(r.torque)),
            None => out.extend([f64::NAN; 6]),
        }
    }
    fn pose_keys(&self) -> &'static str {
        "[[body]] position and orientation, [[point_mass]] position"
    }
}

/// The mechanism of a model file as a [`ModelLookup`].
#[must_use]
pub fn lookup(m: &Mechanism) -> &(dyn ModelLookup + 'static) {
    match m {
        Mechanism::Planar(s) => s,
        Mechanism::Spatial(s) => s,
    }
}
