//! Runs too large to be meant, refused before they start: more steps than
//! [`MAX_STEPS`], an output file larger than the free space of its file
//! system, or a model larger than the memory available. Each refusal gives
//! the estimate and values of the options that would pass.

use std::path::Path;

use anyhow::{Result, bail};
use mstar::newmark::Short;

/// The most steps one run may take: 10⁹ steps are hours of computing and,
/// with an output file, hundreds of gigabytes; a longer run is a mistake in
/// `--t-end` or `--h` far more often than it is meant.
pub const MAX_STEPS: f64 = 1e9;

/// Bytes a CSV field takes on average (measured: 15 to 20 for numbers in
/// shortest round-trip form with their comma, 2 for zeros): a low estimate,
/// so that no run that fits is refused.
pub const BYTES_PER_FIELD: f64 = 14.0;

/// The most bytes a CSV field takes (`-1.2345678901234567e-100,`): the
/// advice of a refusal is worked out with it, so that what it suggests fits.
pub const MAX_BYTES_PER_FIELD: f64 = 25.0;

/// Memory a chain link needs with a sparse KKT solver (peak resident size
/// over 1 000 to 300 000 links: 5.1 kB with Schur, 7.3 kB with LDLᵀ, 8.1 kB
/// with sparse LU).
pub const BYTES_PER_LINK: f64 = 8.1e3;

/// Memory a dense KKT solver needs for `unknowns` unknowns (the matrix and
/// its LU factors, 8-byte entries).
pub fn dense_bytes(unknowns: f64) -> f64 {
    16.0 * unknowns * unknowns
}

/// Bytes a pendulum sample takes in memory (the reference keeps them all):
/// 11 numbers in four vectors, their headers and the allocator's overhead.
pub const BYTES_PER_PENDULUM_SAMPLE: f64 = 400.0;

/// A size in bytes for messages: "27.5 GB".
pub fn bytes(x: f64) -> String {
    let units = ["B", "kB", "MB", "GB", "TB", "PB", "EB"];
    let mut v = x;
    let mut unit = 0;
    while v >= 1000.0 && unit + 1 < units.len() {
        v /= 1000.0;
        unit += 1;
    }
    if unit == units.len() - 1 && v >= 1000.0 {
        return format!("{x:.1e} B");
    }
    format!("{v:.1} {}", units[unit])
}

/// A number for messages: at most 6 significant digits ([`Short`]).
pub fn num(x: f64) -> String {
    Short(x).to_string()
}

/// A count for messages: "about 1.2e10", or "more than 1e308" when it
/// overflows.
pub fn about(x: f64) -> String {
    if x.is_finite() {
        format!("about {}", Short(x))
    } else {
        "more than 1e308".to_string()
    }
}

/// The time resolution of a run, in step sizes (`Integrator::reached`).
pub const RESOLUTION: f64 = 1e-9;

/// `x` to two significant digits, rounded up (`up`) or down, as text that
/// parses back to a value on the same side of `x`.
pub fn round2(x: f64, up: bool) -> String {
    if !(x.is_finite() && x > 0.0) {
        return num(x);
    }
    let e = x.log10().floor();
    let m = x / 10f64.powf(e);
    let mut digits = if up {
        (m * 10.0).ceil()
    } else {
        (m * 10.0).floor()
    };
    // (A digit more or less at most: the text parses to the nearest double.)
    for _ in 0..4 {
        // (99 rounded up is 10e-1: written 1e0.)
        let text = if digits >= 100.0 {
            format!("{}e{}", digits / 100.0, e + 1.0)
        } else {
            format!("{}e{}", digits / 10.0, e)
        };
        match text.parse::<f64>() {
            Ok(v) if (up && v >= x) || (!up && v <= x) => return text,
            _ => digits += if up { 1.0 } else { -1.0 },
        }
    }
    num(x)
}

/// Refuses more than [`MAX_STEPS`] steps of `h` to `t_end` (step control
/// only shortens steps: t_end / h is the fewest the run takes).
///
/// # Errors
/// Too many steps, with the estimate and a `--h` and a `--t-end` that pass.
pub fn check_steps(t_end: f64, h: f64) -> Result<f64> {
    // `Integrator::reached` counts a t_end within 1e-9 h as reached: the
    // run would end at t = 0 without a step.
    let resolution = RESOLUTION * h;
    if t_end <= resolution {
        return Err(crate::output::usage(format!(
            "t_end = {} s is within the time resolution of a run with h = {} s ({} s): it would \
             end at t = 0 without a step; use a --t-end above {} s, or a smaller --h",
            num(t_end),
            num(h),
            num(resolution),
            num(resolution)
        )));
    }
    let steps = t_end / h;
    if steps <= MAX_STEPS {
        return Ok(steps);
    }
    bail!(
        "t_end = {} s with h = {} s is {} steps, more than the {MAX_STEPS:e} \
         that mstar takes in one run: use a larger step (--h {} or more) or a shorter run \
         (--t-end {} or less)",
        num(t_end),
        num(h),
        about(steps),
        round2(t_end / MAX_STEPS, true),
        round2(h * MAX_STEPS, false)
    )
}

/// The most rows one output may get with rows every Δt (`--output-every`),
/// as [`MAX_STEPS`] for steps: also for devices and standard output, which
/// have no free space to check.
pub const MAX_ROWS: f64 = 1e9;

/// Refuses more than [`MAX_ROWS`] rows (`rows`: the grid's `t_end / dt`
/// and the last state). `on_disk` is the most grid rows the output's file
/// system holds ([`grid_rows_on_disk`]), when known: the advice fits it
/// too, so that [`check_output`] passes the run that follows it.
///
/// # Errors
/// Too many rows, with the estimate and an `--output-every` and a `--t-end`
/// that pass.
pub fn check_rows(rows: f64, (t_end, h): (f64, f64), dt: f64, on_disk: Option<f64>) -> Result<()> {
    if rows <= MAX_ROWS {
        return Ok(());
    }
    // Room for the grid's two extra rows (t = 0 and the last state).
    let fit = (MAX_ROWS - 2.0).min(on_disk.unwrap_or(f64::INFINITY));
    if fit < 1.0 {
        bail!(
            "--output-every {} s to t_end = {} s is {} rows, more than the {MAX_ROWS:e} that \
             mstar writes in one run, and not even a few rows fit on the output's file system: \
             write to another file system, or no --out",
            Short(dt),
            Short(t_end),
            about(rows)
        );
    }
    let disk = if fit < MAX_ROWS - 2.0 {
        format!(
            ", and the free space of the output's file system holds {} rows",
            about(fit)
        )
    } else {
        String::new()
    };
    // A shorter run only where it still takes a step (`check_steps`).
    let shorter = round2(dt * fit, false);
    let shorter = match shorter.parse::<f64>() {
        Ok(t) if t > RESOLUTION * h => format!(" or a shorter run (--t-end {shorter} or less)"),
        _ => String::new(),
    };
    bail!(
        "--output-every {} s to t_end = {} s is {} rows, more than the {MAX_ROWS:e} \
         that mstar writes in one run{disk}: write fewer rows (--output-every {} or more){shorter}",
        Short(dt),
        Short(t_end),
        about(rows),
        round2(t_end / fit, true)
    )
}

/// The free space of the file system `path` would be written to, bytes
/// (`None` when it cannot be told, or for standard output and devices).
pub fn free_space(path: &Path) -> Option<f64> {
    let mstar::csv::Target::Replace(target) = mstar::csv::target(path).ok()? else {
        return None;
    };
    let dir = match target.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => std::path::PathBuf::from("."),
    };
    free_space_of(&dir)
}

/// The free space of the file system of directory `dir`, or of its nearest
/// ancestor that exists (where a directory yet to be made would be).
pub fn free_space_of(dir: &Path) -> Option<f64> {
    // (A relative path's last ancestor is "": the current directory.)
    let dir = dir
        .ancestors()
        .map(|d| {
            if d.as_os_str().is_empty() {
                Path::new(".")
            } else {
                d
            }
        })
        .find(|d| d.exists())?;
    statvfs_available(dir)
}

/// The bytes an unprivileged user may still write on `dir`'s file system
/// (statvfs(3): available blocks × fragment size).
#[cfg(unix)]
fn statvfs_available(dir: &Path) -> Option<f64> {
    let c = std::ffi::CString::new(dir.as_os_str().as_encoded_bytes()).ok()?;
    let mut stat = std::mem::MaybeUninit::<libc::statvfs>::zeroed();
    // SAFETY: `c` is a NUL-terminated path, `stat` a buffer of the right type.
    let rc = unsafe { libc::statvfs(c.as_ptr(), stat.as_mut_ptr()) };
    if rc != 0 {
        return None;
    }
    // SAFETY: statvfs filled it in.
    let stat = unsafe { stat.assume_init() };
    Some(stat.f_bavail as f64 * stat.f_frsize as f64)
}

/// Unknown outside Unix: the checks that need it are skipped.
#[cfg(not(unix))]
fn statvfs_available(_: &Path) -> Option<f64> {
    None
}

/// An output's size, rows and fields a row, and the options that shrink it.
pub struct Output<'a> {
    /// The file.
    pub path: &'a Path,
    /// Rows it would get.
    pub rows: f64,
    /// Fields a row.
    pub fields: usize,
    /// The run's end time, s (for the advice).
    pub t_end: f64,
    /// Rows every Δt seconds (`--output-every`, `[output] every_time`)
    /// instead of every step.
    pub every_time: Option<f64>,
}

/// The most rows of a time grid (less its first and last states and the
/// header) that `free` bytes hold, `fields` fields a row at the largest
/// size a field can take in the format of `path`.
pub fn grid_rows_on_disk(path: &Path, fields: usize, free: f64) -> f64 {
    // An `.npz` field is one double, 8 bytes exactly.
    let max_per_field = if mstar::csv::is_npz(path) {
        8.0
    } else {
        MAX_BYTES_PER_FIELD
    };
    (free / (fields as f64 * max_per_field)).floor() - 3.0
}

/// Refuses an output file larger than the free space of its file system.
///
/// The advice is a time grid of rows (`--output-every`), never a larger
/// step or fewer steps a row: a run halves its step where Newton fails, so
/// rows counted in steps are not known before the run, while a grid's rows
/// are (`t_end / Δt` and the last state). With a grid already given, a
/// shorter run is advised too.
///
/// # Errors
/// With the estimate, the free space, and the values that fit.
pub fn check_output(o: &Output<'_>, free: Option<f64>) -> Result<()> {
    // An `.npz` field is one double, 8 bytes exactly.
    let per_field = if mstar::csv::is_npz(o.path) {
        8.0
    } else {
        BYTES_PER_FIELD
    };
    let size = o.rows * o.fields as f64 * per_field;
    let Some(free) = free else {
        return Ok(());
    };
    if size <= free {
        return Ok(());
    }
    let head = format!(
        "{} would take about {} ({:.1e} rows of about {}), more than the {} free on its file \
         system",
        o.path.display(),
        bytes(size),
        o.rows,
        bytes(o.fields as f64 * per_field),
        bytes(free)
    );
    // Rows that fit at the largest size a row can take, less one row's
    // room for the header and two for a grid's first and last states, and
    // no more than `check_rows` passes.
    let grid_rows = grid_rows_on_disk(o.path, o.fields, free).min(MAX_ROWS - 2.0);
    if grid_rows < 1.0 {
        bail!("{head}: not even a few rows fit; write to another file system, or no --out");
    }
    let dt = round2(o.t_end / grid_rows, true);
    match o.every_time {
        Some(every) => bail!(
            "{head}: write fewer rows (--output-every {dt} or more), a shorter run (--t-end {} \
             or less), or no --out",
            round2(every * grid_rows, false)
        ),
        None => bail!(
            "{head}: write a row every Δt seconds instead of every step (--output-every {dt} or \
             more: the rows then do not depend on the steps), or no --out"
        ),
    }
}

/// Bytes a field of a sweep's summary row takes in memory until the sweep
/// ends (its text, the string's header and the allocator's overhead).
pub const BYTES_PER_SUMMARY_FIELD: f64 = 48.0;

/// Refuses a sweep whose runs' CSV files would not fit on the output
/// directory's file system (`free`), or whose summary would not fit in
/// memory (`available`).
///
/// # Errors
/// [`SweepError::TooLarge`] with the estimate and what fits: rows on a time
/// grid (`--set output.every_time=Δt`, whose rows the steps cannot
/// outgrow) or fewer runs.
pub fn check_sweep(
    e: &mstar::sweep::Estimate,
    grid_swept: bool,
    free: Option<f64>,
    available: Option<f64>,
) -> std::result::Result<(), mstar::sweep::SweepError> {
    use mstar::sweep::SweepError;
    let runs = e.runs as f64;
    let memory = runs * e.summary_fields as f64 * BYTES_PER_SUMMARY_FIELD;
    if let Some(available) = available
        && memory > available
    {
        return Err(SweepError::TooLarge(format!(
            "the summary of {} runs would take about {} of memory until the sweep ends, more \
             than the {} available: give fewer runs (at most {} in one process, or --shard I/N \
             over several)",
            e.runs,
            bytes(memory),
            bytes(available),
            Short((available / memory * runs).floor())
        )));
    }
    let size = (e.rows * e.fields as f64 + runs * e.summary_fields as f64) * BYTES_PER_FIELD;
    let Some(free) = free else {
        return Ok(());
    };
    if size <= free {
        return Ok(());
    }
    let head = format!(
        "the {} runs would write about {} ({:.1e} rows of about {}), more than the {} free on \
         the file system of --out",
        e.runs,
        bytes(size),
        e.rows,
        bytes(e.fields as f64 * BYTES_PER_FIELD),
        bytes(free)
    );
    // Each run's share of the free space at the largest field size, less
    // its summary row, a header row and a grid's first and last states.
    let share = free / runs / (e.fields as f64 * MAX_BYTES_PER_FIELD);
    let grid_rows = (share - e.summary_fields as f64 / e.fields as f64).floor() - 3.0;
    if grid_rows < 1.0 || grid_swept {
        return Err(SweepError::TooLarge(format!(
            "{head}: give fewer runs or larger output.every_time values, or an --out on a \
             larger file system"
        )));
    }
    Err(SweepError::TooLarge(format!(
        "{head}: write each run's rows on a time grid (add --set output.every_time={} or \
         more: the rows then do not depend on the steps), give fewer runs, or an --out on a \
         larger file system",
        round2(e.t_end / grid_rows, true)
    )))
}

/// The memory a new allocation can count on, bytes: `MemAvailable` of
/// `/proc/meminfo`, less when the address space (`ulimit -v`) or the control
/// group (`memory.max`) allows less; `None` when none can be read.
pub fn available_memory() -> Option<f64> {
    let meminfo = std::fs::read_to_string("/proc/meminfo").ok().and_then(|s| {
        s.lines()
            .find_map(|l| l.strip_prefix("MemAvailable:"))
            .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<f64>().ok())
            .map(|kb| kb * 1024.0)
    });
    let address_space = address_space_limit();
    let cgroup = std::fs::read_to_string("/sys/fs/cgroup/memory.max")
        .ok()
        .and_then(|max| max.trim().parse::<f64>().ok())
        .map(|max| {
            let used = std::fs::read_to_string("/sys/fs/cgroup/memory.current")
                .ok()
                .and_then(|c| c.trim().parse::<f64>().ok())
                .unwrap_or(0.0);
            max - used
        });
    [meminfo, address_space, cgroup]
        .into_iter()
        .flatten()
        .reduce(f64::min)
}

/// The soft limit of the address space (`ulimit -v`, getrlimit(2)), bytes;
/// `None` when unlimited.
#[cfg(unix)]
fn address_space_limit() -> Option<f64> {
    let mut limit = std::mem::MaybeUninit::<libc::rlimit>::zeroed();
    // SAFETY: `limit` is a buffer of the right type.
    if unsafe { libc::getrlimit(libc::RLIMIT_AS, limit.as_mut_ptr()) } != 0 {
        return None;
    }
    // SAFETY: getrlimit filled it in.
    let l = unsafe { limit.assume_init() };
    (l.rlim_cur != libc::RLIM_INFINITY).then_some(l.rlim_cur as f64)
}

/// No such limit outside Unix.
#[cfg(not(unix))]
fn address_space_limit() -> Option<f64> {
    None
}

/// Refuses a chain of `links` links that will not fit in `available` bytes.
///
/// # Errors
/// With the estimate and a `--links` that fits.
pub fn check_chain(links: usize, dense: bool, available: Option<f64>) -> Result<()> {
    let n = links as f64;
    let need = |n: f64| BYTES_PER_LINK * n + if dense { dense_bytes(5.0 * n) } else { 0.0 };
    let Some(available) = available else {
        return Ok(());
    };
    if need(n) <= available {
        return Ok(());
    }
    // The most links that fit (bisection: `need` grows with n).
    let (mut lo, mut hi) = (0.0_f64, n);
    while hi - lo > 1.0 {
        let mid = (0.5 * (lo + hi)).floor();
        if need(mid) <= available {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    bail!(
        "a chain of {links} links needs about {} of memory{}, more than the {} available: use \
         at most --links {lo}",
        bytes(need(n)),
        if dense {
            " with the dense KKT solver"
        } else {
            ""
        },
        bytes(available)
    )
}

/// Refuses an RK4 reference (which keeps every sample in memory) that will
/// not fit in `available` bytes.
///
/// # Errors
/// With the estimate and a `--h` and a `--t-end` that fit.
pub fn check_reference(t_end: f64, h: f64, available: Option<f64>) -> Result<()> {
    let samples = t_end / h + 2.0;
    let need = samples * BYTES_PER_PENDULUM_SAMPLE;
    let Some(available) = available else {
        return Ok(());
    };
    if need <= available {
        return Ok(());
    }
    let ratio = need / available;
    bail!(
        "the RK4 reference keeps its {samples:.1e} samples in memory, about {}, more than the {} \
         available: use a larger step (--h {} or more) or a shorter run (--t-end {} or less)",
        bytes(need),
        bytes(available),
        round2(h * ratio * 1.01, true),
        round2(t_end / ratio * 0.99, false)
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Pulls `--opt VALUE` out of a message.
    fn option(message: &str, opt: &str) -> f64 {
        let after = message
            .split(opt)
            .nth(1)
            .unwrap_or_else(|| panic!("no {opt} in: {message}"))
            .trim_start_matches([' ', '=']);
        let value = after.split([' ', ')', ',']).next().unwrap_or_default();
        value
            .parse()
            .unwrap_or_else(|_| panic!("{opt} {value} in: {message}"))
    }

    /// The `--h` and `--t-end` a refusal suggests each pass the check.
    #[test]
    fn step_advice_passes() {
        for (t_end, h) in [(1e308, 0.01), (1e7, 1e-3), (0.1, 1e-300), (12.3, 3.7e-9)] {
            let e = check_steps(t_end, h).expect_err("refused").to_string();
            assert!(e.contains("steps"), "{e}");
            assert!(check_steps(t_end, option(&e, "--h")).is_ok(), "{e}");
            assert!(check_steps(option(&e, "--t-end"), h).is_ok(), "{e}");
        }
        assert!(check_steps(10.0, 0.01).is_ok());
        assert!(check_steps(1.0, 1e-9).is_ok());
        assert!(check_steps(f64::INFINITY, 1.0).is_err());
    }

    #[test]
    fn output_advice_passes() {
        let path = Path::new("run.csv");
        let o = Output {
            path,
            rows: 1e8,
            fields: 16,
            t_end: 1e6,
            every_time: None,
        };
        let free = Some(1e9);
        // A file that follows the advice fits even at the largest field
        // size, with a header row.
        let fits = |rows: f64| (rows + 1.0) * 16.0 * MAX_BYTES_PER_FIELD <= 1e9;
        let e = check_output(&o, free).expect_err("refused").to_string();
        assert!(e.contains("22.4 GB") && e.contains("1.0 GB free"), "{e}");
        // Rows every step: a grid is advised, never a larger step (a run
        // halves steps where Newton fails, and its rows are not known).
        assert!(!e.contains("--h ") && !e.contains("output.every"), "{e}");
        let dt = option(&e, "--output-every");
        assert!(fits(1e6 / dt + 2.0), "{e}");
        assert!(check_output(&o, None).is_ok());
        // Rows every Δt: a larger Δt or a shorter run.
        let grid = Output {
            rows: 1e6 / 1e-2 + 2.0,
            every_time: Some(1e-2),
            ..o
        };
        let e = check_output(&grid, free).expect_err("refused").to_string();
        let dt = option(&e, "--output-every");
        let t_end = option(&e, "--t-end");
        for (t, dt) in [(1e6, dt), (t_end, 1e-2)] {
            assert!(fits(t / dt + 2.0), "{t} {dt}: {e}");
        }
        // Where not even a few rows fit, no option is advised.
        let e = check_output(&o, Some(1e3))
            .expect_err("refused")
            .to_string();
        assert!(
            e.contains("another file system") && !e.contains("--output-every"),
            "{e}"
        );
    }

    /// Rows every Δt refused as too many: the `--output-every` advised
    /// passes both the row count and, when the file system's free space
    /// binds, the free space; a `--t-end` is advised only where the run
    /// would still take a step.
    #[test]
    fn rows_advice_fits_the_free_space_too() {
        let path = Path::new("run.csv");
        let (t_end, h, fields) = (2.0, 1e-3, 40);
        for free in [None, Some(1e9), Some(1e13)] {
            let on_disk = free.map(|f| grid_rows_on_disk(path, fields, f));
            let e = check_rows(2e12, (t_end, h), 1e-12, on_disk)
                .expect_err("refused")
                .to_string();
            let dt = option(&e, "(--output-every");
            let rows = t_end / dt + 2.0;
            assert!(check_rows(rows, (t_end, h), dt, on_disk).is_ok(), "{e}");
            let o = Output {
                path,
                rows,
                fields,
                t_end,
                every_time: Some(dt),
            };
            assert!(check_output(&o, free).is_ok(), "{free:?}: {e}");
            let shorter = option(&e, "--t-end");
            assert!(t_end_passes(shorter, h, 1e-12, on_disk), "{e}");
        }
        let e = check_rows(2e300, (t_end, h), 1e-300, None)
            .expect_err("refused")
            .to_string();
        assert!(!e.contains("--t-end"), "{e}");
    }

    /// Whether a run to `t_end` with rows every `dt` passes `check_steps`
    /// and `check_rows`.
    fn t_end_passes(t_end: f64, h: f64, dt: f64, on_disk: Option<f64>) -> bool {
        check_steps(t_end, h).is_ok()
            && check_rows(t_end / dt + 2.0, (t_end, h), dt, on_disk).is_ok()
    }

    #[test]
    fn sweep_advice_passes() {
        let e = mstar::sweep::Estimate {
            runs: 1000,
            rows: 1000.0 * 1e6,
            fields: 15,
            summary_fields: 12,
            t_end: 100.0,
            every_step: true,
        };
        let free = 1e9;
        let m = check_sweep(&e, false, Some(free), None)
            .expect_err("refused")
            .to_string();
        let dt = option(&m, "output.every_time");
        // Every run on the advised grid, at the largest field size, with
        // a header and its summary row, fits.
        let per_run = (100.0 / dt + 3.0) * 15.0 + 12.0;
        assert!(1000.0 * per_run * MAX_BYTES_PER_FIELD <= free, "{m}");
        assert!(check_sweep(&e, false, None, None).is_ok());
        // The summary in memory: the advised number of runs fits.
        let m = check_sweep(&e, false, None, Some(1e5))
            .expect_err("refused")
            .to_string();
        let runs = option(&m, "at most");
        assert!(runs >= 1.0, "{m}");
        let fewer = mstar::sweep::Estimate {
            runs: runs as usize,
            ..e
        };
        assert!(check_sweep(&fewer, false, None, Some(1e5)).is_ok(), "{m}");
    }

    #[test]
    fn chain_advice_passes() {
        let available = Some(23e9);
        let e = check_chain(10_000_000, false, available)
            .expect_err("refused")
            .to_string();
        assert!(e.contains("81.0 GB"), "{e}");
        let links = option(&e, "--links") as usize;
        assert!(check_chain(links, false, available).is_ok(), "{e}");
        assert!(check_chain(links + 2, false, available).is_err(), "{e}");
        let e = check_chain(20_000, true, available)
            .expect_err("dense refused")
            .to_string();
        let links = option(&e, "--links") as usize;
        assert!(check_chain(links, true, available).is_ok(), "{e}");
        assert!(check_chain(usize::MAX, false, available).is_err());
        assert!(check_chain(1000, false, None).is_ok());
    }

    #[test]
    fn reference_advice_passes() {
        let available = Some(1e9);
        let e = check_reference(1e6, 1e-3, available)
            .expect_err("refused")
            .to_string();
        assert!(
            check_reference(1e6, option(&e, "--h"), available).is_ok(),
            "{e}"
        );
        assert!(
            check_reference(option(&e, "--t-end"), 1e-3, available).is_ok(),
            "{e}"
        );
    }

    #[test]
    fn sizes_read_well() {
        assert_eq!(bytes(275.0), "275.0 B");
        assert_eq!(bytes(27.5e9), "27.5 GB");
        assert_eq!(round2(1.234e7, false), "1.2e7");
        assert_eq!(round2(1.234e7, true), "1.3e7");
        assert_eq!(round2(1e299, true), "1e299");
        assert_eq!(round2(0.0995, true), "1e-1");
        assert_eq!(round2(9.96, true), "1e1");
        assert_eq!(num(1e308), "1e308");
        assert_eq!(num(0.01), "0.01");
    }
}
