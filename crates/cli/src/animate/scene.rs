//! What a frame shows, in pixels: the geometry both the GIF and the HTML page
//! draw. [`Scene`] turns a state `u` into [`Item`]s (polylines, polygons,
//! circles, squares) in a [`View`] fitted once over the whole run, so every
//! frame has the same items in the same order with the same point counts.

use mstar::planar::{Attachment, Sketch};

use super::figure::Figure;
use super::geometry::{Point, Shape, whole_body};

/// An RGB colour.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Colour(pub u8, pub u8, pub u8);

impl Colour {
    /// `#rrggbb`.
    #[must_use]
    pub fn hex(self) -> String {
        format!("#{:02x}{:02x}{:02x}", self.0, self.1, self.2)
    }
}

/// Lines, joint marks and the ground.
pub const INK: Colour = Colour(0x33, 0x33, 0x33);
/// The inside of open marks.
pub const PAPER: Colour = Colour(0xff, 0xff, 0xff);
/// Drivers.
const MOTOR: Colour = Colour(0xa0, 0x10, 0x10);
/// Guides of prismatic joints.
const GUIDE: Colour = Colour(0x99, 0x99, 0x99);

/// The body colours (Tableau 10), by body index, repeating after ten.
const PALETTE: [Colour; 10] = [
    Colour(0x1f, 0x77, 0xb4),
    Colour(0xff, 0x7f, 0x0e),
    Colour(0x2c, 0xa0, 0x2c),
    Colour(0xd6, 0x27, 0x28),
    Colour(0x94, 0x67, 0xbd),
    Colour(0x8c, 0x56, 0x4b),
    Colour(0xe3, 0x77, 0xc2),
    Colour(0x7f, 0x7f, 0x7f),
    Colour(0xbc, 0xbd, 0x22),
    Colour(0x17, 0xbe, 0xcf),
];

/// The colour of the `body`-th body, the same in every frame and output.
#[must_use]
pub fn body_colour(body: usize) -> Colour {
    PALETTE[body % PALETTE.len()]
}

/// How a shape is drawn.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Style {
    /// Outline colour and width in px, if outlined.
    pub stroke: Option<(Colour, f64)>,
    /// Fill colour and opacity in [0, 1], if filled.
    pub fill: Option<(Colour, f64)>,
    /// A dashed outline.
    pub dashed: bool,
}

impl Style {
    fn stroke(colour: Colour, width: f64) -> Self {
        Self {
            stroke: Some((colour, width)),
            fill: None,
            dashed: false,
        }
    }

    fn fill(colour: Colour) -> Self {
        Self {
            stroke: None,
            fill: Some((colour, 1.0)),
            dashed: false,
        }
    }

    fn with_fill(mut self, colour: Colour, opacity: f64) -> Self {
        self.fill = Some((colour, opacity));
        self
    }
}

/// One thing drawn.
#[derive(Clone, Debug, PartialEq)]
pub struct Item {
    /// Where, in pixels.
    pub shape: Shape,
    /// How.
    pub style: Style,
    /// The body it draws, if it draws one (for a tooltip).
    pub body: Option<usize>,
}

/// An axis-aligned box in world coordinates, m.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounds {
    /// Smallest x, y.
    pub min: Point,
    /// Largest x, y.
    pub max: Point,
}

impl Bounds {
    fn around(points: impl IntoIterator<Item = Point>) -> Option<Self> {
        let mut it = points
            .into_iter()
            .filter(|p| p.iter().all(|x| x.is_finite()));
        let first = it.next()?;
        Some(it.fold(
            Self {
                min: first,
                max: first,
            },
            |b, p| Self {
                min: [b.min[0].min(p[0]), b.min[1].min(p[1])],
                max: [b.max[0].max(p[0]), b.max[1].max(p[1])],
            },
        ))
    }
}

/// World metres to pixels: equal scales in x and y, y up in the world and
/// down on the screen, a given box centred with a margin.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct View {
    /// Width, px.
    pub width: u32,
    /// Height, px.
    pub height: u32,
    /// Pixels per metre.
    pub scale: f64,
    /// The world point at the centre of the picture.
    centre: Point,
    /// The size unit of marks and lines: 1 at 640×480, in proportion to the
    /// smaller side elsewhere.
    pub unit: f64,
}

impl View {
    /// The view of `width`×`height` px that shows `bounds` whole, with a
    /// margin of 8 % of the smaller side plus room for the ground symbols.
    #[must_use]
    pub fn fit(bounds: Bounds, width: u32, height: u32) -> Self {
        let (w, h) = (f64::from(width), f64::from(height));
        let unit = w.min(h) / 480.0;
        let margin = 0.08 * w.min(h) + 24.0 * unit;
        let extent = |k: usize| (bounds.max[k] - bounds.min[k]).max(1e-9);
        let (dx, dy) = (extent(0), extent(1));
        // A single point (nothing moves, one body): a metre across.
        let (dx, dy) = if dx.max(dy) <= 1e-9 {
            (1.0, 1.0)
        } else {
            (dx, dy)
        };
        let scale = ((w - 2.0 * margin).max(1.0) / dx).min((h - 2.0 * margin).max(1.0) / dy);
        Self {
            width,
            height,
            scale,
            centre: [
                0.5 * (bounds.min[0] + bounds.max[0]),
                0.5 * (bounds.min[1] + bounds.max[1]),
            ],
            unit,
        }
    }

    /// A world point in pixels.
    #[must_use]
    pub fn px(&self, p: Point) -> Point {
        [
            0.5 * f64::from(self.width) + (p[0] - self.centre[0]) * self.scale,
            0.5 * f64::from(self.height) - (p[1] - self.centre[1]) * self.scale,
        ]
    }
}

/// The coils of a spring's zigzag.
pub const COILS: usize = 8;

/// A zigzag from `a` to `b` (pixels): straight leads over the first and last
/// 15 %, then `coils` teeth of `amplitude` px across, spaced over the current
/// length. It starts at `a` and ends at `b`, with `2 coils + 4` points.
#[must_use]
pub fn zigzag(a: Point, b: Point, coils: usize, amplitude: f64) -> Vec<Point> {
    let d = [b[0] - a[0], b[1] - a[1]];
    let len = d[0].hypot(d[1]);
    let e = if len > 1e-12 {
        [d[0] / len, d[1] / len]
    } else {
        [1.0, 0.0]
    };
    let n = [-e[1], e[0]];
    let along = |f: f64, side: f64| {
        [
            a[0] + f * d[0] + side * amplitude * n[0],
            a[1] + f * d[1] + side * amplitude * n[1],
        ]
    };
    let teeth = 2 * coils;
    let mut out = Vec::with_capacity(teeth + 4);
    out.push(a);
    out.push(along(0.15, 0.0));
    for i in 0..teeth {
        let f = 0.15 + 0.7 * (i as f64 + 0.5) / teeth as f64;
        out.push(along(f, if i % 2 == 0 { 1.0 } else { -1.0 }));
    }
    out.push(along(0.85, 0.0));
    out.push(b);
    out
}

/// A spiral of `n` points around `c` (pixels), from radius `r0` to `r1`,
/// starting at the world angle `start` and turning `span` radians
/// counter-clockwise on the screen (y down: the pixel angle is negated).
#[must_use]
pub fn spiral(c: Point, r0: f64, r1: f64, start: f64, span: f64, n: usize) -> Vec<Point> {
    (0..n)
        .map(|i| {
            let f = i as f64 / (n.max(2) - 1) as f64;
            let (s, co) = (start + f * span).sin_cos();
            let r = r0 + f * (r1 - r0);
            [c[0] + r * co, c[1] - r * s]
        })
        .collect()
}

/// Where a prismatic joint's guide lies: its direction in the frame of its
/// first attachment's body (or the world), and how far point b travels along
/// it from point a over the run, m.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Guide {
    local: Point,
    range: [f64; 2],
}

/// The elements whose second end is a placeholder, not a ground point.
fn one_body(kind: &str) -> bool {
    matches!(kind, "driver" | "force" | "torque")
}

/// A model's drawing: what stays the same in every frame (its [`Figure`],
/// guide directions, ground points), and [`Scene::items`] for one state.
pub struct Scene {
    figure: Box<dyn Figure>,
    /// Per element, its guide if it is a prismatic joint whose points part.
    guides: Vec<Option<Guide>>,
    /// The distinct ground points of joints and springs.
    grounds: Vec<Point>,
}

impl Scene {
    /// The scene of `figure` over the run's `states` (for the guides'
    /// directions and lengths).
    #[must_use]
    pub fn new(figure: Box<dyn Figure>, states: &[Vec<f64>]) -> Self {
        let sketch = figure.sketch();
        let mut grounds: Vec<Point> = Vec::new();
        for e in sketch.elements.iter().filter(|e| !whole_body(e.kind)) {
            for (i, end) in e.ends.iter().enumerate() {
                if let Attachment::Ground(p) = *end
                    && !(one_body(e.kind) && i == 1)
                    && !grounds.contains(&p)
                {
                    grounds.push(p);
                }
            }
        }
        let guides = (0..sketch.elements.len())
            .map(|e| guide(figure.as_ref(), e, states))
            .collect();
        Self {
            figure,
            guides,
            grounds,
        }
    }

    /// The model's bodies and elements.
    #[must_use]
    pub fn sketch(&self) -> &Sketch {
        self.figure.sketch()
    }

    /// The box around every body centre, joint point, ground point and
    /// body solid over the given states (the run: the view stays put while
    /// it plays).
    #[must_use]
    pub fn bounds(&self, states: &[Vec<f64>]) -> Bounds {
        let (f, s) = (&self.figure, self.sketch());
        let mut points: Vec<Point> = self.grounds.clone();
        for u in states {
            points.extend((0..s.bodies.len()).map(|b| f.centre(b, u)));
            for b in 0..s.bodies.len() {
                let r = f.reach(b, u);
                if r != [0.0; 2] {
                    let c = f.centre(b, u);
                    points.extend([[c[0] - r[0], c[1] - r[1]], [c[0] + r[0], c[1] + r[1]]]);
                }
            }
            for (i, e) in s.elements.iter().enumerate() {
                let ends = if one_body(e.kind) { 1 } else { 2 };
                points.extend((0..ends).map(|side| f.end(i, side, u)));
            }
        }
        Bounds::around(points).unwrap_or(Bounds {
            min: [-0.5, -0.5],
            max: [0.5, 0.5],
        })
    }

    /// The items of one frame at state `u`, back to front: guides, ground
    /// symbols, springs, rods, bodies, centres of mass, joint marks.
    #[must_use]
    pub fn items(&self, u: &[f64], view: &View) -> Vec<Item> {
        let mut out = Vec::new();
        self.guide_items(u, view, &mut out);
        for &g in &self.grounds {
            ground_symbol(view.px(g), view.unit, &mut out);
        }
        self.element_items(u, view, false, &mut out);
        self.body_items(u, view, &mut out);
        self.element_items(u, view, true, &mut out);
        out
    }

    fn guide_items(&self, u: &[f64], view: &View, out: &mut Vec<Item>) {
        for (i, (e, g)) in self.sketch().elements.iter().zip(&self.guides).enumerate() {
            let Some(g) = g else { continue };
            let a = self.figure.end(i, 0, u);
            let d = rotate(g.local, self.figure.angle(&e.ends[0], u));
            let pad = 14.0 * view.unit / view.scale;
            let end = |s: f64| view.px([a[0] + s * d[0], a[1] + s * d[1]]);
            let mut style = Style::stroke(GUIDE, 1.5 * view.unit);
            style.dashed = true;
            out.push(Item {
                shape: Shape::Line(vec![end(g.range[0] - pad), end(g.range[1] + pad)]),
                style,
                body: None,
            });
        }
    }

    /// Springs and rods (`marks` false), or the marks drawn over the bodies
    /// (`marks` true): joint circles and squares, drivers, forces.
    fn element_items(&self, u: &[f64], view: &View, marks: bool, out: &mut Vec<Item>) {
        let k = view.unit;
        let angle = |at: &Attachment| self.figure.angle(at, u);
        for (i, e) in self.sketch().elements.iter().enumerate() {
            let [a, b] = [0, 1].map(|side| view.px(self.figure.end(i, side, u)));
            // A joint's mark sits on its body's point (the ground's is marked).
            let on_body = if matches!(e.ends[0], Attachment::Ground(_)) {
                b
            } else {
                a
            };
            match (e.kind, marks) {
                ("spring-damper", false) => out.push(line(zigzag(a, b, COILS, 6.0 * k), 1.5 * k)),
                ("rotational-spring-damper", false) => {
                    let turn = angle(&e.ends[1]) - angle(&e.ends[0]);
                    let span = (4.0 * std::f64::consts::PI + turn).clamp(1.0, 30.0);
                    let start = angle(&e.ends[1]);
                    out.push(line(spiral(b, 3.0 * k, 13.0 * k, start, span, 40), 1.5 * k));
                }
                ("distance", false) => out.push(line(vec![a, b], 2.0 * k)),
                // With the spatial joints that keep a point on their axis.
                ("revolute" | "spherical" | "universal" | "cylindrical", true) => {
                    out.push(ring(on_body, 4.5 * k, k));
                }
                ("distance", true) => {
                    out.push(ring(a, 3.0 * k, k));
                    out.push(ring(b, 3.0 * k, k));
                }
                ("weld", true) => out.push(Item {
                    shape: Shape::Square(on_body, 4.0 * k),
                    style: Style::stroke(INK, 1.5 * k).with_fill(PAPER, 1.0),
                    body: None,
                }),
                ("driver", true) => out.push(Item {
                    shape: Shape::Polygon(diamond(a, 4.5 * k)),
                    style: Style::fill(MOTOR),
                    body: None,
                }),
                ("force", true) => {
                    let r = 4.0 * k;
                    out.push(line(
                        vec![[a[0] - r, a[1] - r], [a[0] + r, a[1] + r]],
                        1.5 * k,
                    ));
                    out.push(line(
                        vec![[a[0] - r, a[1] + r], [a[0] + r, a[1] - r]],
                        1.5 * k,
                    ));
                }
                _ => {}
            }
        }
    }

    /// Each body: a bar or a translucent polygon through its outline (rigid),
    /// with its centre of mass as a dot; a filled circle (point mass).
    fn body_items(&self, u: &[f64], view: &View, out: &mut Vec<Item>) {
        let k = view.unit;
        self.face_items(u, view, out);
        for (i, body) in self.sketch().bodies.iter().enumerate() {
            let colour = body_colour(i);
            let centre = view.px(self.figure.centre(i, u));
            if !body.rigid {
                out.push(Item {
                    shape: Shape::Circle(centre, 8.0 * k),
                    style: Style::stroke(INK, k).with_fill(colour, 1.0),
                    body: Some(i),
                });
                continue;
            }
            let half = 8.0 * k / view.scale;
            let shape = self.figure.outline(i, u, half).map(|p| view.px(p));
            let style = match shape {
                Shape::Polygon(_) => Style::stroke(colour, 3.0 * k).with_fill(colour, 0.35),
                _ => Style::stroke(colour, 7.0 * k),
            };
            out.push(Item {
                shape,
                style,
                body: Some(i),
            });
            out.push(Item {
                shape: Shape::Circle(centre, 2.5 * k),
                style: Style::fill(INK),
                body: Some(i),
            });
        }
    }
}

impl Scene {
    /// The faces of the bodies' solids (spatial models), far ones first
    /// (the painter's algorithm), each in its body's colour darkened by its
    /// angle to the light, with a darker outline.
    fn face_items(&self, u: &[f64], view: &View, out: &mut Vec<Item>) {
        let mut faces = self.figure.faces(u);
        faces.sort_by(|a, b| b.depth.total_cmp(&a.depth));
        for face in faces {
            let c = body_colour(face.body);
            let dim = |f: f64| {
                let d = |x: u8| (f64::from(x) * f).round().clamp(0.0, 255.0) as u8;
                Colour(d(c.0), d(c.1), d(c.2))
            };
            out.push(Item {
                shape: Shape::Polygon(face.corners.into_iter().map(|p| view.px(p)).collect()),
                style: Style::stroke(dim(0.45), view.unit).with_fill(dim(face.brightness), 1.0),
                body: Some(face.body),
            });
        }
    }
}

/// The guide of a prismatic joint: its axis in a's frame (from the model)
/// and b's travel along it over the run. None for other elements.
fn guide(figure: &dyn Figure, e: usize, states: &[Vec<f64>]) -> Option<Guide> {
    let element = &figure.sketch().elements[e];
    let local = element.axis?;
    let relative = |u: &Vec<f64>| {
        let a = figure.end(e, 0, u);
        let b = figure.end(e, 1, u);
        rotate(
            [b[0] - a[0], b[1] - a[1]],
            -figure.angle(&element.ends[0], u),
        )
    };
    let range = states.iter().map(relative).fold([0.0f64, 0.0f64], |r, p| {
        let s = p[0] * local[0] + p[1] * local[1];
        [r[0].min(s), r[1].max(s)]
    });
    Some(Guide { local, range })
}

fn rotate(p: Point, theta: f64) -> Point {
    let (s, c) = theta.sin_cos();
    [c * p[0] - s * p[1], s * p[0] + c * p[1]]
}

fn line(points: Vec<Point>, width: f64) -> Item {
    Item {
        shape: Shape::Line(points),
        style: Style::stroke(INK, width),
        body: None,
    }
}

/// An open circle: a joint.
fn ring(c: Point, r: f64, unit: f64) -> Item {
    Item {
        shape: Shape::Circle(c, r),
        style: Style::stroke(INK, 1.5 * unit).with_fill(PAPER, 1.0),
        body: None,
    }
}

fn diamond(c: Point, r: f64) -> Vec<Point> {
    vec![
        [c[0], c[1] - r],
        [c[0] + r, c[1]],
        [c[0], c[1] + r],
        [c[0] - r, c[1]],
    ]
}

/// The ground symbol under a fixed point `g` (pixels): a triangle standing
/// on a short base with diagonal hatches below it.
fn ground_symbol(g: Point, k: f64, out: &mut Vec<Item>) {
    let (half, high) = (7.0 * k, 10.0 * k);
    out.push(Item {
        shape: Shape::Polygon(vec![
            g,
            [g[0] + half, g[1] + high],
            [g[0] - half, g[1] + high],
        ]),
        style: Style::stroke(INK, 1.5 * k).with_fill(Colour(0xdd, 0xdd, 0xdd), 1.0),
        body: None,
    });
    let base = g[1] + high;
    out.push(line(
        vec![[g[0] - 1.6 * half, base], [g[0] + 1.6 * half, base]],
        1.5 * k,
    ));
    for i in 0..5 {
        let x = g[0] - 1.4 * half + f64::from(i) * 0.7 * half;
        out.push(line(
            vec![[x + 0.5 * half, base], [x, base + 0.6 * high]],
            k,
        ));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::animate::figure::PlanarFigure;
    use crate::animate::geometry::hull;
    use mstar::planar::{At, PlanarBuilder, PointMass, RigidBody, SpringDamper};

    /// A plate hinged to the ground with a third point, a bob on a rod from
    /// it and a spring from the bob to the ground.
    fn model() -> (Sketch, Vec<f64>) {
        let mut b = PlanarBuilder::new();
        let plate = b.rigid_body(
            "plate",
            RigidBody {
                mass: 1.0,
                inertia: 0.1,
                pose: [0.5, 0.2, 0.3],
                velocity: [0.0; 3],
            },
        );
        let bob = b.point_mass(
            "bob",
            PointMass {
                mass: 1.0,
                position: [1.5, 0.0],
                velocity: [0.0; 2],
            },
        );
        b.revolute(
            "hinge",
            At::Ground([0.0, 0.0]),
            At::Body(plate, [-0.5, 0.0]),
        );
        b.distance(
            "rod",
            At::Body(plate, [0.5, 0.0]),
            At::Body(bob, [0.0, 0.0]),
            0.6,
        );
        b.distance(
            "strut",
            At::Body(plate, [0.0, 0.4]),
            At::Body(bob, [0.0, 0.0]),
            0.9,
        );
        let spring = SpringDamper {
            stiffness: 1.0,
            damping: 0.0,
            rest_length: 1.0,
        };
        b.spring(
            "spring",
            At::Body(bob, [0.0, 0.0]),
            At::Ground([2.0, 1.0]),
            spring,
        );
        let sys = b.build().expect("valid");
        (sys.sketch(), sys.initial_position())
    }

    fn close(p: Point, q: Point) -> bool {
        (p[0] - q[0]).abs() < 1e-9 && (p[1] - q[1]).abs() < 1e-9
    }

    #[test]
    fn bodies_are_drawn_through_their_joint_points() {
        let (sketch, mut u) = model();
        // Any state, not only the initial one.
        u[2] = 1.1;
        u[0] = 0.7;
        let scene = Scene::new(
            Box::new(PlanarFigure::new(sketch.clone())),
            std::slice::from_ref(&u),
        );
        let view = View::fit(scene.bounds(std::slice::from_ref(&u)), 640, 480);
        let items = scene.items(&u, &view);
        let plate: Vec<&Item> = items.iter().filter(|i| i.body == Some(0)).collect();
        let Shape::Polygon(outline) = &plate[0].shape else {
            panic!("three points make a polygon: {:?}", plate[0]);
        };
        assert_eq!(outline.len(), 3);
        for local in [[-0.5, 0.0], [0.5, 0.0], [0.0, 0.4]] {
            let at = Attachment::Body { body: 0, local };
            let expected = view.px(sketch.position(&at, &u));
            assert!(
                outline.iter().any(|&p| close(p, expected)),
                "{local:?} at {expected:?} not in {outline:?}"
            );
        }
        // The centre of mass, and the bob as a filled circle at its position.
        assert!(
            plate
                .iter()
                .any(|i| matches!(i.shape, Shape::Circle(c, _) if close(c, view.px([u[0], u[1]]))))
        );
        let bob = items.iter().find(|i| i.body == Some(1)).expect("the bob");
        assert!(matches!(bob.shape, Shape::Circle(c, _) if close(c, view.px([u[3], u[4]]))));
        // The hinge is an open circle at the plate's hinge point.
        let hinge = view.px(sketch.position(&sketch.elements[0].ends[1], &u));
        assert!(items.iter().any(
            |i| matches!(i.shape, Shape::Circle(c, _) if close(c, hinge))
                && i.style.fill == Some((PAPER, 1.0))
        ));
    }

    #[test]
    fn the_zigzag_spans_the_spring() {
        let (sketch, u) = model();
        let scene = Scene::new(
            Box::new(PlanarFigure::new(sketch.clone())),
            std::slice::from_ref(&u),
        );
        let view = View::fit(scene.bounds(std::slice::from_ref(&u)), 320, 240);
        let spring = &sketch.elements[3];
        assert_eq!(spring.kind, "spring-damper");
        let ends = spring.ends.map(|e| view.px(sketch.position(&e, &u)));
        let items = scene.items(&u, &view);
        let zig = items
            .iter()
            .find_map(|i| match &i.shape {
                Shape::Line(p) if p.len() == 2 * COILS + 4 => Some(p),
                _ => None,
            })
            .expect("a zigzag");
        assert!(
            close(zig[0], ends[0]) && close(zig[zig.len() - 1], ends[1]),
            "{zig:?} {ends:?}"
        );
        // Its teeth stand off the straight line by the amplitude.
        let z = zigzag([0.0, 0.0], [100.0, 0.0], 4, 5.0);
        assert_eq!(z.len(), 12);
        assert!(
            z[2..10].iter().all(|p| (p[1].abs() - 5.0).abs() < 1e-12),
            "{z:?}"
        );
        assert!(z[2..10].windows(2).all(|w| w[1][0] > w[0][0]));
    }

    #[test]
    fn the_view_fits_the_run_with_equal_scales_and_y_up() {
        let b = Bounds {
            min: [-1.0, 0.0],
            max: [3.0, 1.0],
        };
        let v = View::fit(b, 640, 480);
        let (lo, hi) = (v.px(b.min), v.px(b.max));
        assert!(
            lo[0] > 0.0 && hi[0] < 640.0 && hi[1] > 0.0 && lo[1] < 480.0,
            "{lo:?} {hi:?}"
        );
        assert!(hi[1] < lo[1], "y up");
        // Equal scales: 4 m wide, 1 m high.
        assert!(((hi[0] - lo[0]) - 4.0 * (lo[1] - hi[1])).abs() < 1e-9);
        // Centred.
        assert!((lo[0] + hi[0] - 640.0).abs() < 1e-9 && (lo[1] + hi[1] - 480.0).abs() < 1e-9);
    }

    #[test]
    fn hulls_and_every_frame_alike() {
        let square = hull(&[[0.0, 0.0], [1.0, 1.0], [1.0, 0.0], [0.5, 0.5], [0.0, 1.0]]);
        assert_eq!(square, [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]);
        assert_eq!(
            hull(&[[0.0, 0.0], [2.0, 0.0], [1.0, 0.0]]),
            [[0.0, 0.0], [2.0, 0.0]]
        );
        let (sketch, u) = model();
        let mut v = u.clone();
        v[2] += 2.0;
        v[3] -= 0.3;
        let states = [u.clone(), v.clone()];
        let scene = Scene::new(Box::new(PlanarFigure::new(sketch)), &states);
        let view = View::fit(scene.bounds(&states), 640, 480);
        let (a, b) = (scene.items(&u, &view), scene.items(&v, &view));
        assert_eq!(a.len(), b.len());
        for (x, y) in a.iter().zip(&b) {
            assert_eq!(x.shape.points().len(), y.shape.points().len());
            assert_eq!(x.style, y.style);
        }
    }
}
