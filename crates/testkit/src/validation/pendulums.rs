//! The paper's pendulum and a double pendulum against RK4 on their
//! joint-angle equations (`mstar::rk4::AngleChain`, minimal coordinates).

use std::path::Path;

use mstar::rk4::{AngleChain, AngleLink};

use super::order::order_row;
use super::{Case, Level, Row, samples, worse};

/// `models/pendulum.toml`: the bob's position.
pub(super) const PENDULUM: Case = Case {
    model: "pendulum.toml",
    run: pendulum,
};

/// `models/double-pendulum.toml`: the lower bar's centre of mass.
pub(super) const DOUBLE_PENDULUM: Case = Case {
    model: "double-pendulum.toml",
    run: |models, level| double_pendulum(models, level, "double-pendulum.toml"),
};

/// `models/double-pendulum.json`: the same model in JSON.
pub(super) const DOUBLE_PENDULUM_JSON: Case = Case {
    model: "double-pendulum.json",
    run: |models, level| double_pendulum(models, level, "double-pendulum.json"),
};

fn pendulum(models: &Path, level: Level) -> Result<Vec<Row>, String> {
    // The bob on a massless rod of 1 m, g = 10, from the horizontal at rest:
    // the angle from +x starts at 0.
    let link = AngleLink {
        m: 1.0,
        j: 0.0,
        l: 1.0,
        c: 1.0,
    };
    let chain = AngleChain::new(vec![link], 10.0);
    let t_end = if level == Level::Tight { 10.0 } else { 2.0 };
    let spec = Spec {
        file: "pendulum.toml",
        body: "bob",
        chain: &chain,
        phi0: &[0.0],
        t_end,
        h: 0.01,
    };
    let (coarse, fine) = (spec.error(models, 1.0)?, spec.error(models, 0.5)?);
    Ok(vec![order_row(
        spec.file,
        &format!("max |Δ bob position| over {t_end} s"),
        "RK4 oracle on θ̈ = −(g/l) sin θ",
        spec.h,
        coarse,
        fine,
    )])
}

fn double_pendulum(models: &Path, level: Level, file: &str) -> Result<Vec<Row>, String> {
    let chain = AngleChain::new(
        vec![
            AngleLink {
                m: 1.0,
                j: 1.0 / 12.0,
                l: 1.0,
                c: 0.5,
            },
            AngleLink {
                m: 0.6,
                j: 0.032,
                l: 0.8,
                c: 0.4,
            },
        ],
        9.81,
    );
    let t_end = if level == Level::Tight { 5.0 } else { 1.0 };
    let spec = Spec {
        file,
        body: "lower",
        chain: &chain,
        phi0: &[0.4, -0.3],
        t_end,
        h: 2e-3,
    };
    let (coarse, fine) = (spec.error(models, 1.0)?, spec.error(models, 0.5)?);
    Ok(vec![order_row(
        spec.file,
        &format!("max |Δ lower bar's centre| over {t_end} s"),
        "RK4 on the joint-angle equations",
        spec.h,
        coarse,
        fine,
    )])
}

/// A chain model and its minimal-coordinate reference, released at rest.
struct Spec<'a> {
    file: &'a str,
    /// The body whose centre of mass is compared (the chain's last).
    body: &'a str,
    chain: &'a AngleChain,
    phi0: &'a [f64],
    t_end: f64,
    h: f64,
}

impl Spec<'_> {
    /// The largest distance between the body's centre and the reference's
    /// over the run with step `scale · h`.
    fn error(&self, models: &Path, scale: f64) -> Result<f64, String> {
        let set = [
            format!("simulation.h={:e}", self.h * scale),
            format!("simulation.t_end={:e}", self.t_end),
        ];
        let run = samples(models, self.file, &set)?;
        let model = super::load(models, self.file, &[])?;
        let b = model
            .system
            .body(self.body)
            .ok_or_else(|| format!("{}: no body '{}'", self.file, self.body))?;
        let times: Vec<f64> = run.iter().map(|s| s.t).collect();
        let omega0 = vec![0.0; self.phi0.len()];
        let reference = self.chain.solve(self.phi0, &omega0, &times);
        let mut worst = 0.0f64;
        for (s, (phi, _)) in run.iter().zip(&reference) {
            let want = self.chain.centres(phi)[self.phi0.len() - 1];
            worst = worse(worst, (s.u[b.x] - want[0]).hypot(s.u[b.y] - want[1]));
        }
        Ok(worst)
    }
}
