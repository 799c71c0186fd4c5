//! The plane geometry under every drawing: points, shapes, convex hulls,
//! and which elements attach at a body as a whole. A leaf: the [`Figure`]
//! of a model and the [`Scene`] it is drawn in both build on it.
//!
//! [`Figure`]: super::figure::Figure
//! [`Scene`]: super::scene::Scene

/// A point `[x, y]`: world metres, or pixels (x right, y down).
pub type Point = [f64; 2];

/// A shape in pixels.
#[derive(Clone, Debug, PartialEq)]
pub enum Shape {
    /// An open polyline.
    Line(Vec<Point>),
    /// A closed polygon.
    Polygon(Vec<Point>),
    /// A circle: centre and radius, px.
    Circle(Point, f64),
    /// An axis-aligned square: centre and half side, px.
    Square(Point, f64),
}

impl Shape {
    /// The same shape with every point mapped by `f` (world to pixels).
    #[must_use]
    pub fn map(self, f: impl Fn(Point) -> Point) -> Self {
        match self {
            Self::Line(p) => Self::Line(p.into_iter().map(f).collect()),
            Self::Polygon(p) => Self::Polygon(p.into_iter().map(f).collect()),
            Self::Circle(c, r) => Self::Circle(f(c), r),
            Self::Square(c, h) => Self::Square(f(c), h),
        }
    }

    /// Its points (a circle's or square's centre).
    #[must_use]
    pub fn points(&self) -> &[Point] {
        match self {
            Self::Line(p) | Self::Polygon(p) => p,
            Self::Circle(c, _) | Self::Square(c, _) => std::slice::from_ref(c),
        }
    }
}

/// The convex hull of `points`, counter-clockwise (Andrew's monotone chain);
/// collinear or repeated points give the two ends, a single point itself.
#[must_use]
pub fn hull(points: &[Point]) -> Vec<Point> {
    let mut p = points.to_vec();
    p.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
    p.dedup();
    if p.len() < 3 {
        return p;
    }
    let cross = |o: Point, a: Point, b: Point| {
        (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
    };
    let mut out: Vec<Point> = Vec::with_capacity(2 * p.len());
    for pass in [p.clone(), p.iter().rev().copied().collect()] {
        let start = out.len();
        for q in pass {
            while out.len() >= start + 2 && cross(out[out.len() - 2], out[out.len() - 1], q) <= 0.0
            {
                out.pop();
            }
            out.push(q);
        }
        out.pop();
    }
    out
}

/// The elements that attach at a body as a whole (its centre of mass), not
/// at a point of its outline.
pub fn whole_body(kind: &str) -> bool {
    matches!(kind, "driver" | "torque" | "rotational-spring-damper")
}
