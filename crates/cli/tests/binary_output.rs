//! `--out RUN.npz` (docs/model-format.md, "Binary output"): the archive is
//! read here by a reader written from the formats' specifications (PKWARE's
//! APPNOTE 6.3.9: end records, ZIP64 records, central directory; NumPy's
//! NEP 1 `.npy` headers), each entry's CRC-32 checked; its columns are the
//! CSV file's names and its values the CSV file's numbers, bit for bit, with
//! and without a column choice; a failed run keeps `<stem>.partial.npz`,
//! itself a valid archive of the rows before the failure.

mod common;

use std::collections::HashMap;
use std::path::Path;

use common::{model, mstar, scratch, text};

fn u16_at(b: &[u8], at: usize) -> usize {
    usize::from(u16::from_le_bytes([b[at], b[at + 1]]))
}

fn u32_at(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes(b[at..at + 4].try_into().expect("4 bytes"))
}

fn u64_at(b: &[u8], at: usize) -> usize {
    usize::try_from(u64::from_le_bytes(
        b[at..at + 8].try_into().expect("8 bytes"),
    ))
    .expect("fits")
}

/// The stored entries of a ZIP archive by name (CRC-32 checked), found from
/// the end records as a reader must (APPNOTE §4.3.16, §4.3.15, §4.3.14).
fn entries(zip: &[u8]) -> HashMap<String, Vec<u8>> {
    let eocd = zip.len() - 22;
    assert_eq!(u32_at(zip, eocd), 0x0605_4b50, "end of central directory");
    let locator = eocd - 20;
    assert_eq!(u32_at(zip, locator), 0x0706_4b50, "ZIP64 locator");
    let end64 = u64_at(zip, locator + 8);
    assert_eq!(u32_at(zip, end64), 0x0606_4b50, "ZIP64 end record");
    let (count, cd) = (u64_at(zip, end64 + 32), u64_at(zip, end64 + 48));
    let mut out = HashMap::new();
    let mut at = cd;
    for _ in 0..count {
        assert_eq!(u32_at(zip, at), 0x0201_4b50, "central header");
        assert_eq!(u16_at(zip, at + 10), 0, "stored");
        let crc = u32_at(zip, at + 16);
        let (name_len, extra_len, comment) = (
            u16_at(zip, at + 28),
            u16_at(zip, at + 30),
            u16_at(zip, at + 32),
        );
        let name = String::from_utf8(zip[at + 46..at + 46 + name_len].to_vec()).expect("name");
        let mut size = u32_at(zip, at + 24) as usize;
        let offset = u32_at(zip, at + 42) as usize;
        let extra = &zip[at + 46 + name_len..at + 46 + name_len + extra_len];
        if size == u32::MAX as usize {
            assert_eq!(u16_at(extra, 0), 1, "ZIP64 extra field");
            size = u64_at(extra, 4);
        }
        assert_eq!(u32_at(zip, offset), 0x0403_4b50, "local header");
        let start = offset + 30 + u16_at(zip, offset + 26) + u16_at(zip, offset + 28);
        let data = zip[start..start + size].to_vec();
        assert_eq!(crc32fast::hash(&data), crc, "CRC-32 of {name}");
        out.insert(name, data);
        at += 46 + name_len + extra_len + comment;
    }
    out
}

/// A `.npy` array: its `descr`, its shape and its data bytes (NEP 1).
fn npy(bytes: &[u8]) -> (String, Vec<usize>, &[u8]) {
    assert_eq!(&bytes[..6], b"\x93NUMPY");
    let (len, start) = match bytes[6] {
        1 => (u16_at(bytes, 8), 10),
        _ => (u32_at(bytes, 8) as usize, 12),
    };
    assert_eq!((start + len) % 64, 0, "aligned data");
    let header = std::str::from_utf8(&bytes[start..start + len]).expect("ASCII");
    let field = |key: &str| {
        let from = header.find(key).expect("key") + key.len();
        header[from..].trim_start_matches([':', ' ', '\''])
    };
    let descr = field("'descr'")
        .split('\'')
        .next()
        .expect("descr")
        .to_string();
    assert!(field("'fortran_order'").starts_with("False"));
    let shape = field("'shape'");
    let shape: Vec<usize> = shape[1..shape.find(')').expect("tuple")]
        .split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(|s| s.parse().expect("a dimension"))
        .collect();
    (descr, shape, &bytes[start + len..])
}

/// The names and rows of an `.npz` written by `mstar run`.
fn read_npz(path: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let zip = std::fs::read(path).expect("the archive");
    let e = entries(&zip);
    let (descr, shape, data) = npy(&e["columns.npy"]);
    let width: usize = descr
        .strip_prefix("<U")
        .expect("unicode")
        .parse()
        .expect("width");
    let names = data
        .chunks(4 * width)
        .map(|name| {
            name.chunks(4)
                .map(|c| u32::from_le_bytes(c.try_into().expect("4 bytes")))
                .take_while(|&c| c != 0)
                .map(|c| char::from_u32(c).expect("a character"))
                .collect()
        })
        .collect::<Vec<String>>();
    assert_eq!(shape, vec![names.len()]);
    let (descr, shape, data) = npy(&e["data.npy"]);
    assert_eq!(descr, "<f8");
    assert_eq!(shape.len(), 2);
    assert_eq!(shape[1], names.len());
    assert_eq!(data.len(), 8 * shape[0] * shape[1]);
    let rows = data
        .chunks(8 * shape[1])
        .map(|row| {
            row.chunks(8)
                .map(|x| f64::from_le_bytes(x.try_into().expect("8")))
                .collect()
        })
        .collect();
    (names, rows)
}

fn read_csv(path: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let body = std::fs::read_to_string(path).expect("the CSV file");
    let mut lines = body.lines();
    let names = lines
        .next()
        .expect("header")
        .split(',')
        .map(String::from)
        .collect();
    let rows = lines
        .map(|l| l.split(',').map(|x| x.parse().expect("a number")).collect())
        .collect();
    (names, rows)
}

/// The same run to `.csv` and `.npz`, all columns and a choice of them:
/// the same names and the same numbers, bit for bit (CSV numbers are in
/// shortest round-trip form).
#[test]
fn an_npz_holds_the_csv_columns_to_the_bit() {
    let dir = scratch("npz");
    // The four-bar with a sensor of each kind of column it makes.
    let base = std::fs::read_to_string(model("four-bar.toml")).expect("the model");
    let sensors = dir.join("four-bar-sensors.toml");
    let extra = "\n[[sensor]]\nname = \"tip\"\ntype = \"acceleration\"\nbody = \"coupler\"\npoint = [0.3, 0.0]\n\n[[sensor]]\nname = \"gap\"\ntype = \"distance\"\nbodies = [\"ground\", \"rocker\"]\n";
    std::fs::write(&sensors, format!("{base}{extra}")).expect("written");
    let sensors = sensors.display().to_string();
    for choice in [
        None,
        Some("t,u:crank.*,reaction:O2.*,effort:motor"),
        Some("t,sensor:*"),
    ] {
        let mut outputs = Vec::new();
        for ext in ["csv", "npz"] {
            let out = dir.join(format!("run.{ext}"));
            let file = if choice == Some("t,sensor:*") {
                sensors.clone()
            } else {
                model("four-bar.toml")
            };
            let (m, o) = (file, out.display().to_string());
            let mut args = vec!["run", m.as_str(), "--t-end", "0.05", "--out", o.as_str()];
            if let Some(c) = choice {
                args.extend(["--columns", c]);
            }
            let r = mstar(&args);
            assert!(r.status.success(), "{}", text(&r.stderr));
            outputs.push(out);
        }
        let (csv_names, csv_rows) = read_csv(&outputs[0]);
        let (npz_names, npz_rows) = read_npz(&outputs[1]);
        assert_eq!(npz_names, csv_names);
        assert_eq!(npz_rows.len(), 51);
        for (a, b) in npz_rows.iter().zip(&csv_rows) {
            let same = a
                .iter()
                .zip(b)
                .all(|(x, y)| x.to_bits() == y.to_bits() || (*x == 0.0 && *y == 0.0));
            assert!(same, "{a:?}\n{b:?}");
        }
        match choice {
            Some("t,sensor:*") => assert_eq!(
                npz_names,
                ["t", "sensor:tip.x", "sensor:tip.y", "sensor:gap"]
            ),
            Some(_) => assert_eq!(npz_names.len(), 1 + 3 + 3 + 1),
            None => {}
        }
    }
}

/// A run that fails part way keeps `<stem>.partial.npz`: a valid archive of
/// the rows before the failure (the rows the CSV output keeps), and no
/// `fast.npz`.
#[test]
fn a_failed_run_keeps_a_valid_partial_npz() {
    let dir = scratch("npz-partial");
    let mut kept = Vec::new();
    for ext in ["csv", "npz"] {
        let out = dir.join(format!("fast.{ext}"));
        let failed = mstar(&[
            "run",
            &model("slider-crank.toml"),
            "--h",
            "0.05",
            "--set",
            "simulation.h_min=0.05",
            "--set",
            "simulation.max_iterations=2",
            "--out",
            &out.display().to_string(),
        ]);
        assert_eq!(failed.status.code(), Some(1), "{}", text(&failed.stderr));
        assert!(!out.exists());
        let partial = format!("fast.partial.{ext}");
        assert!(
            text(&failed.stderr).contains(&partial),
            "{}",
            text(&failed.stderr)
        );
        kept.push(dir.join(partial));
    }
    let (csv_names, csv_rows) = read_csv(&kept[0]);
    let (names, rows) = read_npz(&kept[1]);
    assert_eq!(names, csv_names);
    assert!(!rows.is_empty());
    assert_eq!(rows, csv_rows);
}

/// An `.npz` needs a file it can seek in: a FIFO is refused before it is
/// opened (which would wait for a reader), with advice.
#[cfg(unix)]
#[test]
fn an_npz_to_a_fifo_is_refused() {
    let dir = scratch("npz-fifo");
    let fifo = dir.join("pipe.npz");
    let made = std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .expect("mkfifo runs");
    assert!(made.success());
    let r = mstar(&[
        "run",
        &model("pendulum.toml"),
        "--t-end",
        "0.01",
        "--out",
        &fifo.display().to_string(),
    ]);
    let err = text(&r.stderr);
    assert_eq!(r.status.code(), Some(1), "{err}");
    assert!(
        err.contains("an .npz output must be a regular file"),
        "{err}"
    );
}

/// `mstar animate` reads a run's `.npz` as it reads its CSV file: the same
/// picture, byte for byte.
#[test]
fn animate_draws_an_npz_as_its_csv() {
    let dir = scratch("npz-animate");
    let mut pictures = Vec::new();
    for ext in ["csv", "npz"] {
        let out = dir.join(format!("run.{ext}"));
        let r = mstar(&[
            "run",
            &model("four-bar.toml"),
            "--t-end",
            "0.2",
            "--out",
            &out.display().to_string(),
        ]);
        assert!(r.status.success(), "{}", text(&r.stderr));
        let png = dir.join(format!("{ext}.png"));
        let r = mstar(&[
            "animate",
            &model("four-bar.toml"),
            &out.display().to_string(),
            "--png",
            &png.display().to_string(),
        ]);
        assert!(r.status.success(), "{}", text(&r.stderr));
        pictures.push(std::fs::read(&png).expect("the picture"));
    }
    assert!(pictures[0] == pictures[1], "the pictures differ");
}
