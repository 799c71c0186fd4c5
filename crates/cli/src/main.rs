//! The `mstar` command-line program (the library, `src/lib.rs`, is all of it).

use std::process::ExitCode;

fn main() -> ExitCode {
    ExitCode::from(mstar_cli::main_from(std::env::args_os()))
}
