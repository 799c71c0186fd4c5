//! The model-file writers (`cargo xtask n-four-bar-file`, `spatial-chain-file`,
//! `hanging-chain-file`) write a relative `--out` where the command was run,
//! not in the workspace root the studies move to.

use std::path::PathBuf;
use std::process::Command;

fn scratch_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("mstar-xtask-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("a scratch directory");
    dir
}

#[test]
fn a_relative_out_is_written_where_the_command_runs() {
    let dir = scratch_dir("relative-out");
    for (command, size) in [
        ("hanging-chain-file", "--links"),
        ("spatial-chain-file", "--links"),
        ("n-four-bar-file", "--bars"),
    ] {
        let name = format!("{command}.toml");
        let status = Command::new(env!("CARGO_BIN_EXE_xtask"))
            .args([command, size, "2", "--out", &name])
            .current_dir(&dir)
            .output()
            .expect("xtask runs");
        assert!(status.status.success(), "{command}: {status:?}");
        let text =
            std::fs::read_to_string(dir.join(&name)).expect("the file where the command ran");
        assert!(text.contains("[[body]]"), "{command}: {text}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
