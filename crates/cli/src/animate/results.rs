//! The CSV (or `.npz`) file of `mstar run` read back for a model: the times and, per row,
//! the coordinates of the model's bodies, found by column name
//! (`u:<body>.x`, `.y`, `.theta` of a planar model, `.x` … `.z`, `.e0` …
//! `.e3` of a spatial one) so that the column order does not matter.

use std::path::Path;

use anyhow::{Context as _, Result, bail};

/// The rows of a results file, in time order.
#[derive(Clone, Debug, PartialEq)]
pub struct Results {
    /// The time of each row, s (non-decreasing).
    pub times: Vec<f64>,
    /// The coordinates `u` of each row, indexed as the model's `u` (entries
    /// the drawing does not need stay 0).
    pub states: Vec<Vec<f64>>,
}

/// Which CSV column fills which entry of `u`.
struct Column {
    /// Position in the CSV record (0-based).
    field: usize,
    /// Index into `u`.
    coord: usize,
    /// The column's name, for messages.
    name: String,
}

/// Reads the results of `mstar run` for a model with `n_coords` coordinates
/// whose drawing needs the columns `wanted`, each `(name, index in u)` (as
/// [`Figure::columns`](super::figure::Figure::columns) lists them). A `<name>.partial.csv` from a failed run reads the
/// same way.
///
/// # Errors
/// If the file cannot be read, lacks a column the model needs, has no rows,
/// has a field that is not a finite number (named by line and column), or
/// goes back in time.
pub fn read(path: &Path, wanted: &[(String, usize)], n_coords: usize) -> Result<Results> {
    if mstar::csv::is_npz(path) {
        return read_npz(path, wanted, n_coords);
    }
    let file =
        std::fs::File::open(path).with_context(|| format!("could not read {}", path.display()))?;
    parse(std::io::BufReader::new(file), path, wanted, n_coords)
}

/// [`read`] from any reader; `path` names it in messages. Lines end in
/// `\n` or `\r\n` (a file saved on Windows): both are counted alike in
/// the line numbers of errors, and a blank line is skipped.
pub fn parse(
    reader: impl std::io::Read,
    path: &Path,
    wanted: &[(String, usize)],
    n_coords: usize,
) -> Result<Results> {
    let name = path.display();
    // Records end at `\n` only (a `\r` before it ends the last field, and
    // is trimmed), and lines are counted here: the reader's own count skips
    // blank lines, and the line ends of `\r\n` files.
    let mut lines = Lines::default();
    let mut csv = csv::ReaderBuilder::new()
        .has_headers(true)
        .flexible(true)
        .terminator(csv::Terminator::Any(b'\n'))
        .from_reader(lines.counting(reader));
    let header: csv::StringRecord = csv
        .headers()
        .with_context(|| format!("{name}: could not read the header"))?
        .iter()
        .map(|h| h.strip_suffix('\r').unwrap_or(h))
        .collect();
    let (time, columns) =
        columns(&header, wanted, n_coords).map_err(|e| anyhow::anyhow!("{name}: {e}"))?;
    let mut out = Results {
        times: Vec::new(),
        states: Vec::new(),
    };
    let mut record = csv::StringRecord::new();
    while csv
        .read_record(&mut record)
        .with_context(|| format!("{name}: could not read a row"))?
    {
        // The row's last byte, its `\n`: the reader places a row after a
        // blank line at the blank line.
        let line = lines.at(csv.position().byte().saturating_sub(1));
        if record.len() == 1 && record[0].trim().is_empty() {
            continue;
        }
        let at = Row {
            name: &name,
            record: &record,
            line,
        };
        at.check_len(header.len())?;
        let t = at.number(time, "t")?;
        if let Some(&before) = out.times.last()
            && t < before
        {
            bail!(
                "{name}:{line}: t = {} comes before the previous row's t = {}",
                mstar::newmark::Short(t),
                mstar::newmark::Short(before)
            );
        }
        let mut u = vec![0.0; n_coords];
        for c in &columns {
            u[c.coord] = at.number(c.field, &c.name)?;
        }
        out.times.push(t);
        out.states.push(u);
    }
    if out.times.is_empty() {
        bail!("{name}: no rows after the header");
    }
    Ok(out)
}

/// The line numbers of a file read through [`Lines::counting`]: the byte
/// offsets of the `\n`s read but not yet passed, and the line reached.
#[derive(Default)]
struct Lines {
    /// Offsets of the `\n`s read ahead, in order.
    ends: std::rc::Rc<std::cell::RefCell<std::collections::VecDeque<u64>>>,
    /// Line ends before the last offset asked for.
    passed: u64,
}

impl Lines {
    /// `reader`, noting each `\n` it reads.
    fn counting<R: std::io::Read>(&mut self, reader: R) -> LineEnds<R> {
        LineEnds {
            inner: reader,
            read: 0,
            ends: self.ends.clone(),
        }
    }

    /// The line (from 1) of byte `offset`; offsets come in increasing order.
    /// (A `\n` is the last byte of its line.)
    fn at(&mut self, offset: u64) -> u64 {
        let mut ends = self.ends.borrow_mut();
        while ends.front().is_some_and(|&end| end < offset) {
            ends.pop_front();
            self.passed += 1;
        }
        self.passed + 1
    }
}

/// A reader that notes where its `\n`s are ([`Lines`]).
struct LineEnds<R> {
    inner: R,
    /// Bytes read so far.
    read: u64,
    ends: std::rc::Rc<std::cell::RefCell<std::collections::VecDeque<u64>>>,
}

impl<R: std::io::Read> std::io::Read for LineEnds<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        let mut ends = self.ends.borrow_mut();
        for (i, _) in buf[..n].iter().enumerate().filter(|(_, b)| **b == b'\n') {
            ends.push_back(self.read + i as u64);
        }
        self.read += n as u64;
        Ok(n)
    }
}

/// A row of a results file, for its numbers and their errors.
struct Row<'a> {
    /// The file, for messages.
    name: &'a dyn std::fmt::Display,
    /// Its fields.
    record: &'a csv::StringRecord,
    /// Its line, from 1.
    line: u64,
}

impl Row<'_> {
    /// Refuses a row with another number of fields than the header's.
    fn check_len(&self, header: usize) -> Result<()> {
        if self.record.len() == header {
            return Ok(());
        }
        bail!(
            "{}:{}: {} fields, but the header has {header}: a row cut short or joined with \
             another (write the file again with mstar run)",
            self.name,
            self.line,
            self.record.len()
        )
    }

    /// The finite number in field `field` (column `column`).
    fn number(&self, field: usize, column: &str) -> Result<f64> {
        let text = self.record.get(field).unwrap_or_default().trim();
        match text.parse::<f64>() {
            Ok(x) if x.is_finite() => Ok(x),
            _ => bail!(
                "{}:{}:{}: column '{column}': '{text}' is not a finite number",
                self.name,
                self.line,
                field + 1
            ),
        }
    }
}

/// [`read`] of an `.npz` (`mstar run --out FILE.npz`): the same columns by
/// name, the same checks, rows counted from 1.
fn read_npz(path: &Path, wanted: &[(String, usize)], n_coords: usize) -> Result<Results> {
    let name = path.display();
    let (names, data) = mstar::npz::read(path).with_context(|| format!("could not read {name}"))?;
    let header = csv::StringRecord::from(names.clone());
    let (time, columns) =
        columns(&header, wanted, n_coords).map_err(|e| anyhow::anyhow!("{name}: {e}"))?;
    let mut out = Results {
        times: Vec::new(),
        states: Vec::new(),
    };
    for (k, row) in data.chunks_exact(names.len().max(1)).enumerate() {
        let number = |field: usize, column: &str| -> Result<f64> {
            match row.get(field) {
                Some(&x) if x.is_finite() => Ok(x),
                x => bail!(
                    "{name}: row {}: column '{column}': {x:?} is not a finite number",
                    k + 1
                ),
            }
        };
        let t = number(time, "t")?;
        if out.times.last().is_some_and(|&before| t < before) {
            bail!(
                "{name}: row {}: t = {} comes before the previous row's",
                k + 1,
                mstar::newmark::Short(t)
            );
        }
        let mut u = vec![0.0; n_coords];
        for c in &columns {
            u[c.coord] = number(c.field, &c.name)?;
        }
        out.times.push(t);
        out.states.push(u);
    }
    if out.times.is_empty() {
        bail!("{name}: no rows");
    }
    Ok(out)
}

/// The `t` column and the `wanted` columns.
fn columns(
    header: &csv::StringRecord,
    wanted: &[(String, usize)],
    n_coords: usize,
) -> Result<(usize, Vec<Column>)> {
    let find = |name: &str| -> Result<usize> {
        header.iter().position(|h| h == name).with_context(|| {
            format!("no column '{name}' — was it written by 'mstar run' for this model?")
        })
    };
    let time = find("t")?;
    let mut columns = Vec::new();
    for (name, coord) in wanted {
        if *coord >= n_coords {
            bail!("the model has no coordinate {coord} for column '{name}'");
        }
        columns.push(Column {
            field: find(name)?,
            coord: *coord,
            name: name.clone(),
        });
    }
    Ok((time, columns))
}

impl Results {
    /// The state at time `t`, linearly interpolated between the rows around
    /// it (the first or last row outside the run).
    #[must_use]
    pub fn at(&self, t: f64) -> Vec<f64> {
        let k = self.times.partition_point(|&s| s <= t);
        if k == 0 {
            return self.states[0].clone();
        }
        if k == self.times.len() {
            return self.states[k - 1].clone();
        }
        let (t0, t1) = (self.times[k - 1], self.times[k]);
        let w = if t1 > t0 { (t - t0) / (t1 - t0) } else { 0.0 };
        self.states[k - 1]
            .iter()
            .zip(&self.states[k])
            .map(|(a, b)| a + w * (b - a))
            .collect()
    }

    /// The first and the last time.
    #[must_use]
    pub fn span(&self) -> (f64, f64) {
        let first = self.times.first().copied().unwrap_or(0.0);
        (first, self.times.last().copied().unwrap_or(first))
    }

    /// At most `max` rows: all of them when there are no more, else `max`
    /// states at evenly spaced times over the run (interpolated).
    #[must_use]
    pub fn at_most(&self, max: usize) -> Self {
        if self.times.len() <= max || max < 2 {
            return self.clone();
        }
        let (t0, t1) = self.span();
        let times: Vec<f64> = (0..max)
            .map(|k| t0 + (t1 - t0) * k as f64 / (max - 1) as f64)
            .collect();
        let states = times.iter().map(|&t| self.at(t)).collect();
        Self { times, states }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::animate::figure::{Figure, PlanarFigure};
    use mstar::planar::{At, PlanarBuilder, PointMass, RigidBody, Sketch};

    /// A rigid body `a, b` (quotes and a comma in its name) and a point mass.
    fn sketch() -> Sketch {
        let mut b = PlanarBuilder::new();
        let bar = b.rigid_body(
            "a, \"b\"",
            RigidBody {
                mass: 1.0,
                inertia: 0.1,
                pose: [0.0; 3],
                velocity: [0.0; 3],
            },
        );
        let bob = b.point_mass(
            "bob",
            PointMass {
                mass: 1.0,
                position: [1.0, 0.0],
                velocity: [0.0; 2],
            },
        );
        b.distance(
            "rod",
            At::Body(bar, [0.5, 0.0]),
            At::Body(bob, [0.0, 0.0]),
            0.5,
        );
        b.build().expect("valid").sketch()
    }

    fn parse_text(text: &str) -> Result<Results> {
        let wanted = PlanarFigure::new(sketch()).columns();
        parse(text.as_bytes(), Path::new("r.csv"), &wanted, 5)
    }

    #[test]
    fn columns_are_found_by_name_in_any_order() {
        let text = "u:bob.y,t,\"u:a, \"\"b\"\".theta\",u:bob.x,\"u:a, \"\"b\"\".y\",energy,\"u:a, \"\"b\"\".x\"\n\
                    5,0,3,4,2,9,1\n\
                    50,1,30,40,20,9,10\n";
        let r = parse_text(text).expect("readable");
        assert_eq!(r.times, [0.0, 1.0]);
        assert_eq!(r.states[0], [1.0, 2.0, 3.0, 4.0, 5.0]);
        assert_eq!(r.states[1], [10.0, 20.0, 30.0, 40.0, 50.0]);
        let mid = r.at(0.25);
        assert!((mid[0] - 3.25).abs() < 1e-12, "{mid:?}");
        assert_eq!(r.at(-1.0), r.states[0]);
        assert_eq!(r.at(2.0), r.states[1]);
    }

    #[test]
    fn errors_name_the_column_and_the_place() {
        let missing = parse_text("t,u:bob.x,u:bob.y\n0,1,2\n").expect_err("no body columns");
        assert!(
            missing.to_string().contains(
                "r.csv: no column 'u:a, \"b\".x' — was it written by 'mstar run' for this model?"
            ),
            "{missing}"
        );
        let header = "t,\"u:a, \"\"b\"\".x\",\"u:a, \"\"b\"\".y\",\"u:a, \"\"b\"\".theta\",u:bob.x,u:bob.y\n";
        let bad = parse_text(&format!("{header}0,1,2,3,4,5\n0.1,1,2,x3,4,5\n")).expect_err("x3");
        assert!(
            bad.to_string()
                .contains("r.csv:3:4: column 'u:a, \"b\".theta': 'x3' is not a finite number"),
            "{bad}"
        );
        let back = parse_text(&format!("{header}1,1,2,3,4,5\n0.5,1,2,3,4,5\n")).expect_err("back");
        assert!(
            back.to_string().contains("r.csv:3: t = 0.5 comes before"),
            "{back}"
        );
        let empty = parse_text(header).expect_err("no rows");
        assert!(empty.to_string().contains("no rows"), "{empty}");
        let short = parse_text(&format!("{header}0,1,2,3,4,5\n0.1,1,2\n")).expect_err("short");
        assert!(
            short
                .to_string()
                .contains("r.csv:3: 3 fields, but the header has 6"),
            "{short}"
        );
    }

    /// A file whose lines end in `\r\n` reads as with `\n`, its errors at
    /// the same lines; blank lines are skipped.
    #[test]
    fn crlf_lines_are_counted_as_lf_lines() {
        let header = "t,\"u:a, \"\"b\"\".x\",\"u:a, \"\"b\"\".y\",\"u:a, \"\"b\"\".theta\",u:bob.x,u:bob.y\n";
        let rows = "0,1,2,3,4,5\n0.1,1,2,3,4,5\n\n0.2,1,2,x3,4,5\n";
        for ending in ["\n", "\r\n"] {
            let text = format!("{header}{rows}").replace('\n', ending);
            let bad = parse_text(&text).expect_err("x3");
            assert!(
                bad.to_string()
                    .contains("r.csv:5:4: column 'u:a, \"b\".theta': 'x3' is not a finite number"),
                "{ending:?}: {bad}"
            );
            let good = text.replace("x3", "3");
            let r = parse_text(&good).expect("readable");
            assert_eq!(r.times, [0.0, 0.1, 0.2], "{ending:?}");
            assert_eq!(r.states[2], [1.0, 2.0, 3.0, 4.0, 5.0], "{ending:?}");
            let short = parse_text(&text.replace("0.1,1,2,3,4,5", "0.1,1,2")).expect_err("short");
            assert!(
                short.to_string().contains("r.csv:3: 3 fields"),
                "{ending:?}: {short}"
            );
        }
    }

    #[test]
    fn long_runs_are_resampled_evenly() {
        let r = Results {
            times: (0..=100).map(|k| f64::from(k) * 0.01).collect(),
            states: (0..=100).map(|k| vec![f64::from(k)]).collect(),
        };
        let few = r.at_most(11);
        assert_eq!(few.times.len(), 11);
        assert!((few.times[10] - 1.0).abs() < 1e-12);
        assert!(
            (few.states[5][0] - 50.0).abs() < 1e-9,
            "{:?}",
            few.states[5]
        );
        assert_eq!(r.at_most(1000), r);
    }
}
