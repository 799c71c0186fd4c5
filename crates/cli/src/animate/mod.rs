//! `mstar animate`: the mechanism of a model file moving through the results
//! of `mstar run`, as an animated GIF, a self-contained HTML page, or one
//! frame as a PNG picture. The GIF, the PNG and a planar model's page draw
//! the same [`scene`]: each body through its joint points, springs as
//! zigzags, the ground marked, the time in a corner (docs/model-format.md,
//! "Animating a run"). A planar model is drawn in its plane ([`figure`]), a
//! spatial one projected onto the picture by `--view` ([`spatial`]), each
//! body also as a shaded box of its inertia ([`solid`]); a spatial model's
//! page is 3-D, drawn in the browser by a script of its own ([`page3d`]).

pub mod figure;
pub mod geometry;
pub mod html;
pub mod mode_shape;
pub mod page3d;
pub mod picture;
pub mod results;
pub mod scene;
pub mod solid;
pub mod spatial;

/// A 1 m bar named `name`, hinged at the origin, lying along +x: the model
/// of the drawing tests.
#[cfg(test)]
pub(crate) fn hinged_bar(name: &str) -> mstar::planar::PlanarSystem {
    use mstar::planar::{At, PlanarBuilder, RigidBody};
    let mut b = PlanarBuilder::new();
    let bar = b.rigid_body(
        name,
        RigidBody {
            mass: 1.0,
            inertia: 0.1,
            pose: [0.5, 0.0, 0.0],
            velocity: [0.0; 3],
        },
    );
    b.revolute("hinge", At::Ground([0.0, 0.0]), At::Body(bar, [-0.5, 0.0]));
    b.build().expect("valid")
}
