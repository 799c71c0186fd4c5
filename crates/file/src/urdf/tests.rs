//! The URDF reader: conventions (URDF's roll-pitch-yaw, inertial frames,
//! joint origins and axes, massless links), the `urdf =` key's initial
//! joint states, and the errors. Expected values are derived by hand in
//! the comments.

use crate::{FileError, Format, Mechanism, MechanismFile};

/// A robot with `body` (elements inside `<robot>`).
fn robot(body: &str) -> String {
    format!("<?xml version=\"1.0\"?>\n<robot name=\"r\">\n{body}\n</robot>\n")
}

/// A link with mass 1 and the inertial frame `origin` (attributes).
fn link(name: &str, origin: &str) -> String {
    format!(
        "<link name=\"{name}\"><inertial><origin {origin}/><mass value=\"1\"/>\
         <inertia ixx=\"0.02\" ixy=\"0\" ixz=\"0\" iyy=\"0.03\" iyz=\"0\" izz=\"0.04\"/></inertial></link>"
    )
}

fn joint(name: &str, kind: &str, parent: &str, child: &str, extra: &str) -> String {
    format!(
        "<joint name=\"{name}\" type=\"{kind}\"><parent link=\"{parent}\"/><child link=\"{child}\"/>{extra}</joint>"
    )
}

fn load(text: &str) -> Result<MechanismFile, FileError> {
    MechanismFile::parse(text, "r.urdf", Format::Urdf)
}

/// The initial coordinates of body `name`: position and Euler parameters.
fn pose(file: &MechanismFile, name: &str) -> Vec<f64> {
    let Mechanism::Spatial(sys) = &file.mechanism else {
        panic!("a spatial model")
    };
    let (x, rigid) = sys.body(name).expect("the body");
    assert!(rigid);
    sys.initial_position()[x..x + 7].to_vec()
}

fn velocity(file: &MechanismFile, name: &str) -> Vec<f64> {
    let Mechanism::Spatial(sys) = &file.mechanism else {
        panic!("a spatial model")
    };
    let (x, _) = sys.body(name).expect("the body");
    sys.initial_velocity()[x..x + 7].to_vec()
}

fn close(a: &[f64], b: &[f64]) {
    // Products and sums of a few unit quaternions: round-off of 1e-15.
    assert_eq!(a.len(), b.len());
    for (x, y) in a.iter().zip(b) {
        assert!((x - y).abs() < 1e-14, "{a:?} != {b:?}");
    }
}

/// URDF's rpy is fixed-axis roll, pitch, yaw: R = Rz(y) Ry(p) Rx(r). For
/// r = y = π/2, p = 0: Rx(π/2) takes y to z and z to −y; Rz(π/2) takes x to
/// y, y to −x. So R e_x = Rz e_x = e_y, R e_y = Rz e_z = e_z, R e_z =
/// Rz(−e_y) = e_x: the cyclic permutation, the rotation by 2π/3 about
/// (1, 1, 1)/√3, whose Euler parameters are [cos(π/3), sin(π/3)/√3 (1, 1, 1)]
/// = [1/2, 1/2, 1/2, 1/2]. The body's centre is the inertial origin.
#[test]
fn roll_pitch_yaw_is_fixed_axis_z_y_x() {
    let h = std::f64::consts::FRAC_PI_2;
    let text = robot(&format!(
        "<link name=\"base\"/>{}{}",
        link("a", &format!("xyz=\"0.1 0.2 0.3\" rpy=\"{h} 0 {h}\"")),
        joint("j", "fixed", "base", "a", "")
    ));
    let file = load(&text).expect("valid");
    close(&pose(&file, "a"), &[0.1, 0.2, 0.3, 0.5, 0.5, 0.5, 0.5]);
}

/// Joint origins chain: the child link frame is the parent's moved by the
/// origin; the inertial origin is in the child's frame. Base → (yaw π/2,
/// at (1, 0, 0)) → link a, whose centre is 0.5 along its x: global
/// (1, 0.5, 0), orientation [cos(π/4), 0, 0, sin(π/4)]. Then a massless
/// link m fixed to a at (0, 1, 0) in a's frame (global (0, 1, 0) turned: (−1,
/// 0, 0) from a's origin: (0, 0, 0)); b on a revolute joint of m at m's
/// origin, axis z: b's centre 0.5 along its x, turned by π/2: (0, 0.5, 0).
#[test]
fn origins_chain_and_massless_links_merge_into_their_parent() {
    let h = std::f64::consts::FRAC_PI_2;
    let text = robot(&format!(
        "<link name=\"base\"/>{}<link name=\"m\"/>{}{}{}{}",
        link("a", "xyz=\"0.5 0 0\""),
        link("b", "xyz=\"0.5 0 0\""),
        joint(
            "j1",
            "revolute",
            "base",
            "a",
            &format!("<origin xyz=\"1 0 0\" rpy=\"0 0 {h}\"/><axis xyz=\"0 0 1\"/>")
        ),
        joint("fix", "fixed", "a", "m", "<origin xyz=\"0 1 0\"/>"),
        joint("j2", "continuous", "m", "b", "<axis xyz=\"0 0 2\"/>"),
    ));
    let file = load(&text).expect("valid");
    let s = std::f64::consts::FRAC_1_SQRT_2;
    close(&pose(&file, "a"), &[1.0, 0.5, 0.0, s, 0.0, 0.0, s]);
    close(&pose(&file, "b"), &[0.0, 0.5, 0.0, s, 0.0, 0.0, s]);
    let Mechanism::Spatial(sys) = &file.mechanism else {
        panic!("spatial")
    };
    // Two bodies; the massless link is no body, its fixed joint no joint.
    assert_eq!(sys.body_names().collect::<Vec<_>>(), ["a", "b"]);
    use mstar_model::System;
    // Rows: a.norm, j1 (5), b.norm, j2 (5).
    assert_eq!(sys.n_constraints(), 12);
}

/// A massless link `m` moved by a revolute joint, with a link of mass `a`
/// fixed to it at (0, 1, 0) in its frame: `a`'s body carries `m`, so `j1`
/// joins the ground and `a` at `m`'s origin (1, 0, 0) and `j2` hangs from
/// `a`. The same robot written without `m` (`a` on `j1` directly, its
/// inertial origin and `j2`'s origin moved by (0, 1, 0)) has the same
/// bodies and joints.
#[test]
fn a_massless_link_on_a_moving_joint_is_carried_by_the_link_fixed_to_it() {
    let with_frame = robot(&format!(
        "<link name=\"base\"/><link name=\"m\"/>{}{}{}{}{}",
        link("a", "xyz=\"0.5 0 0\""),
        link("b", "xyz=\"0.5 0 0\""),
        joint(
            "j1",
            "revolute",
            "base",
            "m",
            "<origin xyz=\"1 0 0\"/><axis xyz=\"0 0 1\"/>"
        ),
        joint("fix", "fixed", "m", "a", "<origin xyz=\"0 1 0\"/>"),
        joint(
            "j2",
            "revolute",
            "a",
            "b",
            "<origin xyz=\"1 0 0\"/><axis xyz=\"0 1 0\"/>"
        ),
    ));
    let direct = robot(&format!(
        "<link name=\"base\"/>{}{}{}{}",
        link("a", "xyz=\"0.5 1 0\""),
        link("b", "xyz=\"0.5 0 0\""),
        joint(
            "j1",
            "revolute",
            "base",
            "a",
            "<origin xyz=\"1 0 0\"/><axis xyz=\"0 0 1\"/>"
        ),
        joint(
            "j2",
            "revolute",
            "a",
            "b",
            "<origin xyz=\"1 1 0\"/><axis xyz=\"0 1 0\"/>"
        ),
    ));
    let (a, b) = (
        load(&with_frame).expect("valid"),
        load(&direct).expect("valid"),
    );
    for body in ["a", "b"] {
        close(&pose(&a, body), &pose(&b, body));
    }
    close(&pose(&a, "a"), &[1.5, 1.0, 0.0, 1.0, 0.0, 0.0, 0.0]);
    let (doc, _) = crate::convert_urdf(&with_frame, "r.urdf").expect("valid");
    assert!(
        doc.contains(
            "name = \"j1\"\ntype = \"revolute\"\nbodies = [\"ground\", \"a\"]\nat = [1.0, 0.0, 0.0]"
        ),
        "{doc}"
    );
    assert!(
        !doc.contains("name = \"fix\""),
        "a weld of a to itself: {doc}"
    );
    let Mechanism::Spatial(sys) = &a.mechanism else {
        panic!("spatial")
    };
    use mstar_model::System;
    // Rows: a.norm, j1 (5), b.norm, j2 (5).
    assert_eq!(sys.n_constraints(), 12);
}

/// A massless link moved by a joint and carrying a further moving joint,
/// with no link of mass fixed to it, is refused at that joint; the advice
/// (make the joint fixed) loads.
#[test]
fn a_massless_link_between_moving_joints_is_refused_and_the_advice_loads() {
    let make = |kind: &str| {
        robot(&format!(
            "<link name=\"base\"/><link name=\"m\"/>{}{}{}",
            link("b", "xyz=\"0.5 0 0\""),
            joint("j1", kind, "base", "m", "<axis xyz=\"0 0 1\"/>"),
            joint("j2", "revolute", "m", "b", "<axis xyz=\"0 1 0\"/>"),
        ))
    };
    let Err(e) = load(&make("revolute")) else {
        panic!("a massless link between moving joints loaded")
    };
    let text = e.to_string();
    assert!(text.starts_with("r.urdf:"), "{text}");
    assert!(
        text.contains("joint 'j1': its child link 'm' has no mass"),
        "{text}"
    );
    assert!(text.contains("or make the joint fixed"), "{text}");
    load(&make("fixed")).expect("the advice loads");
}

/// A continuous joint is a revolute joint: the same document.
#[test]
fn continuous_is_revolute() {
    let make = |kind: &str| {
        robot(&format!(
            "<link name=\"base\"/>{}{}",
            link("a", "xyz=\"0.5 0 0\""),
            joint("j", kind, "base", "a", "<axis xyz=\"0 1 0\"/>")
        ))
    };
    let (a, _) = crate::convert_urdf(&make("revolute"), "r.urdf").expect("valid");
    let (b, _) = crate::convert_urdf(&make("continuous"), "r.urdf").expect("valid");
    assert_eq!(a, b);
}

/// Off-diagonal products of inertia are kept: the full tensor.
#[test]
fn off_diagonal_inertia_is_written_as_a_tensor() {
    let text = robot(
        "<link name=\"a\"><inertial><mass value=\"2\"/>\
         <inertia ixx=\"0.02\" ixy=\"-0.001\" ixz=\"0.002\" iyy=\"0.03\" iyz=\"0.003\" izz=\"0.04\"/></inertial></link>",
    );
    let (doc, _) = crate::convert_urdf(&text, "r.urdf").expect("valid");
    assert!(
        doc.contains(
            "inertia = [[0.02, -0.001, 0.002], [-0.001, 0.03, 0.003], [0.002, 0.003, 0.04]]"
        ),
        "{doc}"
    );
    // A root with mass is welded to the ground.
    assert!(
        doc.contains("name = \"a_to_ground\"\ntype = \"weld\""),
        "{doc}"
    );
}

/// `urdf =` with `[[initial]]`: the shoulder at angle θ about y places the
/// bar's centre (0.5 along x from the pivot) at (0.5 cos θ, 0, −0.5 sin θ)
/// (a rotation by θ about y takes x to (cos θ, 0, −sin θ)), with Euler
/// parameters [cos θ/2, 0, sin θ/2, 0]; turning at ω about y, the centre
/// moves at ω × r = ω (−0.5 sin θ, 0, −0.5 cos θ) and the Euler parameters
/// at ṗ = ½ ω [−sin θ/2, 0, cos θ/2, 0].
#[test]
fn initial_joint_states_place_the_bodies_by_forward_kinematics() {
    let dir = std::env::temp_dir().join(format!("mstar-urdf-unit-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a directory");
    let urdf = robot(&format!(
        "<link name=\"base\"/>{}{}",
        link("bar", "xyz=\"0.5 0 0\""),
        joint(
            "shoulder",
            "revolute",
            "base",
            "bar",
            "<axis xyz=\"0 1 0\"/>"
        )
    ));
    std::fs::write(dir.join("arm.urdf"), urdf).expect("written");
    let (theta, omega) = (0.3_f64, 2.0_f64);
    let wrapper = format!(
        "format = \"mstar.spatial/1\"\nurdf = \"arm.urdf\"\n\n[[initial]]\njoint = \"shoulder\"\nposition = {theta}\nvelocity = {omega}\n"
    );
    let origin = dir.join("arm.toml").display().to_string();
    let file = MechanismFile::parse(&wrapper, &origin, Format::Toml).expect("valid");
    let (s, c) = theta.sin_cos();
    let (sh, ch) = (theta / 2.0).sin_cos();
    close(
        &pose(&file, "bar"),
        &[0.5 * c, 0.0, -0.5 * s, ch, 0.0, sh, 0.0],
    );
    close(
        &velocity(&file, "bar"),
        &[
            -0.5 * s * omega,
            0.0,
            -0.5 * c * omega,
            -0.5 * omega * sh,
            0.0,
            0.5 * omega * ch,
            0.0,
        ],
    );
    // An [[initial]] of a joint the URDF does not have: at its name.
    let bad = wrapper.replace("joint = \"shoulder\"", "joint = \"elbow\"");
    let e = MechanismFile::parse(&bad, &origin, Format::Toml).expect_err("no elbow");
    assert_eq!(e.place, Some((5, 9)), "{e}");
    assert!(
        e.message.contains("'elbow' is not a joint of the URDF"),
        "{e}"
    );
    assert!(e.message.ends_with("(here: shoulder)"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Each error names the file, the line and column, and what to do.
#[test]
fn errors_name_the_place_and_the_fix() {
    let base = "<link name=\"base\"/>";
    let cases = [
        // Malformed XML: the place of the mismatched close tag.
        (
            "<robot name=\"r\">\n<link name=\"a\">\n</robot>\n".to_string(),
            (3, 1),
            "XML syntax",
        ),
        (
            robot(&format!(
                "{base}{}{}",
                link("a", ""),
                joint("free", "floating", "base", "a", "")
            )),
            (3, 1),
            "'floating' is not supported",
        ),
        (
            robot(&format!(
                "{base}{}{}",
                link("a", ""),
                joint("j", "revolute", "base", "arm", "")
            )),
            (3, 1),
            "joint 'j': child: no link is called 'arm' (known: a, base)",
        ),
        (
            robot(&format!("{base}{}", link("a", ""))),
            (3, 1),
            "two root links, 'base' and 'a'",
        ),
        (
            robot(&format!(
                "{base}{}{}{}{}",
                link("a", ""),
                link("b", ""),
                joint("ab", "revolute", "a", "b", ""),
                joint("ba", "revolute", "b", "a", "")
            )),
            (3, 1),
            "cycle through the links",
        ),
        (
            robot(&format!(
                "{base}<link name=\"m\"/>{}{}{}",
                link("a", ""),
                joint("j1", "revolute", "base", "m", ""),
                joint("j2", "revolute", "m", "a", "")
            )),
            (3, 1),
            "joint 'j1': its child link 'm' has no mass",
        ),
        (
            robot(&format!(
                "{base}{}{}",
                link("a", ""),
                joint("a", "revolute", "base", "a", "")
            )),
            (3, 1),
            "'a': a link and a joint",
        ),
    ];
    for (text, (line, _), says) in cases {
        let e = load(&text).expect_err(says);
        assert_eq!(e.origin, "r.urdf");
        assert_eq!(e.place.map(|p| p.0), Some(line), "{says}: {e}");
        assert!(e.message.contains(says), "{says}: {e}");
    }
}

/// The elements read and ignored: one note each, at the first.
#[test]
fn ignored_elements_get_one_note_each() {
    let limit = "<limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/>";
    let text = robot(&format!(
        "<link name=\"base\"/>{}{}{}{}<transmission name=\"t\"/>",
        link("a", ""),
        link("b", ""),
        joint("j1", "revolute", "base", "a", limit),
        joint("j2", "revolute", "a", "b", limit),
    ));
    let file = load(&text).expect("valid");
    assert_eq!(file.warnings.len(), 2, "{:?}", file.warnings);
    assert!(
        file.warnings[0].starts_with("r.urdf:3:365: "),
        "{:?}",
        file.warnings
    );
    assert!(
        file.warnings[0].contains("<limit>: ignored"),
        "{:?}",
        file.warnings
    );
    assert!(
        file.warnings[1].contains("<transmission>: ignored"),
        "{:?}",
        file.warnings
    );
}

/// A prismatic joint on a turning arm: the arm turns about z at ω (at
/// angle 0), the slider sits at d along the arm's x moving out at ḋ. Its
/// centre is at (d, 0, 0) and moves at ḋ x̂ + ω ẑ × d x̂ = (ḋ, ω d, 0); it
/// turns with the arm, so its Euler parameters (the identity) change at
/// ṗ = ½ (0, ω ẑ) ⊗ p = (0, 0, 0, ω/2).
#[test]
fn prismatic_joints_on_moving_parents_carry_the_transport_velocity() {
    let dir = std::env::temp_dir().join(format!("mstar-urdf-slider-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a directory");
    let urdf = robot(&format!(
        "<link name=\"base\"/>{}{}{}{}",
        link("arm", ""),
        link("slider", ""),
        joint("turn", "revolute", "base", "arm", "<axis xyz=\"0 0 1\"/>"),
        joint("slide", "prismatic", "arm", "slider", "")
    ));
    std::fs::write(dir.join("slider.urdf"), urdf).expect("written");
    let (omega, d, d_dot) = (3.0, 0.4, 0.7);
    let wrapper = format!(
        "format = \"mstar.spatial/1\"\nurdf = \"slider.urdf\"\n\
         [[initial]]\njoint = \"turn\"\nvelocity = {omega}\n\
         [[initial]]\njoint = \"slide\"\nposition = {d}\nvelocity = {d_dot}\n"
    );
    let origin = dir.join("slider.toml").display().to_string();
    let file = MechanismFile::parse(&wrapper, &origin, Format::Toml).expect("valid");
    close(&pose(&file, "slider"), &[d, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0]);
    close(
        &velocity(&file, "slider"),
        &[d_dot, omega * d, 0.0, 0.0, 0.0, 0.0, omega / 2.0],
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A value the spatial reader refuses is placed at the URDF element of its
/// body: izz = 0.1 > ixx + iyy = 0.05 is no rigid body's inertia.
#[test]
fn spatial_errors_point_at_the_urdf_element() {
    let text = robot(
        "<link name=\"base\"/>\n<link name=\"a\"><inertial><mass value=\"1\"/>\
         <inertia ixx=\"0.02\" ixy=\"0\" ixz=\"0\" iyy=\"0.03\" iyz=\"0\" izz=\"0.1\"/></inertial></link>\n\
         <joint name=\"j\" type=\"fixed\"><parent link=\"base\"/><child link=\"a\"/></joint>",
    );
    let e = load(&text).expect_err("no rigid body");
    assert_eq!(
        (e.origin.as_str(), e.place),
        ("r.urdf", Some((4, 1))),
        "{e}"
    );
    assert!(e.message.starts_with("body 'a': "), "{e}");
    // No rotational inertia: the advice is the URDF's, not a
    // [[point_mass]] (which a URDF has no way to give); followed, it loads.
    let link = |moments: &str| {
        robot(&format!(
            "<link name=\"base\"/>\n<link name=\"a\"><inertial><mass value=\"1\"/>\
             <inertia {moments} ixy=\"0\" ixz=\"0\" iyz=\"0\"/></inertial></link>\n\
             <joint name=\"j\" type=\"fixed\"><parent link=\"base\"/><child link=\"a\"/></joint>"
        ))
    };
    let e = load(&link("ixx=\"0\" iyy=\"0\" izz=\"0\"")).expect_err("no inertia");
    assert_eq!(e.place, Some((4, 1)), "{e}");
    assert!(
        e.message
            .contains("give the link's <inertia> positive moments"),
        "{e}"
    );
    assert!(!e.message.contains("point_mass"), "{e}");
    load(&link("ixx=\"0.01\" iyy=\"0.01\" izz=\"0.01\"")).expect("the advice loads");
}
