//! What the command-line tests share: running the `mstar` program, its
//! output as text, the paths of `models/`, scratch directories.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Runs `script` with `sh -c` in `dir`, the `mstar` program's path in `$M`
/// (for limits set with `ulimit` and redirections the test needs).
#[allow(dead_code)] // (used by the tests that need a shell)
pub fn sh(script: &str, dir: &Path) -> Output {
    Command::new("sh")
        .arg("-c")
        .arg(script)
        .env("M", env!("CARGO_BIN_EXE_mstar"))
        .current_dir(dir)
        .output()
        .expect("sh runs")
}

/// Runs the `mstar` program with `args`.
pub fn mstar(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mstar"))
        .args(args)
        .output()
        .expect("the mstar program runs")
}

/// Program output as text.
#[allow(dead_code)] // (not every test reads output as text)
pub fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// The path of a file of `models/`.
#[allow(dead_code)] // (not every test reads `models/`)
pub fn model(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../models")
        .join(name)
        .display()
        .to_string()
}

/// A fresh directory for one test's files (`tag` names the test), removed
/// when the test passes and kept for a look when it fails.
#[allow(dead_code)] // (not every test writes files)
pub fn scratch(tag: &str) -> Scratch {
    let dir = std::env::temp_dir().join(format!("mstar-cli-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("a scratch directory");
    Scratch(dir)
}

/// A scratch directory: a path while the test runs, gone after it passes.
#[allow(dead_code)] // (not every test writes files)
pub struct Scratch(PathBuf);

impl std::ops::Deref for Scratch {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.0
    }
}

impl AsRef<Path> for Scratch {
    fn as_ref(&self) -> &Path {
        &self.0
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        if !std::thread::panicking() {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }
}
