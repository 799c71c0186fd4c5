//! `mstar animate` on spatial model files: every model of models/spatial
//! drawn in every output, the four `--view` projections checked point by
//! point against coordinates worked out by hand (in the drawing the 3-D
//! page carries for a browser without script, the PNG's), a body's shaded
//! box of its inertia, and the errors of `--view` (an unknown view; a
//! planar file, which is drawn in its own plane).

mod common;

use std::path::Path;

use common::{model, mstar, scratch, text};

fn path(p: &Path) -> String {
    p.display().to_string()
}

#[test]
fn every_spatial_model_animates_in_every_output() {
    let dir = scratch("animate-spatial");
    let models = [
        ("top", &["top"][..]),
        ("double-pendulum", &["upper", "lower"]),
        ("tilted-hinge", &["bar"]),
        ("bricard", &["rod1", "rod2", "rod3", "rod4", "rod5"]),
        ("slider-crank", &["crank", "rod", "slider"]),
    ];
    for (name, bodies) in models {
        let file = model(&format!("spatial/{name}.toml"));
        let csv = dir.join(format!("{name}.csv"));
        // (At h = 1e-3 whatever the file's: 101 rows.)
        let ran = mstar(&[
            "run",
            &file,
            "--t-end",
            "0.1",
            "--h",
            "1e-3",
            "--out",
            &path(&csv),
        ]);
        assert!(ran.status.success(), "{name}: {}", text(&ran.stderr));
        let (gif, html, png) = (
            dir.join(format!("{name}.gif")),
            dir.join(format!("{name}.html")),
            dir.join(format!("{name}.png")),
        );
        for view in ["oblique", "xz", "yz", "xy"] {
            let ok = mstar(&[
                "animate",
                &file,
                &path(&csv),
                "--gif",
                &path(&gif),
                "--html",
                &path(&html),
                "--png",
                &path(&png),
                "--at",
                "0.05",
                "--fps",
                "20",
                "--size",
                "160x120",
                "--view",
                view,
            ]);
            assert!(ok.status.success(), "{name} {view}: {}", text(&ok.stderr));
            let out = text(&ok.stdout);
            // 20 fps over 0.1 s slowed to 1 s: 21 frames; every row on the page.
            assert!(out.contains("(21 frames, 160×120)"), "{name}: {out}");
            assert!(out.contains("(101 frames,"), "{name}: {out}");
            assert!(std::fs::read(&gif).expect("GIF").starts_with(b"GIF89a"));
            assert!(std::fs::read(&png).expect("PNG").starts_with(b"\x89PNG"));
            let page = std::fs::read_to_string(&html).expect("the page");
            for body in bodies {
                assert!(
                    page.contains(&format!("<title>{body}</title>")),
                    "{name}: {body}"
                );
            }
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A bar of 1 m along its body x axis, its centre at (0.5, 0, 0) at the
/// start, on a ball joint at the origin (its local (−0.5, 0, 0)) and a rod
/// from its local (0.5, 0, 0) to the ground point (2, 0, 0).
const BAR: &str = r#"format = "mstar.spatial/1"

[[body]]
name = "bar"
mass = 1.0
inertia = [0.001, 0.1, 0.1]
position = [0.5, 0.0, 0.0]
orientation = [1.0, 0.0, 0.0, 0.0]

[[joint]]
name = "ball"
type = "spherical"
bodies = ["ground", "bar"]
points = [[0.0, 0.0, 0.0], [-0.5, 0.0, 0.0]]

[[joint]]
name = "rod"
type = "distance"
bodies = ["bar", "ground"]
points = [[0.5, 0.0, 0.0], [2.0, 0.0, 0.0]]
"#;

/// One state of the bar: its centre at (1, 1, 1), turned by 90° about the
/// global z axis (its body x axis along global y), so its local (∓0.5, 0, 0)
/// are at (1, 0.5, 1) and (1, 1.5, 1).
const STATE: &str = "t,u:bar.x,u:bar.y,u:bar.z,u:bar.e0,u:bar.e1,u:bar.e2,u:bar.e3\n\
                     0,1,1,1,0.7071067811865476,0,0,0.7071067811865476\n";

/// The points of the SVG elements on the page's lines that contain all of
/// `marks`, each as `[x, y]` px.
fn svg_points(page: &str, marks: &[&str]) -> Vec<Vec<[f64; 2]>> {
    page.lines()
        .filter(|l| marks.iter().all(|m| l.contains(m)))
        .filter_map(|l| l.split("points=\"").nth(1)?.split('"').next())
        .map(|list| {
            list.split(' ')
                .map(|xy| {
                    let (x, y) = xy.split_once(',').expect("x,y");
                    [x.parse().expect("x"), y.parse().expect("y")]
                })
                .collect()
        })
        .collect()
}

/// Whether pixel points `px` are the world points `world` (picture plane,
/// m) under one map `x → a + s x`, `y → b − s y` with `s > 0` (equal scales,
/// y up), to `tol` px.
fn one_view(px: &[[f64; 2]], world: &[[f64; 2]], tol: f64) -> Result<(), String> {
    // The scale from the two world points farthest apart.
    let d = |p: [f64; 2], q: [f64; 2]| (p[0] - q[0]).hypot(p[1] - q[1]);
    let (mut best, mut pair) = (0.0, (0, 0));
    for i in 0..world.len() {
        for j in 0..i {
            if d(world[i], world[j]) > best {
                (best, pair) = (d(world[i], world[j]), (i, j));
            }
        }
    }
    let s = d(px[pair.0], px[pair.1]) / best;
    let n = px.len() as f64;
    let a = px
        .iter()
        .zip(world)
        .map(|(p, w)| p[0] - s * w[0])
        .sum::<f64>()
        / n;
    let b = px
        .iter()
        .zip(world)
        .map(|(p, w)| p[1] + s * w[1])
        .sum::<f64>()
        / n;
    for (p, w) in px.iter().zip(world) {
        let expected = [a + s * w[0], b - s * w[1]];
        if d(*p, expected) > tol {
            return Err(format!(
                "{w:?} drawn at {p:?}, expected {expected:?} (s = {s})"
            ));
        }
    }
    Ok(())
}

#[test]
fn each_view_puts_body_points_where_the_projection_says() {
    let dir = scratch("animate-views");
    let (model_file, csv) = (dir.join("bar.toml"), dir.join("bar.csv"));
    std::fs::write(&model_file, BAR).expect("write");
    std::fs::write(&csv, STATE).expect("write");
    // The bar's points ball end, centre, rod end, and the ground points of
    // the ball and the rod, in [right, up] for each view, by hand:
    // oblique: (x + 0.5 cos 30° y, z + 0.5 sin 30° y).
    let c = 0.5 * 30f64.to_radians().cos();
    let views: [(&str, [[f64; 2]; 5]); 4] = [
        (
            "xz",
            [[1.0, 1.0], [1.0, 1.0], [1.0, 1.0], [0.0, 0.0], [2.0, 0.0]],
        ),
        (
            "yz",
            [[0.5, 1.0], [1.0, 1.0], [1.5, 1.0], [0.0, 0.0], [0.0, 0.0]],
        ),
        (
            "xy",
            [[1.0, 0.5], [1.0, 1.0], [1.0, 1.5], [0.0, 0.0], [2.0, 0.0]],
        ),
        (
            "oblique",
            [
                [1.0 + 0.5 * c, 1.0 + 0.125],
                [1.0 + c, 1.25],
                [1.0 + 1.5 * c, 1.0 + 0.375],
                [0.0, 0.0],
                [2.0, 0.0],
            ],
        ),
    ];
    for (view, world) in views {
        let html = dir.join(format!("{view}.html"));
        let mut args = vec!["animate", model_file.to_str().expect("path")];
        args.extend([csv.to_str().expect("path"), "--html"]);
        args.push(html.to_str().expect("path"));
        if view != "oblique" {
            // The default is the oblique view.
            args.extend(["--view", view]);
        }
        let ok = mstar(&args);
        assert!(ok.status.success(), "{view}: {}", text(&ok.stderr));
        let page = std::fs::read_to_string(&html).expect("the page");
        // The bar: one polyline, ball end → centre → rod end.
        let bar = svg_points(&page, &["<polyline", "<title>bar</title>"]);
        assert_eq!(bar.len(), 1, "{view}: {bar:?}");
        assert_eq!(bar[0].len(), 3, "{view}: {bar:?}");
        // Each ground point under its symbol (the triangle's apex), once
        // (the yz view sees both at the same place).
        let grounds: Vec<[f64; 2]> = svg_points(&page, &["<polygon", "fill=\"#dddddd\""])
            .iter()
            .map(|p| p[0])
            .collect();
        let distinct = if view == "yz" { 1 } else { 2 };
        assert_eq!(grounds.len(), distinct, "{view}: {grounds:?}");
        let px: Vec<[f64; 2]> = bar[0].iter().chain(&grounds).copied().collect();
        one_view(&px, &world[..3 + distinct], 0.3).unwrap_or_else(|e| panic!("{view}: {e}"));
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// The bar of [`BAR`] as a solid, seen from the side (`yz`, looking along
/// −x) in [`STATE`]. Its box by hand: m = 1 kg, I = (0.001, 0.1, 0.1) kg m²
/// give sides a = √(6 (0.1 + 0.1 − 0.001)) = 1.0927 m and
/// b = c = √(6 · 0.001) = 0.07746 m. Turned 90° about z, its body −y face
/// looks along +x, toward the viewer: the only face drawn, y from
/// 1 ∓ 0.54635, z from 1 ∓ 0.03873. The light l = (1, −0.4, 0.6)/√1.52
/// (toward the viewer, up, left) meets it at n·l = 1/√1.52: brightness
/// 0.3 + 0.7/√1.52 = 0.8678, the body colour (31, 119, 180) becomes
/// (27, 103, 156), #1b679c. The PNG shows that colour inside the face,
/// off the stick figure drawn over it.
#[test]
fn a_spatial_body_is_a_shaded_box_of_its_inertia() {
    let dir = scratch("animate-solid");
    let (model_file, csv) = (dir.join("bar.toml"), dir.join("bar.csv"));
    std::fs::write(&model_file, BAR).expect("write");
    std::fs::write(&csv, STATE).expect("write");
    let (html, png) = (dir.join("bar.html"), dir.join("bar.png"));
    let ok = mstar(&[
        "animate",
        &path(&model_file),
        &path(&csv),
        "--html",
        &path(&html),
        "--png",
        &path(&png),
        "--view",
        "yz",
    ]);
    assert!(ok.status.success(), "{}", text(&ok.stderr));
    // The page's drawing for a browser without script is the PNG's.
    let page = std::fs::read_to_string(&html).expect("the page");
    let faces = svg_points(&page, &["<polygon", "<title>bar</title>"]);
    assert_eq!(faces.len(), 1, "{faces:?}");
    let shaded = svg_points(&page, &["<polygon", "fill=\"#1b679c\""]);
    assert_eq!(shaded, faces, "the face's colour");
    let (h, w) = (0.546_35, 0.038_73);
    let world = [
        [1.0 - h, 1.0 - w],
        [1.0 + h, 1.0 - w],
        [1.0 - h, 1.0 + w],
        [1.0 + h, 1.0 + w],
    ];
    let mut corners = faces[0].clone();
    // In the order of `world`: left to right, then bottom (larger y px) first.
    corners.sort_by(|p, q| p[1].total_cmp(&q[1]).reverse().then(p[0].total_cmp(&q[0])));
    one_view(&corners, &world, 0.3).unwrap_or_else(|e| panic!("{e}: {corners:?}"));
    // In the PNG: a quarter of the way along the face, halfway between the
    // stick figure (7 px wide on the face's middle line, plus a pixel of
    // anti-aliasing) and the face's 1 px outline.
    let (left, right) = (corners[0], corners[1]);
    let top = corners[2];
    let x = 0.75 * left[0] + 0.25 * right[0];
    let middle = 0.5 * (left[1] + top[1]);
    let half = 0.5 * (left[1] - top[1]);
    assert!(
        half > 7.0,
        "the face is {} px high: too thin to probe",
        2.0 * half
    );
    let y = middle - 0.5 * ((3.5 + 1.0) + (half - 1.0));
    let pixel = png_pixel(&png, x, y);
    assert_eq!(pixel, [27, 103, 156], "at ({x}, {y})");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The RGB of pixel (x, y) of a PNG picture.
fn png_pixel(file: &Path, x: f64, y: f64) -> [u8; 3] {
    let bytes = std::fs::read(file).expect("the picture");
    let decoder = png::Decoder::new(bytes.as_slice());
    let mut reader = decoder.read_info().expect("a PNG");
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).expect("a frame");
    let channels = info.color_type.samples();
    let i = (y.round() as usize * info.width as usize + x.round() as usize) * channels;
    [buf[i], buf[i + 1], buf[i + 2]]
}

#[test]
fn a_wrong_view_is_refused_with_the_views_there_are() {
    let dir = scratch("animate-view-errors");
    let (model_file, csv) = (dir.join("bar.toml"), dir.join("bar.csv"));
    std::fs::write(&model_file, BAR).expect("write");
    std::fs::write(&csv, STATE).expect("write");
    let png = dir.join("frame.png");
    let unknown = mstar(&[
        "animate",
        &path(&model_file),
        &path(&csv),
        "--png",
        &path(&png),
        "--view",
        "zx",
    ]);
    assert_eq!(unknown.status.code(), Some(2));
    let e = text(&unknown.stderr);
    assert!(
        e.contains("invalid value 'zx' for '--view <VIEW>'")
            && e.contains("[possible values: oblique, xz, yz, xy]"),
        "{e}"
    );
    // A planar model is drawn in its own plane: --view is an error there.
    let planar_csv = dir.join("four-bar.csv");
    let ran = mstar(&[
        "run",
        &model("four-bar.toml"),
        "--t-end",
        "0.01",
        "--out",
        &path(&planar_csv),
    ]);
    assert!(ran.status.success(), "{}", text(&ran.stderr));
    let planar = mstar(&[
        "animate",
        &model("four-bar.toml"),
        &path(&planar_csv),
        "--png",
        &path(&png),
        "--view",
        "xy",
    ]);
    assert_eq!(planar.status.code(), Some(2));
    let e = text(&planar.stderr);
    assert!(
        e.contains("--view is for spatial models") && e.contains("four-bar.toml is planar"),
        "{e}"
    );
    assert!(!png.exists());
    let _ = std::fs::remove_dir_all(&dir);
}
