//! A spatial model in the picture's plane: every point projected by one of
//! four fixed [`Projection`]s (`--view`), the bodies drawn as the planar
//! scene draws them from the projected points.

use mstar::model::spatial::{SpatialAttachment, SpatialSketch, rotation_matrix};
use mstar::planar::{Attachment, Sketch, SketchBody, SketchElement};

use super::figure::{Face, Figure};
use super::geometry::{Point, Shape, whole_body};
use super::solid::Solid;

/// How far the oblique view draws the global y axis, per metre.
pub const OBLIQUE_DEPTH: f64 = 0.5;
/// The angle of the oblique view's y axis above the picture's x axis, degrees.
pub const OBLIQUE_ANGLE_DEG: f64 = 30.0;

/// Which global axes go right and up in the picture (`--view`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum Projection {
    /// Oblique (cabinet): x right, z up, y (into the picture) drawn at half
    /// length, 30° above the horizontal: seen from the front, a little above
    /// and to the right.
    #[default]
    Oblique,
    /// From the front (looking along +y): x right, z up.
    Xz,
    /// From the side (looking along −x): y right, z up.
    Yz,
    /// From above (looking along −z): x right, y up.
    Xy,
}

impl Projection {
    /// A global point `[x, y, z]` in the picture's plane `[right, up]`, m.
    #[must_use]
    pub fn project(self, p: [f64; 3]) -> Point {
        let [x, y, z] = p;
        match self {
            Self::Oblique => {
                let (s, c) = OBLIQUE_ANGLE_DEG.to_radians().sin_cos();
                [x + OBLIQUE_DEPTH * c * y, z + OBLIQUE_DEPTH * s * y]
            }
            Self::Xz => [x, z],
            Self::Yz => [y, z],
            Self::Xy => [x, y],
        }
    }

    /// The unit direction of the lines of sight, into the picture: every
    /// point along it projects to the same place (for the oblique view,
    /// `(−½ cos 30°, 1, −½ sin 30°)` normalized).
    #[must_use]
    pub fn into_picture(self) -> [f64; 3] {
        match self {
            Self::Oblique => {
                let (s, c) = OBLIQUE_ANGLE_DEG.to_radians().sin_cos();
                let d = [-OBLIQUE_DEPTH * c, 1.0, -OBLIQUE_DEPTH * s];
                let n = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                d.map(|x| x / n)
            }
            Self::Xz => [0.0, 1.0, 0.0],
            Self::Yz => [-1.0, 0.0, 0.0],
            Self::Xy => [0.0, 0.0, -1.0],
        }
    }

    /// The unit light direction (toward the light) of the shaded boxes:
    /// from the viewer's side, above and to the left.
    fn light(self) -> [f64; 3] {
        let (right, up) = match self {
            Self::Xy => ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0]),
            Self::Yz => ([0.0, 1.0, 0.0], [0.0, 0.0, 1.0]),
            Self::Oblique | Self::Xz => ([1.0, 0.0, 0.0], [0.0, 0.0, 1.0]),
        };
        let d = self.into_picture();
        let l: [f64; 3] = std::array::from_fn(|k| -d[k] + 0.6 * up[k] - 0.4 * right[k]);
        let n = dot(l, l).sqrt();
        l.map(|x| x / n)
    }
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The box's faces as corner indices (bit `i` of a corner: the sign of half
/// axis `i`, set for +) and each face's outward normal: half axis and sign.
const FACES: [([usize; 4], usize, f64); 6] = [
    ([0, 2, 6, 4], 0, -1.0),
    ([1, 5, 7, 3], 0, 1.0),
    ([0, 4, 5, 1], 1, -1.0),
    ([2, 3, 7, 6], 1, 1.0),
    ([0, 1, 3, 2], 2, -1.0),
    ([4, 6, 7, 5], 2, 1.0),
];

/// A spatial model seen through a [`Projection`].
#[derive(Clone, Debug)]
pub struct SpatialFigure {
    model: SpatialSketch,
    projection: Projection,
    /// The bodies and elements for the scene: ground points projected,
    /// kinds in the planar drawing's words.
    sketch: Sketch,
    /// Per body, the distinct local points where joints and loads attach.
    points: Vec<Vec<[f64; 3]>>,
    /// Per body, its solid (none: stick figures only).
    solids: Vec<Solid>,
}

impl SpatialFigure {
    /// The figure of a spatial model's sketch seen through `projection`.
    #[must_use]
    pub fn new(model: SpatialSketch, projection: Projection) -> Self {
        let bodies = model
            .bodies
            .iter()
            .map(|b| SketchBody {
                name: b.name.clone(),
                x: b.x,
                rigid: b.rigid,
                points: Vec::new(),
            })
            .collect();
        let elements: Vec<SketchElement> = model
            .elements
            .iter()
            .map(|e| SketchElement {
                name: e.name.clone(),
                kind: planar_kind(e.kind, e.driver),
                ends: e.ends.map(|end| match end {
                    SpatialAttachment::Ground(p) => Attachment::Ground(projection.project(p)),
                    SpatialAttachment::Body { body, .. } => Attachment::Body {
                        body,
                        local: [0.0; 2],
                    },
                }),
                axis: None,
            })
            .collect();
        let mut points: Vec<Vec<[f64; 3]>> = vec![Vec::new(); model.bodies.len()];
        for (e, drawn) in model.elements.iter().zip(&elements) {
            if whole_body(drawn.kind) {
                continue;
            }
            for end in &e.ends {
                if let SpatialAttachment::Body { body, local } = *end
                    && let Some(list) = points.get_mut(body)
                    && !list.contains(&local)
                {
                    list.push(local);
                }
            }
        }
        Self {
            model,
            projection,
            sketch: Sketch { bodies, elements },
            points,
            solids: Vec::new(),
        }
    }

    /// The same figure with each rigid body drawn as its solid too: shaded
    /// faces, far ones first, under the stick figure.
    #[must_use]
    pub fn with_solids(mut self, solids: Vec<Solid>) -> Self {
        self.solids = solids;
        self
    }

    /// The rotation matrix of the rigid body whose coordinates start at `x`,
    /// its Euler parameters normalized (interpolated rows are shorter);
    /// none for a row of zeros or NaN.
    fn turn(&self, x: usize, u: &[f64]) -> Option<[[f64; 3]; 3]> {
        let p = [u[x + 3], u[x + 4], u[x + 5], u[x + 6]];
        let n = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2] + p[3] * p[3]).sqrt();
        (n > 0.0).then(|| rotation_matrix(p.map(|e| e / n)))
    }

    /// The faces of body `body`'s box that face the viewer at `u`.
    fn body_faces(&self, body: usize, solid: &Solid, u: &[f64], out: &mut Vec<Face>) {
        let x = self.model.bodies[body].x;
        let r = [u[x], u[x + 1], u[x + 2]];
        let Some(a) = self.turn(x, u) else {
            return;
        };
        let turn = |v: [f64; 3]| -> [f64; 3] { std::array::from_fn(|i| dot(a[i], v)) };
        let corners = solid.corners().map(|c| {
            let g = turn(c);
            std::array::from_fn::<f64, 3, _>(|k| r[k] + g[k])
        });
        let (d, light) = (self.projection.into_picture(), self.projection.light());
        for (face, axis, sign) in FACES {
            let h = turn(solid.half_axes[axis]);
            let len = dot(h, h).sqrt();
            if len == 0.0 {
                continue;
            }
            let normal = h.map(|v| sign * v / len);
            if dot(normal, d) >= 0.0 {
                continue;
            }
            let centre: [f64; 3] =
                std::array::from_fn(|k| face.iter().map(|&c| corners[c][k]).sum::<f64>() / 4.0);
            out.push(Face {
                body,
                corners: face
                    .iter()
                    .map(|&c| self.projection.project(corners[c]))
                    .collect(),
                depth: dot(centre, d),
                brightness: 0.3 + 0.7 * dot(normal, light).max(0.0),
            });
        }
    }
}

/// A spatial element's kind as the planar drawing names the same mark.
fn planar_kind(kind: &'static str, driver: bool) -> &'static str {
    match kind {
        _ if driver => "driver",
        "rotational spring-damper" => "rotational-spring-damper",
        other => other,
    }
}

impl Figure for SpatialFigure {
    fn sketch(&self) -> &Sketch {
        &self.sketch
    }

    fn end(&self, element: usize, side: usize, u: &[f64]) -> Point {
        let at = &self.model.elements[element].ends[side];
        self.projection.project(self.model.position(at, u))
    }

    fn centre(&self, body: usize, u: &[f64]) -> Point {
        let x = self.model.bodies[body].x;
        self.projection.project([u[x], u[x + 1], u[x + 2]])
    }

    /// Lines from the centre of mass to each of the body's points, in one
    /// polyline (`p₁ c p₂ c p₃ …`: a bar through the centre for two points);
    /// a body attached only at its centre is a square in its own x-y plane,
    /// turning with it.
    fn outline(&self, body: usize, u: &[f64], half: f64) -> Shape {
        let at = |local: [f64; 3]| {
            let p = SpatialAttachment::Body { body, local };
            self.projection.project(self.model.position(&p, u))
        };
        let Some((first, rest)) = self.points[body]
            .split_first()
            .filter(|_| self.points[body].iter().any(|p| *p != [0.0; 3]))
        else {
            let h = half;
            let square = [[-h, -h, 0.0], [h, -h, 0.0], [h, h, 0.0], [-h, h, 0.0]];
            return Shape::Polygon(square.map(at).to_vec());
        };
        let centre = self.centre(body, u);
        let mut line = vec![at(*first)];
        for &p in rest {
            line.extend([centre, at(p)]);
        }
        if rest.is_empty() {
            line.push(centre);
        }
        Shape::Line(line)
    }

    fn angle(&self, _: &Attachment, _: &[f64]) -> f64 {
        0.0
    }

    fn faces(&self, u: &[f64]) -> Vec<Face> {
        let mut out = Vec::new();
        for (body, solid) in self.solids.iter().enumerate() {
            if self.model.bodies.get(body).is_some_and(|b| b.rigid) {
                self.body_faces(body, solid, u, &mut out);
            }
        }
        out
    }

    /// A box with half axes `g_i` (global) reaches `Σ_i |P g_i|` from its
    /// centre along each picture axis, exactly (`P`, the projection, is
    /// linear).
    fn reach(&self, body: usize, u: &[f64]) -> Point {
        let (Some(solid), Some(b)) = (self.solids.get(body), self.model.bodies.get(body)) else {
            return [0.0; 2];
        };
        let Some(a) = self.turn(b.x, u).filter(|_| b.rigid) else {
            return [0.0; 2];
        };
        solid.half_axes.iter().fold([0.0; 2], |r, h| {
            let g: [f64; 3] = std::array::from_fn(|i| dot(a[i], *h));
            let p = self.projection.project(g);
            [r[0] + p[0].abs(), r[1] + p[1].abs()]
        })
    }

    fn columns(&self) -> Vec<(String, usize)> {
        let mut out = Vec::new();
        for body in &self.model.bodies {
            let axes: &[&str] = if body.rigid {
                &["x", "y", "z", "e0", "e1", "e2", "e3"]
            } else {
                &["x", "y", "z"]
            };
            for (k, axis) in axes.iter().enumerate() {
                out.push((format!("u:{}.{axis}", body.name), body.x + k));
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mstar::model::spatial::{
        Attach, JointSpec, JointType, SpatialBody, SpatialBuilder, SpatialInertia, euler_parameters,
    };

    fn close(p: Point, q: Point) -> bool {
        (p[0] - q[0]).abs() < 1e-12 && (p[1] - q[1]).abs() < 1e-12
    }

    #[test]
    fn each_view_takes_its_axes() {
        let p = [1.0, 2.0, 3.0];
        assert_eq!(Projection::Xz.project(p), [1.0, 3.0]);
        assert_eq!(Projection::Yz.project(p), [2.0, 3.0]);
        assert_eq!(Projection::Xy.project(p), [1.0, 2.0]);
        // y = 2 m drawn 1 m long at 30°: (√3/2, 1/2) m.
        let oblique = Projection::Oblique.project(p);
        assert!(close(oblique, [1.0 + 0.75f64.sqrt(), 3.5]), "{oblique:?}");
        assert_eq!(Projection::default(), Projection::Oblique);
    }

    /// A bar along its body x axis, centre at (1, 2, 3), turned 90° about
    /// global z, on a ball joint at its local (−0.5, 0, 0), with a point
    /// mass on a rod at its local (0.5, 0, 0).
    fn bar() -> (SpatialFigure, Vec<f64>) {
        let mut b = SpatialBuilder::new();
        let bar = b.body(
            "bar",
            SpatialBody {
                mass: 1.0,
                inertia: SpatialInertia::Principal([0.001, 0.1, 0.1]),
                position: [1.0, 2.0, 3.0],
                orientation: euler_parameters([0.0, 0.0, 1.0], std::f64::consts::FRAC_PI_2),
                velocity: [0.0; 3],
                angular_velocity: [0.0; 3],
            },
        );
        let spec = |kind, bodies, points| JointSpec {
            kind,
            bodies,
            points,
            axes: [[0.0, 0.0, 1.0]; 2],
            length: None,
        };
        b.joint(
            "ball",
            spec(
                JointType::Spherical,
                [Attach::Ground, Attach::Body(bar)],
                [[1.0, 1.5, 3.0], [-0.5, 0.0, 0.0]],
            ),
        );
        let sys = b.build().expect("valid");
        let u = sys.initial_position();
        (SpatialFigure::new(sys.sketch(), Projection::Xy), u)
    }

    /// A cube of half side 0.5 m at (1, 2, 3), unturned, as a solid.
    fn cube(projection: Projection) -> (SpatialFigure, Vec<f64>) {
        let (figure, _) = bar();
        let h = [[0.5, 0.0, 0.0], [0.0, 0.5, 0.0], [0.0, 0.0, 0.5]];
        let mut figure = figure.with_solids(vec![Solid { half_axes: h }]);
        figure.projection = projection;
        (figure, vec![1.0, 2.0, 3.0, 1.0, 0.0, 0.0, 0.0])
    }

    /// Seen from the front (`xz`, looking along +y) a cube shows its −y face
    /// only: the square x ∈ [0.5, 1.5], z ∈ [2.5, 3.5], lit by
    /// l = (−0.4, −1, 0.6)/√1.52 at 0.3 + 0.7 (n·l) = 0.3 + 0.7/√1.52.
    /// Obliquely (from the front, above, right) it shows −y, +x and +z.
    #[test]
    fn a_solid_shows_the_faces_toward_the_viewer_lit_by_their_angle() {
        let (front, u) = cube(Projection::Xz);
        let faces = front.faces(&u);
        assert_eq!(faces.len(), 1, "{faces:?}");
        let mut corners = faces[0].corners.clone();
        corners.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
        let want = [[0.5, 2.5], [0.5, 3.5], [1.5, 2.5], [1.5, 3.5]];
        for (p, q) in corners.iter().zip(want) {
            assert!(close(*p, q), "{corners:?}");
        }
        let lit = 0.3 + 0.7 / 1.52f64.sqrt();
        assert!((faces[0].brightness - lit).abs() < 1e-12, "{faces:?}");
        // Depth along +y: the face's centre at y = 1.5.
        assert!((faces[0].depth - 1.5).abs() < 1e-12);
        let (oblique, u) = cube(Projection::Oblique);
        let faces = oblique.faces(&u);
        assert_eq!(faces.len(), 3, "{faces:?}");
        // The top face (+z, centre (1, 2, 3.5)) and the right face (+x,
        // centre (1.5, 2, 3)) in the picture: their centres projected.
        let centre = |f: &Face| {
            let n = f.corners.len() as f64;
            let s = f
                .corners
                .iter()
                .fold([0.0, 0.0], |a, p| [a[0] + p[0], a[1] + p[1]]);
            [s[0] / n, s[1] / n]
        };
        for c in [[1.0, 2.0, 3.5], [1.5, 2.0, 3.0], [1.0, 1.5, 3.0]] {
            let p = Projection::Oblique.project(c);
            assert!(faces.iter().any(|f| close(centre(f), p)), "{c:?}");
        }
        // Its reach: 0.5 m each way from the front; obliquely the y half
        // axis adds 0.5 (½ cos 30°, ½ sin 30°) m.
        assert!(close(front.reach(0, &u), [0.5, 0.5]));
        let c = 0.5 * 30f64.to_radians().cos();
        assert!(close(oblique.reach(0, &u), [0.5 + 0.5 * c, 0.5 + 0.125]));
    }

    #[test]
    fn body_points_turn_with_the_body_and_are_projected() {
        let (figure, u) = bar();
        // The ball end at (1, 1.5, 3): seen from above, (1, 1.5).
        assert!(close(figure.end(0, 1, &u), [1.0, 1.5]));
        assert!(close(figure.end(0, 0, &u), [1.0, 1.5]));
        assert!(close(figure.centre(0, &u), [1.0, 2.0]));
        // One point: a line from it to the centre.
        let Shape::Line(line) = figure.outline(0, &u, 0.1) else {
            panic!("a line");
        };
        assert!(
            close(line[0], [1.0, 1.5]) && close(line[1], [1.0, 2.0]),
            "{line:?}"
        );
        assert_eq!(figure.sketch().elements[0].kind, "spherical");
        assert_eq!(
            figure.sketch().elements[0].ends[0],
            Attachment::Ground([1.0, 1.5])
        );
        let columns: Vec<String> = figure.columns().into_iter().map(|c| c.0).collect();
        assert_eq!(columns[0], "u:bar.x");
        assert_eq!(columns[6], "u:bar.e3");
    }
}
