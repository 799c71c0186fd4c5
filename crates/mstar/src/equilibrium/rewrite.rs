//! A model file rewritten to start at an equilibrium (`mstar equilibrium
//! --write-model`, Python's `Equilibrium.write_model`): each element's
//! initial pose replaced, everything else of the text kept, and the result
//! read back to check that it is the same mechanism.

use mstar_file::{FileError, Format, MechanismFile};

use crate::run::ModelLookup;

/// Why [`model_text`] wrote nothing.
#[derive(Debug, thiserror::Error)]
pub enum RewriteError {
    /// The text's initial poses could not be replaced.
    #[error("{0}")]
    Pose(String),
    /// The rewritten text is not a model file any more.
    #[error("the written model cannot be read back: {0}")]
    ReadBack(#[from] FileError),
    /// The rewritten model has other coordinates or constraints.
    #[error("the written model has other dimensions ({n} coordinates and {m} constraints)")]
    Dimensions {
        /// Its coordinates.
        n: usize,
        /// Its constraint rows.
        m: usize,
    },
    /// An element is defined from the initial pose, so moving the pose
    /// changed the mechanism.
    #[error(
        "{what} is not the same in the written model: an element is defined from the initial pose; give it explicitly in the file and run again: a joint's local `points` instead of `at`, its local `axes` instead of `axis` (spatial), a `length` or `rest_length` instead of the default, a planar rotational spring's `rest_angle` (a spatial one is measured from the initial pose: a model with one cannot be rewritten)"
    )]
    PoseDependent {
        /// `the constraint <row>` or `the force on <coordinate>`.
        what: String,
    },
}

/// The elements' coordinates by name: `body.x, body.y, body.theta` →
/// `("body", [x, y, θ])`, in the model's order.
fn poses(sys: &dyn ModelLookup, u: &[f64]) -> Vec<(String, Vec<f64>)> {
    let mut out: Vec<(String, Vec<f64>)> = Vec::new();
    for (i, &x) in u.iter().enumerate() {
        let name = sys.coord_name(i);
        let element = name.rsplit_once('.').map_or(name.as_str(), |(e, _)| e);
        match out.last_mut() {
            Some((last, values)) if last == element => values.push(x),
            _ => out.push((element.to_string(), vec![x])),
        }
    }
    out
}

/// The TOML model file `text` (the model `sys`, named `origin` in
/// messages) with the pose `u` as its initial pose: each `[[body]]`'s
/// `pose` (planar) or `position` and `orientation` (spatial), each
/// `[[point_mass]]`'s `position`; comments and everything else kept.
///
/// # Errors
/// [`RewriteError`] when the poses cannot be replaced, or the text written
/// is not the same mechanism once read back (its constraints and forces at
/// `u`, with the drivers at `t = 0`, differ from `sys`'s beyond round-off).
pub fn model_text(
    text: &str,
    origin: &str,
    sys: &dyn ModelLookup,
    u: &[f64],
) -> Result<String, RewriteError> {
    let written = mstar_file::pose::with_initial_pose(text, &poses(sys, u))
        .map_err(|e| RewriteError::Pose(format!("{origin}: {e}")))?;
    let file = MechanismFile::parse_with(&written, origin, Format::Toml, &[])?;
    same_mechanism(sys, crate::run::lookup(&file.mechanism), u)?;
    Ok(written)
}

/// Compares the constraints and forces of `new` at `u` (at rest, `t = 0`)
/// with `old`'s: an element defined from the initial pose (a joint's `at`,
/// a default length or rest angle) would change with it.
fn same_mechanism(
    old: &dyn ModelLookup,
    new: &dyn ModelLookup,
    u: &[f64],
) -> Result<(), RewriteError> {
    let (n, m) = (old.n_coords(), old.n_constraints());
    if new.n_coords() != n || new.n_constraints() != m {
        return Err(RewriteError::Dimensions {
            n: new.n_coords(),
            m: new.n_constraints(),
        });
    }
    let zeros = vec![0.0; n];
    let (mut phi_old, mut phi_new) = (vec![0.0; m], vec![0.0; m]);
    old.phi_into(0.0, u, &mut phi_old);
    new.phi_into(0.0, u, &mut phi_new);
    let (mut g_old, mut g_new) = (vec![0.0; n], vec![0.0; n]);
    old.forces_into(0.0, u, &zeros, &mut g_old);
    new.forces_into(0.0, u, &zeros, &mut g_new);
    // Round-off of the pose written and read back, relative to the sizes.
    let length = u.iter().fold(1.0_f64, |a, x| a.max(x.abs()));
    let force = g_old.iter().fold(f64::MIN_POSITIVE, |a, x| a.max(x.abs()));
    // A NaN is a difference too.
    let differs = |a: f64, b: f64, scale: f64| {
        let d = (a - b).abs();
        d.is_nan() || d > 1e-9 * scale
    };
    if let Some(i) = (0..m).find(|&i| differs(phi_old[i], phi_new[i], length)) {
        let what = format!("the constraint {}", old.constraint_name(i));
        return Err(RewriteError::PoseDependent { what });
    }
    if let Some(i) = (0..n).find(|&i| differs(g_old[i], g_new[i], force)) {
        let what = format!("the force on {}", old.coord_name(i));
        return Err(RewriteError::PoseDependent { what });
    }
    Ok(())
}
