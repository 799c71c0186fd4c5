//! The integrator options of `mstar pendulum` and `mstar chain`.

use anyhow::{Context, Result, bail};
use clap::ValueEnum;
use mstar::kkt::Backend;
use mstar::{Config, Newton, Scheme, StepMode};

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Integrator {
    /// Newmark(β, γ); the paper's scheme with β = 1/4, γ = 1/2.
    Newmark,
    /// Hilber-Hughes-Taylor α (--alpha in [−1/3, 0]).
    Hht,
    /// Generalized-α (Chung & Hulbert) with spectral radius --rho.
    GeneralizedAlpha,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum NewtonArg {
    /// Refactor at every iteration (the paper's setting).
    Full,
    /// Reuse the factorization while the iteration contracts fast.
    Modified,
    /// A fresh factorization at each step's first iteration, reused by the
    /// step's later ones while they contract fast (the default of `mstar chain`).
    PerStep,
}

/// The `--kkt` values: `auto` and every registered backend, with its summary.
fn kkt_values() -> clap::builder::PossibleValuesParser {
    let auto = clap::builder::PossibleValue::new("auto")
        .help("chosen from the size and structure (the default, above)");
    clap::builder::PossibleValuesParser::new(
        std::iter::once(auto).chain(
            mstar::kkt::backends()
                .iter()
                .map(|r| clap::builder::PossibleValue::new(r.backend.name()).help(r.summary)),
        ),
    )
}

/// Integrator options shared by every model command.
#[derive(clap::Args, Debug, Default)]
pub struct IntegratorArgs {
    /// Step size h, s [default: pendulum 0.01, chain 1e-3].
    #[arg(long, allow_negative_numbers = true)]
    pub h: Option<f64>,
    /// Smallest step size for step control, s [default: h/1024; with
    /// --adaptive h·1e-6; paper: h, i.e. off].
    #[arg(long, allow_negative_numbers = true)]
    pub h_min: Option<f64>,
    /// Integrator [default: generalized-alpha; paper: newmark].
    #[arg(long, value_enum)]
    pub integrator: Option<Integrator>,
    /// Newmark β [paper: 0.25]; implies --integrator newmark.
    #[arg(long, allow_negative_numbers = true)]
    pub beta: Option<f64>,
    /// Newmark γ [paper: 0.5]; implies --integrator newmark.
    #[arg(long, allow_negative_numbers = true)]
    pub gamma: Option<f64>,
    /// Generalized-α spectral radius ρ∞ in [0, 1] [default: 0.9].
    #[arg(long, allow_negative_numbers = true)]
    pub rho: Option<f64>,
    /// HHT α in [−1/3, 0] [default: −0.1].
    #[arg(long, allow_hyphen_values = true)]
    pub alpha: Option<f64>,
    /// Newton variant [default: per-step with schur-lu, else modified; chain: per-step; paper: full].
    #[arg(long, value_enum)]
    pub newton: Option<NewtonArg>,
    /// KKT solver [default: auto: dense LU up to 24 unknowns; above, Schur when
    /// the bodies interact only through constraints, have mass and symmetric
    /// force Jacobians, else LDLᵀ, else (unsymmetric) sparse LU].
    #[arg(long, value_parser = kkt_values())]
    pub kkt: Option<String>,
    /// Relative Newton tolerance on ‖r‖ and ‖Φ‖ [default: 1e-10].
    #[arg(long, allow_negative_numbers = true)]
    pub tol: Option<f64>,
    /// Newton iterations per step attempt [default: 20].
    #[arg(long, allow_negative_numbers = true)]
    pub max_iter: Option<usize>,
    /// Relative tolerance of the local error estimate on the positions
    /// [default: 1e-3]: a step is within it when its estimated error is at
    /// most atol + rtol·|u| in every coordinate.
    #[arg(long, allow_negative_numbers = true)]
    pub rtol: Option<f64>,
    /// Absolute tolerance of the local error estimate, m or rad [default: 1e-6].
    #[arg(long, allow_negative_numbers = true)]
    pub atol: Option<f64>,
    /// Adapt the step size to the error estimate (--h is the first step;
    /// ρ∞ defaults to 0.5). Without it the step size is fixed and the
    /// estimate only monitored: a warning when it exceeds the tolerance.
    #[arg(long, conflicts_with = "strict")]
    pub adaptive: bool,
    /// Fixed step size, and an error (exit 1, samples kept) at the first step
    /// whose estimated error exceeds the tolerance.
    #[arg(long)]
    pub strict: bool,
    /// Largest step size with --adaptive, s [default: none].
    #[arg(long, requires = "adaptive", allow_negative_numbers = true)]
    pub h_max: Option<f64>,
}

/// Applies the error-control options to `c`: `--adaptive` without an
/// explicit scheme is generalized-α with ρ∞ = 0.5 (`docs/work-precision.md`).
fn apply_error_control(args: &IntegratorArgs, c: &mut Config) {
    c.error.rtol = args.rtol.unwrap_or(c.error.rtol);
    c.error.atol = args.atol.unwrap_or(c.error.atol);
    c.error.h_max = args.h_max.or(c.error.h_max);
    if args.strict {
        c.error.mode = StepMode::Strict;
    }
    let explicit_scheme = args.integrator.is_some()
        || args.rho.is_some()
        || args.alpha.is_some()
        || args.beta.is_some()
        || args.gamma.is_some();
    if args.adaptive {
        c.error.mode = StepMode::Adaptive;
        if c.scheme == Scheme::default() && !explicit_scheme {
            c.scheme = Scheme::GeneralizedAlpha {
                rho_inf: mstar::run::defaults::RHO_ADAPTIVE,
            };
        }
    }
}

/// Applies the integrator options to `c` (`paper_preset`: an explicit `--h`
/// also fixes `h_min`, keeping step control off as in the paper).
pub fn apply_integrator(args: &IntegratorArgs, c: &mut Config, paper_preset: bool) -> Result<()> {
    if let Some(h) = args.h {
        c.h = h;
        if paper_preset {
            c.h_min = Some(h);
        }
    }
    if args.h_min.is_some() {
        c.h_min = args.h_min;
    }
    if let Some(tol) = args.tol {
        c.tol = tol;
    }
    if let Some(k) = args.max_iter {
        c.max_iterations = k;
    }
    apply_error_control(args, c);
    if let Some(n) = args.newton {
        c.newton = match n {
            NewtonArg::Full => Newton::Full,
            NewtonArg::Modified => Newton::MODIFIED,
            NewtonArg::PerStep => Newton::PER_STEP,
        };
    }
    if let Some(name) = &args.kkt {
        c.kkt.backend =
            Backend::named(name).with_context(|| format!("no KKT solver is called '{name}'"))?;
    }
    // Scheme: explicit --integrator, else implied by --beta/--gamma, --rho, --alpha.
    let newmark_args = args.beta.is_some() || args.gamma.is_some();
    let integrator = args.integrator.or(if newmark_args {
        Some(Integrator::Newmark)
    } else if args.rho.is_some() {
        Some(Integrator::GeneralizedAlpha)
    } else if args.alpha.is_some() {
        Some(Integrator::Hht)
    } else {
        None
    });
    if let Some(integrator) = integrator {
        let misplaced = |opt: &str, needs: &str| -> Result<()> {
            bail!("{opt} applies to --integrator {needs}, not {integrator:?}")
        };
        if newmark_args && integrator != Integrator::Newmark {
            misplaced("--beta/--gamma", "newmark")?;
        }
        if args.rho.is_some() && integrator != Integrator::GeneralizedAlpha {
            misplaced("--rho", "generalized-alpha")?;
        }
        if args.alpha.is_some() && integrator != Integrator::Hht {
            misplaced("--alpha", "hht")?;
        }
        let (beta0, gamma0) = match c.scheme {
            Scheme::Newmark { beta, gamma } => (beta, gamma),
            _ => (0.25, 0.5),
        };
        c.scheme = match integrator {
            Integrator::Newmark => Scheme::Newmark {
                beta: args.beta.unwrap_or(beta0),
                gamma: args.gamma.unwrap_or(gamma0),
            },
            Integrator::Hht => Scheme::Hht {
                alpha: args.alpha.unwrap_or(-0.1),
            },
            Integrator::GeneralizedAlpha => Scheme::GeneralizedAlpha {
                rho_inf: args.rho.unwrap_or(if args.adaptive {
                    mstar::run::defaults::RHO_ADAPTIVE
                } else {
                    mstar::run::defaults::RHO
                }),
            },
        };
    }
    Ok(())
}
