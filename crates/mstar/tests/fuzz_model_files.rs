//! Fuzzing the model-file loader and `mstar check`: every input of the corpus
//! (`tests/fuzz_corpus/`, `models/` and `models/spatial/`), and random mutations of them, must
//! load or fail with an error that names the file — never panic, never hang
//! — and a model that loads must go through `check` and a few steps the same
//! way. `cargo test` runs a short pass (256 mutated documents); a longer
//! one: `PROPTEST_CASES=20000 cargo test -p mstar --test fuzz_model_files`.
//! An input that once failed belongs in the corpus.

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};

use mstar::file::{Format, MechanismFile};
use proptest::prelude::*;
use proptest::test_runner::FileFailurePersistence;

fn corpus() -> Vec<(String, String)> {
    let here = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut out = Vec::new();
    for dir in [
        here.join("tests/fuzz_corpus"),
        here.join("../../models"),
        here.join("../../models/spatial"),
    ] {
        let mut paths: Vec<PathBuf> = std::fs::read_dir(&dir)
            .expect("corpus directory")
            .map(|e| e.expect("entry").path())
            .filter(|p| p.is_file())
            .collect();
        paths.sort();
        for path in paths {
            let name = path
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default();
            out.push((name, std::fs::read_to_string(&path).expect("corpus file")));
        }
    }
    out
}

/// Loads `text` as `name`, then checks and runs a few steps of what loads:
/// `Err` with the message when the loader refuses it (which must name the
/// file), `Ok` otherwise; panics are the caller's to catch.
fn exercise(name: &str, text: &str) -> Result<(), String> {
    let format = if name.ends_with(".json") {
        Format::Json
    } else {
        Format::Toml
    };
    // A few steps at most, whatever the document's settings say.
    let set: Vec<String> = [
        "simulation.t_end=0.003",
        "simulation.h=0.001",
        "simulation.max_iterations=20",
    ]
    .map(String::from)
    .to_vec();
    let file = match MechanismFile::parse_with(text, name, format, &set) {
        Ok(file) => file,
        Err(e) => {
            let message = e.to_string();
            assert!(
                message.starts_with(name),
                "the error does not name the file: {message}"
            );
            return Err(message);
        }
    };
    if let Ok((config, _)) = mstar::run::config(&file.simulation) {
        let redundant = file.simulation.redundant.unwrap_or_default();
        let sys = mstar::run::lookup(&file.mechanism);
        let report = mstar::run::check(sys, &config, redundant);
        assert!(!report.to_string().is_empty());
        let _ = mstar::run::simulate(sys, &file.simulation, &mut |_: &mstar::SampleRef<'_>| {});
    }
    Ok(())
}

#[test]
fn every_corpus_input_loads_or_fails_cleanly() {
    let mut refused = 0;
    for (name, text) in corpus() {
        match catch_unwind(AssertUnwindSafe(|| exercise(&name, &text))) {
            Ok(Ok(())) => {}
            Ok(Err(_)) => refused += 1,
            Err(_) => panic!("{name} panicked"),
        }
    }
    // The hand-made inputs are mostly malformed; the models load.
    assert!(refused >= 6, "{refused}");
}

/// Tokens that make interesting documents when spliced in.
const TOKENS: &[&str] = &[
    "=",
    "[",
    "]",
    "[[",
    "]]",
    "{",
    "}",
    ",",
    "\"",
    "'",
    "\n",
    "#",
    ".",
    "nan",
    "inf",
    "-inf",
    "-0.0",
    "1e308",
    "1e-320",
    "0",
    "-1",
    "9999999999999999999",
    "true",
    "\"ground\"",
    "[[body]]",
    "[[joint]]",
    "[[driver]]",
    "[[force]]",
    "[[point_mass]]",
    "[simulation]",
    "format = \"mstar.spatial/1\"",
    "type = \"universal\"",
    "axes = [[0, 0, 1], [1, 0, 0]]",
    "orientation = [0, 0, 0, 0]",
    "inertia = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]",
    "rotational_mass = \"regularized\"",
    "name = \"x\"",
    "type = \"weld\"",
    "bodies = [\"ground\", \"x\"]",
    "coordinate = \"theta\"",
    "function = { table = [[0.0, 1.0]] }",
    "redundant = \"minimum-norm\"",
    "\u{0}",
    "Θ",
];

/// One edit of a document.
#[derive(Clone, Debug)]
enum Edit {
    Delete(usize, usize),
    Insert(usize, usize),
    DuplicateLine(usize),
    SwapLines(usize, usize),
}

fn edit() -> impl Strategy<Value = Edit> {
    prop_oneof![
        (any::<usize>(), 1usize..40).prop_map(|(a, n)| Edit::Delete(a, n)),
        (any::<usize>(), 0..TOKENS.len()).prop_map(|(a, t)| Edit::Insert(a, t)),
        any::<usize>().prop_map(Edit::DuplicateLine),
        (any::<usize>(), any::<usize>()).prop_map(|(a, b)| Edit::SwapLines(a, b)),
    ]
}

/// The nearest character boundary at or below `at % (len + 1)`.
fn boundary(text: &str, at: usize) -> usize {
    let mut i = at % (text.len() + 1);
    while !text.is_char_boundary(i) {
        i -= 1;
    }
    i
}

fn apply(text: &str, e: &Edit) -> String {
    let mut lines: Vec<&str> = text.lines().collect();
    match *e {
        Edit::Delete(a, n) => {
            let start = boundary(text, a);
            let end = boundary(text, start + n.min(text.len() - start));
            format!("{}{}", &text[..start], &text[end.max(start)..])
        }
        Edit::Insert(a, t) => {
            let at = boundary(text, a);
            format!("{}{}{}", &text[..at], TOKENS[t], &text[at..])
        }
        Edit::DuplicateLine(a) if !lines.is_empty() => {
            let k = a % lines.len();
            lines.insert(k, lines[k]);
            lines.join("\n")
        }
        Edit::SwapLines(a, b) if !lines.is_empty() => {
            let n = lines.len();
            lines.swap(a % n, b % n);
            lines.join("\n")
        }
        _ => text.to_string(),
    }
}

proptest! {
    #![proptest_config(ProptestConfig {
        failure_persistence: Some(Box::new(FileFailurePersistence::WithSource("regressions"))),
        ..ProptestConfig::default()
    })]
    #[test]
    fn mutated_documents_load_or_fail_cleanly(
        pick in any::<usize>(),
        edits in prop::collection::vec(edit(), 1..6),
    ) {
        let inputs = corpus();
        let (name, text) = &inputs[pick % inputs.len()];
        let mutated = edits.iter().fold(text.clone(), |t, e| apply(&t, e));
        let _ = exercise(name, &mutated);
    }
}
