//! `mstar convert`: a URDF robot written as the `mstar.spatial/1` model file
//! it means (docs/model-format.md, "URDF robots").

use std::io::Write as _;
use std::path::PathBuf;
use std::process::ExitCode;

/// Arguments of `mstar convert`.
#[derive(clap::Args, Debug)]
pub struct ConvertArgs {
    /// The URDF file (`.urdf`).
    urdf: PathBuf,
    /// The `mstar.spatial/1` TOML file to write (`-` or none: standard output).
    #[arg(long, value_name = "FILE")]
    out: Option<PathBuf>,
}

/// `mstar convert`: exit 0 when written, 2 when the URDF cannot be read or
/// converted, 1 when the output cannot be written.
pub fn convert(args: &ConvertArgs) -> ExitCode {
    if let Some(out) = args.out.as_deref().filter(|p| p.as_os_str() != "-")
        && let Err(e) =
            crate::output::refuse_overwrites(&[("the URDF file", &args.urdf)], &[("--out", out)])
    {
        note!("error: {e}");
        return ExitCode::from(2);
    }
    let origin = args.urdf.display().to_string();
    let text = match std::fs::read_to_string(&args.urdf) {
        Ok(text) => text,
        Err(e) => {
            note!("error: {origin}: cannot read the URDF file: {e}");
            return ExitCode::from(2);
        }
    };
    let (document, notes) = match mstar::file::convert_urdf(&text, &origin) {
        Ok(converted) => converted,
        Err(e) => {
            note!("error: {e}");
            return ExitCode::from(2);
        }
    };
    for n in &notes {
        note!("warning: {n}");
    }
    let written = match args.out.as_deref() {
        Some(path) if path.as_os_str() != "-" => {
            mstar::csv::write_atomically(path, document.as_bytes())
                .map_err(|e| format!("{}: cannot write the model file: {e}", path.display()))
        }
        _ => std::io::stdout()
            .write_all(document.as_bytes())
            .map_err(|e| format!("standard output: {e}")),
    };
    match written {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            note!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
