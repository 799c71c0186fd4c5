//! `[[sensor]]`: quantities to write beside the state (`docs/model-format.md`,
//! "`[[sensor]]`"), read the same way in planar and spatial files. Sensors
//! are read after every other element, so they may name any body, joint or
//! driver of the file.

use mstar_model::sensor::{BodyPoint, Motion, Sensor, SensorKind};

use super::FileError;
use super::bodies::{GROUND, Placed, Reader};
use super::fields::{Fields, list, numbers, string, two_names};
use super::node::{Entry, Node};

/// The sensor types, as `type` names them.
pub(crate) const SENSOR_TYPES: [&str; 8] = [
    "position",
    "velocity",
    "acceleration",
    "angular-velocity",
    "orientation",
    "distance",
    "reaction",
    "effort",
];

impl<'a, I: Copy, P: Copy> Reader<'a, Placed<I, P>> {
    /// A `[[sensor]]` of a model of dimension `D` (2 or 3).
    pub(crate) fn sensor<const D: usize>(
        &mut self,
        node: &'a Node,
        what: String,
    ) -> Result<Sensor, FileError> {
        let (mut f, name, kind) = self.typed(node, what, "sensor", &SENSOR_TYPES)?;
        let motion = match kind {
            "position" => Some(Motion::Position),
            "velocity" => Some(Motion::Velocity),
            "acceleration" => Some(Motion::Acceleration),
            _ => None,
        };
        let kind = match (kind, motion) {
            (_, Some(motion)) => {
                let at = self.body_point::<D>(&mut f)?;
                f.finish(&["name", "type", "body", "point"])?;
                SensorKind::Point { motion, at }
            }
            ("distance", _) => {
                let [a, b] = self.two_points::<D>(&mut f)?;
                f.finish(&["name", "type", "bodies", "points"])?;
                SensorKind::Distance { a, b }
            }
            ("reaction", _) => SensorKind::Reaction {
                joint: self.element(&mut f, "joint", &["joint", "driver"])?,
            },
            ("effort", _) => SensorKind::Effort {
                driver: self.element(&mut f, "driver", &["driver"])?,
            },
            (turning, _) => {
                let body = self.rigid_body(&mut f, turning)?;
                f.finish(&["name", "type", "body"])?;
                if turning == "orientation" {
                    SensorKind::Orientation { body }
                } else {
                    SensorKind::AngularVelocity { body }
                }
            }
        };
        Ok(Sensor { name, kind })
    }

    /// `body` (not the ground) and `point` (body axes, default the centre of
    /// mass; only the centre for a point mass).
    fn body_point<const D: usize>(&self, f: &mut Fields<'a>) -> Result<BodyPoint, FileError> {
        let placed = self.bodies.body_of(f, "body")?;
        let body = f.required("body", string)?.to_string();
        let point = f.optional("point", numbers::<D>)?.unwrap_or([0.0; D]);
        if !placed.rigid && point.iter().any(|&x| x != 0.0) {
            let e = f.read_entry("point")?;
            return Err(f.bad(
                e,
                "a point mass has no body axes: leave `point` out (its own position)",
            ));
        }
        Ok(BodyPoint {
            body,
            point: widened(point),
        })
    }

    /// `bodies = [a, b]` (either may be the ground) and `points` (body axes,
    /// global for the ground; default each body's centre and the origin).
    fn two_points<const D: usize>(&self, f: &mut Fields<'a>) -> Result<[BodyPoint; 2], FileError> {
        let names = f.required("bodies", two_names)?;
        let e = f.read_entry("bodies")?;
        let mut rigid = [false; 2];
        for (k, name) in names.iter().enumerate() {
            if *name != GROUND {
                let placed = self
                    .bodies
                    .get(name)
                    .ok_or_else(|| f.bad(e, self.bodies.unknown(name)))?;
                rigid[k] = placed.rigid;
            }
        }
        let points = f
            .optional("points", |n: &Node| {
                let items = list(n)?;
                if items.len() != 2 {
                    return Err(format!("expected two points, found {} items", items.len()));
                }
                Ok([numbers::<D>(&items[0])?, numbers::<D>(&items[1])?])
            })?
            .unwrap_or([[0.0; D]; 2]);
        if let Some(k) = (0..2).find(|&k| names[k] != GROUND && !rigid[k] && points[k] != [0.0; D])
        {
            let e = f.read_entry("points")?;
            return Err(f.bad(
                e,
                format!(
                    "'{}' is a point mass, which has no body axes: give [0, …] as its point",
                    names[k].escape_debug()
                ),
            ));
        }
        Ok([0, 1].map(|k| BodyPoint {
            body: names[k].to_string(),
            point: widened(points[k]),
        }))
    }

    /// `body`, which must be rigid (`kind` names the sensor type in the
    /// message).
    fn rigid_body(&self, f: &mut Fields<'a>, kind: &str) -> Result<String, FileError> {
        let placed = self.bodies.body_of(f, "body")?;
        let e = f.read_entry("body")?;
        let body = f.required("body", string)?.to_string();
        if !placed.rigid {
            return Err(f.bad(
                e,
                format!("a point mass does not turn: an {kind} sensor needs a [[body]]"),
            ));
        }
        Ok(body)
    }

    /// The key `key`: the name of an element of one of the `kinds`.
    fn element(&self, f: &mut Fields<'a>, key: &str, kinds: &[&str]) -> Result<String, FileError> {
        let name = f.required(key, string)?.to_string();
        let e: &Entry = f.read_entry(key)?;
        let found = self.kind_of(&name);
        if !found.is_some_and(|k| kinds.contains(&k)) {
            let known = self.names_of(kinds);
            let was = found.map_or(String::new(), |k| {
                format!(" ('{}' is a {k})", name.escape_debug())
            });
            return Err(f.bad(
                e,
                format!(
                    "no {} is called '{}'{was} (known: {})",
                    kinds.join(" or "),
                    name.escape_debug(),
                    if known.is_empty() {
                        "none".to_string()
                    } else {
                        known.join(", ")
                    }
                ),
            ));
        }
        f.finish(&["name", "type", key])?;
        Ok(name)
    }
}

/// A point of `D` ≤ 3 numbers as three (`z = 0` in the plane).
fn widened<const D: usize>(p: [f64; D]) -> [f64; 3] {
    let mut out = [0.0; 3];
    out[..D].copy_from_slice(&p);
    out
}
