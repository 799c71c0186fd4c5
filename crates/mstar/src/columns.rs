//! The columns a model file's run writes beyond the state: reactions and
//! efforts ([`ReactionColumns`]), then sensors ([`SensorColumns`]); and the
//! choice of columns by name (`[output] columns`, `--columns`;
//! [`Selection`]). `docs/model-format.md`, "`[[sensor]]`" and "Output".

use mstar_model::sensor::{BodyPoint, Frame, Motion, Sensor, SensorKind, cardan_angles};
use mstar_model::{SampleRef, StateRef};

use crate::run::ModelLookup;

/// Columns a model adds after the standard ones (e.g. reactions by joint,
/// see [`ReactionColumns`]).
pub trait Columns {
    /// Their header names.
    fn names(&self) -> Vec<String>;

    /// How many there are (as many as `names`, without naming them).
    fn count(&self) -> usize {
        self.names().len()
    }

    /// Their values at a sample, appended to `out` (as many as `names`).
    fn values(&self, s: &SampleRef<'_>, out: &mut Vec<f64>);

    /// [`values`](Self::values) where only the columns `wanted[i]` are
    /// needed: the others may be NaN, unworked (a column choice of a large
    /// model saves working out what it does not write). As many values as
    /// `names` either way.
    fn values_wanted(&self, s: &SampleRef<'_>, wanted: &[bool], out: &mut Vec<f64>) {
        let _ = wanted;
        self.values(s, out);
    }
}

/// The reaction and effort columns of a model's CSV
/// (`docs/model-format.md`, "Output"): per joint and driver, in the order of
/// the file, `reaction:<name>.fx`, `.fy`, `.tau` (planar) or `.fx`, `.fy`,
/// `.fz`, `.tx`, `.ty`, `.tz` (spatial) — the constraint force `−Bᵀλ` its
/// rows put on its body ([`PlanarSystem::reaction`](mstar_model::planar::PlanarSystem::reaction),
/// [`SpatialSystem::reaction`](mstar_model::spatial::SpatialSystem::reaction)) — then per driver `effort:<name>` = `−λ`,
/// the force (N) or torque (N m) the driver applies along the coordinate
/// (or joint motion) it drives, positive in that coordinate's direction.
pub struct ReactionColumns<'a> {
    sys: &'a dyn ModelLookup,
    /// How many joints (drivers included) it has.
    joints: usize,
    /// `(joint index, first row)` of each driver.
    drivers: Vec<(usize, usize)>,
}

impl std::fmt::Debug for ReactionColumns<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ReactionColumns")
            .field("drivers", &self.drivers)
            .finish_non_exhaustive()
    }
}

impl<'a> ReactionColumns<'a> {
    /// The columns of `sys`.
    #[must_use]
    pub fn new(sys: &'a dyn ModelLookup) -> Self {
        let names = sys.joint_names();
        let joints = names.len();
        let drivers = names
            .into_iter()
            .enumerate()
            .filter(|(_, name)| sys.is_driver(name) == Some(true))
            .filter_map(|(i, name)| Some((i, sys.joint_rows(name)?.start)))
            .collect();
        Self {
            sys,
            joints,
            drivers,
        }
    }
}

impl Columns for ReactionColumns<'_> {
    fn names(&self) -> Vec<String> {
        let joints = self.sys.joint_names();
        let components = self.sys.reaction_components();
        let mut names: Vec<String> = joints
            .iter()
            .flat_map(|j| components.iter().map(move |c| format!("reaction:{j}.{c}")))
            .collect();
        names.extend(
            self.drivers
                .iter()
                .map(|&(i, _)| format!("effort:{}", joints[i])),
        );
        names
    }

    fn count(&self) -> usize {
        self.joints * self.sys.reaction_components().len() + self.drivers.len()
    }

    fn values(&self, s: &mstar_model::SampleRef<'_>, out: &mut Vec<f64>) {
        for i in 0..self.joints {
            self.sys.reaction_into(i, s.t, s.u, s.lambda, out);
        }
        out.extend(
            self.drivers
                .iter()
                .map(|&(_, row)| s.lambda.get(row).map_or(f64::NAN, |l| -l)),
        );
    }

    fn values_wanted(&self, s: &SampleRef<'_>, wanted: &[bool], out: &mut Vec<f64>) {
        let c = self.sys.reaction_components().len();
        for i in 0..self.joints {
            if wanted
                .get(i * c..(i + 1) * c)
                .is_none_or(|w| w.contains(&true))
            {
                self.sys.reaction_into(i, s.t, s.u, s.lambda, out);
            } else {
                out.extend(std::iter::repeat_n(f64::NAN, c));
            }
        }
        out.extend(
            self.drivers
                .iter()
                .map(|&(_, row)| s.lambda.get(row).map_or(f64::NAN, |l| -l)),
        );
    }
}

/// A sensor that names what the model does not have (a model built in
/// code: a file's sensors are checked where they are written).
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("sensor '{sensor}': {what}")]
pub struct SensorError {
    /// The sensor.
    pub sensor: String,
    /// What is wrong.
    pub what: String,
}

/// A body point as the model has it: the body's first coordinate and
/// whether it turns (`None`: the ground), and the point.
type Located = (Option<(usize, bool)>, [f64; 3]);

/// A [`Sensor`] with its names looked up.
#[derive(Clone, Debug)]
enum Resolved {
    Point(Motion, Located),
    AngularVelocity(usize),
    Orientation(usize),
    Distance(Located, Located),
    /// The joint's index in file order.
    Reaction(usize),
    /// The driver's first row.
    Effort(usize),
}

/// The `sensor:` columns of a model (`docs/model-format.md`, "`[[sensor]]`").
pub struct SensorColumns<'a> {
    sys: &'a dyn ModelLookup,
    sensors: Vec<(String, Resolved)>,
}

impl std::fmt::Debug for SensorColumns<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SensorColumns")
            .field("sensors", &self.sensors)
            .finish_non_exhaustive()
    }
}

impl<'a> SensorColumns<'a> {
    /// The columns of `sensors` on `sys`.
    ///
    /// # Errors
    /// A sensor that names a body, joint or driver `sys` does not have, or a
    /// point mass where a turning body is needed.
    pub fn new(sys: &'a dyn ModelLookup, sensors: &[Sensor]) -> Result<Self, SensorError> {
        let sensors = sensors
            .iter()
            .map(|s| {
                resolve(sys, &s.kind)
                    .map(|r| (s.name.clone(), r))
                    .map_err(|what| SensorError {
                        sensor: s.name.clone(),
                        what,
                    })
            })
            .collect::<Result<_, _>>()?;
        Ok(Self { sys, sensors })
    }

    /// The component suffixes of a sensor (empty: one column, `sensor:<name>`).
    fn components(&self, r: &Resolved) -> &'static [&'static str] {
        let planar = self.sys.dimension() == 2;
        match (r, planar) {
            (Resolved::Point(..), true) => &["x", "y"],
            (Resolved::Point(..), false) => &["x", "y", "z"],
            (Resolved::AngularVelocity(_), true) => &["w"],
            (Resolved::AngularVelocity(_), false) => &["wx", "wy", "wz"],
            (Resolved::Orientation(_), true) => &["theta"],
            (Resolved::Orientation(_), false) => &["roll", "pitch", "yaw"],
            (Resolved::Reaction(_), _) => self.sys.reaction_components(),
            (Resolved::Distance(..) | Resolved::Effort(_), _) => &[],
        }
    }

    /// The values of one sensor at `s`, appended to `out`.
    fn value(&self, r: &Resolved, s: &StateRef<'_>, out: &mut Vec<f64>) {
        let dim = self.sys.dimension();
        let frame = |x: usize, rigid: bool| self.sys.frame(x, rigid, s);
        match r {
            Resolved::Point(motion, (body, point)) => {
                let f = body.map_or(Frame::GROUND, |(x, rigid)| frame(x, rigid));
                out.extend_from_slice(&f.point(*motion, *point)[..dim]);
            }
            Resolved::AngularVelocity(x) => {
                let w = frame(*x, true).omega;
                out.extend_from_slice(if dim == 2 { &w[2..] } else { &w });
            }
            Resolved::Orientation(x) if dim == 2 => out.push(s.u[x + 2]),
            Resolved::Orientation(x) => out.extend(cardan_angles(&frame(*x, true).rotation)),
            Resolved::Distance(a, b) => {
                let at = |(body, point): &Located| {
                    let f = body.map_or(Frame::GROUND, |(x, rigid)| frame(x, rigid));
                    f.point(Motion::Position, *point)
                };
                let (p, q) = (at(a), at(b));
                let d = (0..3).map(|i| (p[i] - q[i]).powi(2)).sum::<f64>().sqrt();
                out.push(d);
            }
            Resolved::Reaction(joint) => self.sys.reaction_into(*joint, s.t, s.u, s.lambda, out),
            Resolved::Effort(row) => out.push(s.lambda.get(*row).map_or(f64::NAN, |l| -l)),
        }
    }
}

/// The names of `sensors` looked up in `sys`.
fn resolve(sys: &dyn ModelLookup, kind: &SensorKind) -> Result<Resolved, String> {
    let turning = |body: &str| match sys.body_coordinates(body) {
        Some((x, true)) => Ok(x),
        Some((_, false)) => Err(format!("'{body}' is a point mass, which does not turn")),
        None => Err(format!("no body is called '{body}'")),
    };
    let located = |p: &BodyPoint| -> Result<Located, String> {
        if p.body == "ground" {
            return Ok((None, p.point));
        }
        sys.body_coordinates(&p.body)
            .map(|b| (Some(b), p.point))
            .ok_or_else(|| format!("no body is called '{}'", p.body))
    };
    let joint = |name: &str| sys.joint_names().iter().position(|j| *j == name);
    Ok(match kind {
        SensorKind::Point { motion, at } if at.body != "ground" => {
            Resolved::Point(*motion, located(at)?)
        }
        SensorKind::Point { .. } => return Err("the ground does not move: name a body".into()),
        SensorKind::AngularVelocity { body } => Resolved::AngularVelocity(turning(body)?),
        SensorKind::Orientation { body } => Resolved::Orientation(turning(body)?),
        SensorKind::Distance { a, b } => Resolved::Distance(located(a)?, located(b)?),
        SensorKind::Reaction { joint: name } => Resolved::Reaction(
            joint(name).ok_or_else(|| format!("no joint or driver is called '{name}'"))?,
        ),
        SensorKind::Effort { driver } => match (sys.is_driver(driver), sys.joint_rows(driver)) {
            (Some(true), Some(rows)) => Resolved::Effort(rows.start),
            _ => return Err(format!("no driver is called '{driver}'")),
        },
        _ => return Err("a sensor type this version does not write".into()),
    })
}

impl Columns for SensorColumns<'_> {
    fn names(&self) -> Vec<String> {
        let mut names = Vec::new();
        for (name, r) in &self.sensors {
            match self.components(r) {
                [] => names.push(format!("sensor:{name}")),
                c => names.extend(c.iter().map(|c| format!("sensor:{name}.{c}"))),
            }
        }
        names
    }

    fn count(&self) -> usize {
        self.sensors
            .iter()
            .map(|(_, r)| self.components(r).len().max(1))
            .sum()
    }

    fn values(&self, s: &SampleRef<'_>, out: &mut Vec<f64>) {
        let state = s.state();
        for (_, r) in &self.sensors {
            self.value(r, &state, out);
        }
    }

    fn values_wanted(&self, s: &SampleRef<'_>, wanted: &[bool], out: &mut Vec<f64>) {
        let state = s.state();
        let mut at = 0;
        for (_, r) in &self.sensors {
            let c = self.components(r).len().max(1);
            if wanted.get(at..at + c).is_none_or(|w| w.contains(&true)) {
                self.value(r, &state, out);
            } else {
                out.extend(std::iter::repeat_n(f64::NAN, c));
            }
            at += c;
        }
    }
}

/// Every column a model file's run writes after the state: reactions and
/// efforts, then sensors.
#[derive(Debug)]
pub struct OutputColumns<'a> {
    reactions: ReactionColumns<'a>,
    sensors: SensorColumns<'a>,
}

impl<'a> OutputColumns<'a> {
    /// The columns of `sys` with `sensors`.
    ///
    /// # Errors
    /// As [`SensorColumns::new`].
    pub fn new(sys: &'a dyn ModelLookup, sensors: &[Sensor]) -> Result<Self, SensorError> {
        Ok(Self {
            reactions: ReactionColumns::new(sys),
            sensors: SensorColumns::new(sys, sensors)?,
        })
    }
}

impl OutputColumns<'_> {
    /// The sensors' columns alone.
    #[must_use]
    pub fn sensors(&self) -> &SensorColumns<'_> {
        &self.sensors
    }
}

impl Columns for OutputColumns<'_> {
    fn names(&self) -> Vec<String> {
        let mut names = self.reactions.names();
        names.extend(self.sensors.names());
        names
    }

    fn count(&self) -> usize {
        self.reactions.count() + self.sensors.count()
    }

    fn values(&self, s: &SampleRef<'_>, out: &mut Vec<f64>) {
        self.reactions.values(s, out);
        self.sensors.values(s, out);
    }

    fn values_wanted(&self, s: &SampleRef<'_>, wanted: &[bool], out: &mut Vec<f64>) {
        let (first, second) = wanted.split_at(self.reactions.count().min(wanted.len()));
        self.reactions.values_wanted(s, first, out);
        self.sensors.values_wanted(s, second, out);
    }
}

/// Columns chosen by name: their indices in the full header, in the
/// header's order.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Selection {
    indices: Vec<usize>,
}

/// A column pattern that selects nothing.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("'{pattern}' names no column{}", hint(.close))]
pub struct SelectionError {
    /// The pattern.
    pub pattern: String,
    /// Column names close to it.
    pub close: Vec<String>,
}

fn hint(close: &[String]) -> String {
    if close.is_empty() {
        " (names are t, u:<coordinate>, v:…, a:…, lambda:<row>, reaction:<joint>.<component>, effort:<driver>, sensor:<name>…, energy, iterations, residual, constraint; `*` matches any text)".to_string()
    } else {
        format!(" (did you mean {}?)", close.join(", "))
    }
}

impl Selection {
    /// The columns of `names` (the full header) that match any of
    /// `patterns` (`*` matches any run of characters, `:` and `.`
    /// included).
    ///
    /// # Errors
    /// The first pattern that matches no column, with the closest names.
    pub fn new(names: &[String], patterns: &[String]) -> Result<Self, SelectionError> {
        let mut chosen = vec![false; names.len()];
        for pattern in patterns {
            let mut any = false;
            for (c, name) in chosen.iter_mut().zip(names) {
                if glob(pattern, name) {
                    *c = true;
                    any = true;
                }
            }
            if !any {
                return Err(SelectionError {
                    pattern: pattern.clone(),
                    close: closest(pattern, names),
                });
            }
        }
        let indices = (0..names.len()).filter(|&i| chosen[i]).collect();
        Ok(Self { indices })
    }

    /// The chosen indices, ascending.
    #[must_use]
    pub fn indices(&self) -> &[usize] {
        &self.indices
    }

    /// How many columns are chosen.
    #[must_use]
    pub fn len(&self) -> usize {
        self.indices.len()
    }

    /// Whether none is (never, for a [`Selection::new`]).
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.indices.is_empty()
    }

    /// Whether any chosen index is at or after `first`.
    #[must_use]
    pub fn reaches(&self, first: usize) -> bool {
        self.indices.last().is_some_and(|&i| i >= first)
    }
}

/// Up to three names of `names` closest to `pattern` (Jaro–Winkler ≥ 0.8).
fn closest(pattern: &str, names: &[String]) -> Vec<String> {
    let mut scored: Vec<(f64, &String)> = names
        .iter()
        .map(|n| (strsim::jaro_winkler(pattern, n), n))
        .filter(|(s, _)| *s >= 0.8)
        .collect();
    scored.sort_by(|a, b| b.0.total_cmp(&a.0));
    scored.into_iter().take(3).map(|(_, n)| n.clone()).collect()
}

/// Whether `name` matches `pattern`, where `*` matches any run of
/// characters (none included) and every other character itself.
#[must_use]
pub fn glob(pattern: &str, name: &str) -> bool {
    // Bytes of UTF-8: `*` is never part of another character's bytes, and
    // equal characters are equal bytes.
    let (p, n) = (pattern.as_bytes(), name.as_bytes());
    if !p.contains(&b'*') {
        return p == n;
    }
    // Greedy matching with one back-track point (the last `*`).
    let (mut i, mut j) = (0, 0);
    let mut star: Option<(usize, usize)> = None;
    while j < n.len() {
        if i < p.len() && p[i] == b'*' {
            star = Some((i, j));
            i += 1;
        } else if i < p.len() && p[i] == n[j] {
            i += 1;
            j += 1;
        } else if let Some((si, sj)) = star {
            i = si + 1;
            j = sj + 1;
            star = Some((si, sj + 1));
        } else {
            return false;
        }
    }
    p[i..].iter().all(|&c| c == b'*')
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn globs_match_as_documented() {
        assert!(glob("reaction:O2.*", "reaction:O2.fx"));
        assert!(!glob("reaction:O2.*", "reaction:O23.fx"));
        assert!(glob("*", ""));
        assert!(glob("u:*.theta", "u:crank.theta"));
        assert!(!glob("u:*.theta", "u:crank.x"));
        assert!(glob("a*b*c", "aXbYbZc"));
        assert!(!glob("t", "theta"));
        assert!(glob("sensor:é*", "sensor:éa"));
        assert!(!glob("sensor:é*", "sensor:ea"));
        assert!(glob("t", "t"));
    }

    #[test]
    fn a_selection_keeps_header_order_and_names_misses() {
        let names: Vec<String> = ["t", "u:a.x", "u:a.y", "sensor:tip.x"]
            .map(String::from)
            .to_vec();
        let s = Selection::new(&names, &["sensor:*".into(), "t".into()]).expect("matches");
        assert_eq!(s.indices(), &[0, 3]);
        assert!(s.reaches(3) && !s.reaches(4));
        let e = Selection::new(&names, &["sensor:tp.x".into()]).expect_err("no match");
        assert_eq!(e.close, vec!["sensor:tip.x".to_string()]);
    }
}
