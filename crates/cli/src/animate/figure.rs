//! A model placed in the picture's plane: the [`Figure`] trait that the
//! [`Scene`](super::scene::Scene) draws, and its planar implementation. A
//! planar model lies in the picture's plane already; a spatial one gets there
//! through a projection (`spatial.rs`).

use mstar::planar::{Attachment, Sketch};

use super::geometry::{Point, Shape, hull, whole_body};

/// What the scene needs of a model: its bodies and elements, and where each
/// of them is in the picture's plane (world metres, y up) at a state `u`.
pub trait Figure {
    /// The bodies (names, coordinates, rigid or not) and elements (kinds,
    /// ends). Its ground points lie in the picture's plane; where a body's
    /// attachment lies is [`Figure::end`]'s business (a spatial figure
    /// leaves the planar `local` offsets at zero).
    fn sketch(&self) -> &Sketch;

    /// Where end `side` (0 or 1) of the `element`-th element is at `u`.
    fn end(&self, element: usize, side: usize, u: &[f64]) -> Point;

    /// Where the `body`-th body's centre of mass is at `u`.
    fn centre(&self, body: usize, u: &[f64]) -> Point;

    /// The `body`-th (rigid) body's shape at `u`, in world metres; a body
    /// without points is a square of half side `half`, m.
    fn outline(&self, body: usize, u: &[f64], half: f64) -> Shape;

    /// The angle an attachment's body has turned by in the picture's plane
    /// (0 for the ground, point masses and bodies that turn out of it).
    fn angle(&self, at: &Attachment, u: &[f64]) -> f64;

    /// The results columns the drawing reads, each `u:<body>.<axis>` with
    /// its index in `u`.
    fn columns(&self) -> Vec<(String, usize)>;

    /// The faces of the bodies' solids that face the viewer at `u`, in any
    /// order (the scene sorts them by depth); none for a planar model.
    fn faces(&self, _u: &[f64]) -> Vec<Face> {
        Vec::new()
    }

    /// How far the `body`-th body's solid reaches from its centre of mass at
    /// `u` along the picture's right and up, m (0 without a solid): the
    /// view's fit over a long run, without working out every face.
    fn reach(&self, _body: usize, _u: &[f64]) -> Point {
        [0.0; 2]
    }
}

/// One face of a body's solid in the picture's plane.
#[derive(Clone, Debug, PartialEq)]
pub struct Face {
    /// The body.
    pub body: usize,
    /// Its corners, world metres in the picture's plane.
    pub corners: Vec<Point>,
    /// How far its centre lies behind the picture, m (larger: farther).
    pub depth: f64,
    /// Its brightness in the light, 0 to 1 (Lambert).
    pub brightness: f64,
}

/// A planar model: its sketch as it is, each rigid body drawn through the
/// hull of its joint and load points.
#[derive(Clone, Debug)]
pub struct PlanarFigure {
    sketch: Sketch,
    /// Per body, the local outline: the hull of its joint and load points.
    outlines: Vec<Vec<Point>>,
}

impl PlanarFigure {
    /// The figure of a planar model's sketch.
    #[must_use]
    pub fn new(sketch: Sketch) -> Self {
        let mut local: Vec<Vec<Point>> = vec![Vec::new(); sketch.bodies.len()];
        for e in sketch.elements.iter().filter(|e| !whole_body(e.kind)) {
            for end in &e.ends {
                if let Attachment::Body { body, local: p } = *end
                    && let Some(points) = local.get_mut(body)
                {
                    points.push(p);
                }
            }
        }
        let outlines = local.iter().map(|p| hull(p)).collect();
        Self { sketch, outlines }
    }
}

impl Figure for PlanarFigure {
    fn sketch(&self) -> &Sketch {
        &self.sketch
    }

    fn end(&self, element: usize, side: usize, u: &[f64]) -> Point {
        self.sketch
            .position(&self.sketch.elements[element].ends[side], u)
    }

    fn centre(&self, body: usize, u: &[f64]) -> Point {
        let x = self.sketch.bodies[body].x;
        [u[x], u[x + 1]]
    }

    /// A bar for two points (or from a single point to the centre of mass),
    /// a polygon for more; a body attached only at its centre is a small
    /// square turning with it.
    fn outline(&self, body: usize, u: &[f64], half: f64) -> Shape {
        let at = |local: Point| self.sketch.position(&Attachment::Body { body, local }, u);
        let h = half;
        match self.outlines[body].as_slice() {
            [] | [[0.0, 0.0]] => {
                Shape::Polygon([[-h, -h], [h, -h], [h, h], [-h, h]].map(at).to_vec())
            }
            [p] => Shape::Line(vec![at(*p), at([0.0, 0.0])]),
            outline @ [_, _] => Shape::Line(outline.iter().map(|&p| at(p)).collect()),
            outline => Shape::Polygon(outline.iter().map(|&p| at(p)).collect()),
        }
    }

    fn angle(&self, at: &Attachment, u: &[f64]) -> f64 {
        match *at {
            Attachment::Body { body, .. } => self
                .sketch
                .bodies
                .get(body)
                .filter(|b| b.rigid)
                .map_or(0.0, |b| u[b.x + 2]),
            Attachment::Ground(_) => 0.0,
        }
    }

    fn columns(&self) -> Vec<(String, usize)> {
        let mut out = Vec::new();
        for body in &self.sketch.bodies {
            let axes: &[&str] = if body.rigid {
                &["x", "y", "theta"]
            } else {
                &["x", "y"]
            };
            for (k, axis) in axes.iter().enumerate() {
                out.push((format!("u:{}.{axis}", body.name), body.x + k));
            }
        }
        out
    }
}
