//! A parallelogram with a redundant third crank (minimum-norm multipliers)
//! against the plain parallelogram whose two cranks carry the third one's
//! mass: all cranks move alike, so the two move the same.

use std::path::Path;

use super::{Case, Level, Row, samples, worse};

/// `models/parallelogram-third-crank.toml`.
pub(super) const CASE: Case = Case {
    model: "parallelogram-third-crank.toml",
    run: parallelogram,
};

fn parallelogram(models: &Path, _: Level) -> Result<Vec<Row>, String> {
    let (third, plain) = ("parallelogram-third-crank.toml", "parallelogram.toml");
    let (a, b) = (
        super::load(models, third, &[])?,
        super::load(models, plain, &[])?,
    );
    let (ra, rb) = (samples(models, third, &[])?, samples(models, plain, &[])?);
    if ra.len() != rb.len() {
        return Err(format!("{} samples against {}", ra.len(), rb.len()));
    }
    let mut pairs = Vec::new();
    for body in ["left", "right", "coupler"] {
        let (x, y) = (a.system.body(body), b.system.body(body));
        let (x, y) = x.zip(y).ok_or(format!("no body '{body}' in both"))?;
        pairs.extend([(x.x, y.x), (x.y, y.y)]);
        pairs.extend(x.theta.zip(y.theta));
    }
    let mut worst = 0.0f64;
    for (sa, sb) in ra.iter().zip(&rb) {
        for &(i, j) in &pairs {
            worst = worse(worst, (sa.u[i] - sb.u[j]).abs());
        }
    }
    let t_end = ra.last().map_or(0.0, |s| s.t);
    Ok(vec![Row {
        model: third.to_string(),
        quantity: format!("max |Δu| of the cranks and coupler over {t_end} s"),
        reference: format!("{plain} (no redundancy)"),
        ours: format!("{worst:.2e}"),
        error: worst,
        tolerance: 1e-10,
    }])
}
