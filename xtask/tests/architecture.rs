//! The architecture invariants of `docs/architecture.md`, checked on the
//! workspace as it is (in the manner of rust-analyzer's `tidy` tests):
//!
//! 1. no library crate has a command-line crate (clap, plotters, indicatif,
//!    anyhow) in its normal dependency tree;
//! 2. the workspace crates depend on one another in the declared order only;
//! 3. the modules inside each crate's `src/` form no cycle, except the
//!    allow-listed ones.
//!
//! Each checker is a function of its input, shown to fail on a small
//! synthetic input that breaks its rule. Run with
//! `cargo test -p xtask --test architecture`.

use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::{Value, json};

// ---------------------------------------------------------------------------
// The rules
// ---------------------------------------------------------------------------

/// The library crates: what a user of mstar links.
const LIBRARIES: &[&str] = &[
    "mstar-model",
    "mstar-file",
    "mstar-linearize",
    "mstar-kkt",
    "mstar-newmark",
    "mstar-rk4",
    "mstar",
];

/// Crates for a command-line program, never in a library's tree (a name, or
/// a name followed by `-` or `_`: `plotters-backend`, `clap_derive`).
const FORBIDDEN_IN_LIBRARIES: &[&str] = &["clap", "plotters", "indicatif", "anyhow"];

/// The workspace crates in dependency order: a crate's normal and build
/// dependencies are in earlier layers. `mstar-model` and `mstar-kkt` are
/// independent (the KKT solvers know nothing of mechanics); `mstar-linearize`
/// fills the KKT matrix on `mstar-kkt`'s types; `mstar-rk4` sits beside
/// `mstar-linearize`, so it may depend on `mstar-model` only; `mstar-file`
/// reads files into `mstar-model`'s systems and needs nothing else.
const LAYERS: &[&[&str]] = &[
    &["mstar-model", "mstar-kkt"],
    &["mstar-linearize", "mstar-rk4", "mstar-file"],
    &["mstar-newmark"],
    &["mstar"],
    &["mstar-cli"],
    &["mstar-testkit"],
    &["mstar-python", "xtask", "mstar-benches"],
];

/// Dependencies that break the order today and that this workspace keeps
/// until the crates involved are restructured (each with its reason).
const ORDER_ALLOWED: &[(&str, &str)] = &[];

/// Dev-dependencies may also reach these crates, whatever their layer: the
/// test kit, and the RK4 oracles the integrator's tests compare with.
const DEV_ANYWHERE: &[&str] = &["mstar-testkit", "mstar-rk4"];

/// Module cycles that exist and are kept for now: a cycle whose modules
/// all belong to one group here is allowed.
const CYCLES_ALLOWED: &[(&str, &[&str])] = &[
    // The registry of built-in backends (`backend::BUILT_IN`) names every
    // backend of the crate, and every backend implements
    // `backend::KktBackend`, defined beside it. (Backends of other crates
    // join at run time with `register`, without a module edge.)
    (
        "mstar-kkt",
        &[
            "backend",
            "dense",
            "envelope",
            "envelope_lu",
            "schur",
            "sparse_ldlt",
            "sparse_lu",
        ],
    ),
];

// ---------------------------------------------------------------------------
// The tests on the workspace
// ---------------------------------------------------------------------------

fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("xtask/ is in the workspace")
        .to_path_buf()
}

/// `cargo metadata` of the workspace (offline: the lock file's versions).
fn metadata() -> Value {
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    let out = Command::new(cargo)
        .args(["metadata", "--format-version", "1", "--offline"])
        .current_dir(workspace_root())
        .output()
        .expect("cargo metadata runs");
    assert!(
        out.status.success(),
        "cargo metadata failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("cargo metadata prints JSON")
}

#[test]
fn no_library_depends_on_a_command_line_crate() {
    let violations = forbidden_in_library_trees(&metadata());
    assert!(violations.is_empty(), "{}", violations.join("\n"));
}

#[test]
fn workspace_crates_depend_in_the_declared_order() {
    let violations = order_violations(&metadata());
    assert!(violations.is_empty(), "{}", violations.join("\n"));
}

#[test]
fn no_module_cycles_inside_a_crate() {
    let meta = metadata();
    let mut violations = Vec::new();
    for package in workspace_packages(&meta) {
        let name = package["name"].as_str().unwrap_or_default();
        let manifest = PathBuf::from(package["manifest_path"].as_str().unwrap_or_default());
        let src = manifest.parent().map(|d| d.join("src")).unwrap_or_default();
        let files = source_files(&src);
        for cycle in module_cycles(&files) {
            if !cycle_allowed(name, &cycle) {
                violations.push(format!("{name}: module cycle {}", cycle.join(" ⇄ ")));
            }
        }
    }
    assert!(violations.is_empty(), "{}", violations.join("\n"));
}

/// Every allow-listed cycle still exists: an entry that no longer matches
/// anything is removed rather than left to hide a new cycle.
#[test]
fn every_allowed_cycle_exists() {
    let meta = metadata();
    for (krate, group) in CYCLES_ALLOWED {
        let package = workspace_packages(&meta)
            .into_iter()
            .find(|p| p["name"] == *krate)
            .expect("an allow-listed crate is in the workspace");
        let manifest = PathBuf::from(package["manifest_path"].as_str().unwrap_or_default());
        let src = manifest.parent().map(|d| d.join("src")).unwrap_or_default();
        let cycles = module_cycles(&source_files(&src));
        assert!(
            cycles
                .iter()
                .any(|c| c.iter().all(|m| group.contains(&m.as_str()))),
            "{krate}: no cycle among {group:?} any more: remove it from CYCLES_ALLOWED"
        );
    }
}

// ---------------------------------------------------------------------------
// Checker 1: no command-line crate in a library's tree
// ---------------------------------------------------------------------------

fn workspace_packages(meta: &Value) -> Vec<&Value> {
    let members: BTreeSet<&str> = meta["workspace_members"]
        .as_array()
        .into_iter()
        .flatten()
        .filter_map(Value::as_str)
        .collect();
    meta["packages"]
        .as_array()
        .into_iter()
        .flatten()
        .filter(|p| p["id"].as_str().is_some_and(|id| members.contains(id)))
        .collect()
}

fn is_forbidden(name: &str) -> bool {
    FORBIDDEN_IN_LIBRARIES.iter().any(|f| {
        name == *f
            || name
                .strip_prefix(f)
                .is_some_and(|rest| rest.starts_with('-') || rest.starts_with('_'))
    })
}

/// For each library, the forbidden crates reachable through normal and
/// build dependencies (not dev-dependencies), each with the path to it.
fn forbidden_in_library_trees(meta: &Value) -> Vec<String> {
    let names: HashMap<&str, &str> = meta["packages"]
        .as_array()
        .into_iter()
        .flatten()
        .filter_map(|p| Some((p["id"].as_str()?, p["name"].as_str()?)))
        .collect();
    let nodes: HashMap<&str, &Value> = meta["resolve"]["nodes"]
        .as_array()
        .into_iter()
        .flatten()
        .filter_map(|n| Some((n["id"].as_str()?, n)))
        .collect();
    let mut violations = Vec::new();
    for package in workspace_packages(meta) {
        let (Some(name), Some(id)) = (package["name"].as_str(), package["id"].as_str()) else {
            continue;
        };
        if !LIBRARIES.contains(&name) {
            continue;
        }
        // Breadth first, remembering how each crate was reached.
        let mut parent: HashMap<&str, &str> = HashMap::new();
        let mut queue = std::collections::VecDeque::from([id]);
        let mut seen = BTreeSet::from([id]);
        while let Some(at) = queue.pop_front() {
            // A forbidden crate is reported once, not its own dependencies.
            if at != id && is_forbidden(names.get(at).copied().unwrap_or(at)) {
                continue;
            }
            let deps = nodes.get(at).and_then(|n| n["deps"].as_array());
            for dep in deps.into_iter().flatten() {
                let Some(pkg) = dep["pkg"].as_str() else {
                    continue;
                };
                let non_dev = dep["dep_kinds"]
                    .as_array()
                    .into_iter()
                    .flatten()
                    .any(|k| k["kind"].as_str() != Some("dev"));
                if non_dev && seen.insert(pkg) {
                    parent.insert(pkg, at);
                    queue.push_back(pkg);
                }
            }
        }
        for &reached in &seen {
            let dep_name = names.get(reached).copied().unwrap_or(reached);
            if reached != id && is_forbidden(dep_name) {
                let mut path = vec![dep_name];
                let mut at = reached;
                while let Some(&p) = parent.get(at) {
                    path.push(names.get(p).copied().unwrap_or(p));
                    at = p;
                }
                path.reverse();
                violations.push(format!(
                    "library {name} depends on {dep_name} (a command-line crate): {}",
                    path.join(" → ")
                ));
            }
        }
    }
    violations
}

// ---------------------------------------------------------------------------
// Checker 2: dependency direction
// ---------------------------------------------------------------------------

fn layer_of(name: &str) -> Option<usize> {
    LAYERS.iter().position(|layer| layer.contains(&name))
}

/// Dependencies between workspace crates against [`LAYERS`]: normal and
/// build dependencies point to an earlier layer; dev-dependencies to an
/// earlier layer or to [`DEV_ANYWHERE`]. A workspace crate missing from the
/// layers is a violation too (the order must name every crate).
fn order_violations(meta: &Value) -> Vec<String> {
    let members: BTreeSet<&str> = workspace_packages(meta)
        .iter()
        .filter_map(|p| p["name"].as_str())
        .collect();
    let mut violations = Vec::new();
    for package in workspace_packages(meta) {
        let name = package["name"].as_str().unwrap_or_default();
        let Some(layer) = layer_of(name) else {
            violations.push(format!(
                "{name} is not in the declared order (LAYERS in xtask/tests/architecture.rs)"
            ));
            continue;
        };
        for dep in package["dependencies"].as_array().into_iter().flatten() {
            let dep_name = dep["name"].as_str().unwrap_or_default();
            if !members.contains(dep_name) {
                continue;
            }
            let kind = dep["kind"].as_str().unwrap_or("normal");
            let dep_layer = layer_of(dep_name).unwrap_or(usize::MAX);
            let ok = dep_layer < layer
                || (kind == "dev" && DEV_ANYWHERE.contains(&dep_name))
                || ORDER_ALLOWED.contains(&(name, dep_name));
            if !ok {
                violations.push(format!(
                    "{name} ({kind} dependency) depends on {dep_name}, which is not below it in the order {}",
                    order_text()
                ));
            }
        }
    }
    violations
}

fn order_text() -> String {
    LAYERS
        .iter()
        .map(|layer| layer.join(" | "))
        .collect::<Vec<_>>()
        .join(" → ")
}

// ---------------------------------------------------------------------------
// Checker 3: module cycles
// ---------------------------------------------------------------------------

/// The `.rs` files under `src`, by path relative to it, with their text.
fn source_files(src: &Path) -> Vec<(PathBuf, String)> {
    let mut files = Vec::new();
    let mut stack = vec![src.to_path_buf()];
    while let Some(dir) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(&dir) else {
            continue;
        };
        for entry in entries.flatten() {
            let path = entry.path();
            if path.is_dir() {
                stack.push(path);
            } else if path.extension().is_some_and(|e| e == "rs")
                && let (Ok(rel), Ok(text)) =
                    (path.strip_prefix(src), std::fs::read_to_string(&path))
            {
                files.push((rel.to_path_buf(), text));
            }
        }
    }
    files.sort();
    files
}

/// The module a file defines, as segments: `lib.rs`, `main.rs` → `[]`;
/// `a.rs`, `a/mod.rs` → `[a]`; `a/b.rs` → `[a, b]`. (`src/bin/` targets are
/// crates of their own and are left out.)
fn module_of(rel: &Path) -> Option<Vec<String>> {
    let mut parts: Vec<String> = rel
        .iter()
        .map(|p| p.to_string_lossy().into_owned())
        .collect();
    if parts.first().is_some_and(|p| p == "bin") {
        return None;
    }
    let last = parts.pop()?;
    let stem = last.strip_suffix(".rs")?;
    if !(parts.is_empty() && (stem == "lib" || stem == "main")) && stem != "mod" {
        parts.push(stem.to_string());
    }
    Some(parts)
}

fn display(module: &[String]) -> String {
    if module.is_empty() {
        "crate".into()
    } else {
        module.join("::")
    }
}

/// The module cycles among `files` (paths relative to `src/`, texts), each
/// as its sorted module names. An edge `a → b` is a path in `a`'s file that
/// names module `b` through `crate::`, `super::` or `self::` (in `use`
/// declarations or in expressions); inline modules count as their file's
/// module. Test code (`#[cfg(test)]` modules, inline or in files of their
/// own) is left out: tests sit above the code they test.
fn module_cycles(files: &[(PathBuf, String)]) -> Vec<Vec<String>> {
    let stripped: Vec<(Vec<String>, String)> = files
        .iter()
        .filter_map(|(p, t)| Some((module_of(p)?, strip_comments_and_strings(t))))
        .collect();
    let tests: BTreeSet<Vec<String>> = stripped
        .iter()
        .flat_map(|(m, code)| {
            test_module_declarations(code).into_iter().map(|name| {
                let mut child = m.clone();
                child.push(name);
                child
            })
        })
        .collect();
    let in_tests = |m: &[String]| (1..=m.len()).any(|k| tests.contains(&m[..k]));
    let modules: BTreeSet<Vec<String>> = stripped
        .iter()
        .map(|(m, _)| m.clone())
        .filter(|m| !in_tests(m))
        .collect();
    let mut edges: BTreeMap<Vec<String>, BTreeSet<Vec<String>>> = BTreeMap::new();
    for (module, code) in &stripped {
        if in_tests(module) {
            continue;
        }
        for (at, segments) in crate_paths(code) {
            let Some(inline) = inline_module_at(code, at) else {
                continue; // in a #[cfg(test)] module
            };
            let here = [module.clone(), inline].concat();
            let Some(target) = resolve(&here, &segments, &modules) else {
                continue;
            };
            if &target != module {
                edges.entry(module.clone()).or_default().insert(target);
            }
        }
    }
    let mut cycles: Vec<Vec<String>> = strongly_connected(&modules, &edges)
        .into_iter()
        .filter(|c| c.len() > 1)
        .map(|c| {
            let mut names: Vec<String> = c.iter().map(|m| display(m)).collect();
            names.sort();
            names
        })
        .collect();
    cycles.sort();
    cycles
}

/// Whether the code before offset `at` ends with a `#[cfg(test)]`
/// attribute (other attributes may follow it).
fn after_cfg_test(code: &str, at: usize) -> bool {
    let mut before = code[..at].trim_end();
    loop {
        if before.ends_with("#[cfg(test)]") {
            return true;
        }
        // Skip one more attribute `#[…]`.
        let Some(open) = before.strip_suffix(']').and_then(|b| b.rfind("#[")) else {
            return false;
        };
        before = before[..open].trim_end();
    }
}

/// The names of the file modules declared `#[cfg(test)] mod name;`.
fn test_module_declarations(code: &str) -> Vec<String> {
    let mut names = Vec::new();
    let mut from = 0;
    while let Some(pos) = find_word(code, "mod", from) {
        from = pos + 3;
        let rest = code[pos + 3..].trim_start();
        let name: String = rest
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect();
        let declared = rest[name.len()..].trim_start().starts_with(';');
        let start = code[..pos]
            .trim_end()
            .strip_suffix("pub")
            .map_or(pos, str::len);
        if declared && after_cfg_test(code, start) {
            names.push(name);
        }
    }
    names
}

/// Whether a cycle of `krate` lies within one group of [`CYCLES_ALLOWED`].
fn cycle_allowed(krate: &str, cycle: &[String]) -> bool {
    CYCLES_ALLOWED
        .iter()
        .any(|(k, group)| *k == krate && cycle.iter().all(|m| group.contains(&m.as_str())))
}

/// The module a path names, from module `here`: `crate`/`super`/`self`
/// then as many segments as name known modules (the rest are items).
fn resolve(
    here: &[String],
    segments: &[String],
    modules: &BTreeSet<Vec<String>>,
) -> Option<Vec<String>> {
    let mut at: Vec<String> = match segments.first()?.as_str() {
        "crate" | "$crate" => Vec::new(),
        "self" => here.to_vec(),
        "super" => here[..here.len().checked_sub(1)?].to_vec(),
        _ => return None,
    };
    for seg in &segments[1..] {
        if seg == "super" {
            at.pop()?;
            continue;
        }
        if seg == "self" {
            continue;
        }
        let mut next = at.clone();
        next.push(seg.clone());
        if modules.contains(&next) {
            at = next;
        } else {
            break;
        }
    }
    // An inline module's path resolves to the file module that holds it.
    while !at.is_empty() && !modules.contains(&at) {
        at.pop();
    }
    Some(at)
}

/// The code with comments, string and character literals blanked (each
/// character a space, line breaks kept; offsets are into the result).
fn strip_comments_and_strings(text: &str) -> String {
    let b: Vec<char> = text.chars().collect();
    let mut out = String::with_capacity(text.len());
    let mut i = 0;
    let blank = |out: &mut String, c: char| out.push(if c == '\n' { '\n' } else { ' ' });
    while i < b.len() {
        let c = b[i];
        let next = b.get(i + 1).copied();
        if c == '/' && next == Some('/') {
            while i < b.len() && b[i] != '\n' {
                blank(&mut out, b[i]);
                i += 1;
            }
        } else if c == '/' && next == Some('*') {
            let mut depth = 0;
            while i < b.len() {
                if b[i] == '/' && b.get(i + 1) == Some(&'*') {
                    depth += 1;
                    out.push_str("  ");
                    i += 2;
                } else if b[i] == '*' && b.get(i + 1) == Some(&'/') {
                    depth -= 1;
                    out.push_str("  ");
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    blank(&mut out, b[i]);
                    i += 1;
                }
            }
        } else if c == 'r'
            && (next == Some('"') || next == Some('#'))
            && !b[..i]
                .last()
                .is_some_and(|p| p.is_alphanumeric() || *p == '_')
        {
            // A raw string r#"…"#: find the opening quote, then the closing
            // quote with as many hashes.
            let mut j = i + 1;
            let mut hashes = 0;
            while b.get(j) == Some(&'#') {
                hashes += 1;
                j += 1;
            }
            if b.get(j) != Some(&'"') {
                out.push(c);
                i += 1;
                continue;
            }
            j += 1;
            loop {
                if j >= b.len() {
                    break;
                }
                if b[j] == '"' && (0..hashes).all(|k| b.get(j + 1 + k) == Some(&'#')) {
                    j += 1 + hashes;
                    break;
                }
                j += 1;
            }
            for &ch in &b[i..j.min(b.len())] {
                blank(&mut out, ch);
            }
            i = j;
        } else if c == '"' {
            blank(&mut out, c);
            i += 1;
            while i < b.len() && b[i] != '"' {
                if b[i] == '\\' {
                    blank(&mut out, b[i]);
                    i += 1;
                }
                if i < b.len() {
                    blank(&mut out, b[i]);
                    i += 1;
                }
            }
            if i < b.len() {
                blank(&mut out, b[i]);
                i += 1;
            }
        } else if c == '\'' {
            // A character literal ('x', '\n', '\u{..}') or a lifetime ('a).
            let end = if next == Some('\\') {
                (i + 2..b.len()).find(|&k| b[k] == '\'')
            } else if b.get(i + 2) == Some(&'\'') {
                Some(i + 2)
            } else {
                None
            };
            match end {
                Some(e) => {
                    for &ch in &b[i..=e] {
                        blank(&mut out, ch);
                    }
                    i = e + 1;
                }
                None => {
                    out.push(c);
                    i += 1;
                }
            }
        } else {
            out.push(c);
            i += 1;
        }
    }
    out
}

/// Every path that starts with `crate`, `$crate`, `super` or `self`, with
/// its byte offset: `use` trees expanded (`use crate::a::{b, c::d}` gives
/// `crate::a::b` and `crate::a::c::d`), then the paths in the rest of the
/// code.
fn crate_paths(code: &str) -> Vec<(usize, Vec<String>)> {
    let mut paths = Vec::new();
    let mut rest = String::from(code);
    // `use` declarations (blanked out of `rest` once read).
    let mut from = 0;
    while let Some(pos) = find_word(code, "use", from) {
        let Some(end) = code[pos..].find(';').map(|e| pos + e) else {
            break;
        };
        let tree = &code[pos + 3..end];
        for p in expand_use_tree(tree) {
            if p.first()
                .is_some_and(|s| matches!(s.as_str(), "crate" | "$crate" | "super" | "self"))
            {
                paths.push((pos, p));
            }
        }
        rest.replace_range(pos..end, &" ".repeat(end - pos));
        from = end;
    }
    // Paths in expressions, types and macros.
    let chars: Vec<(usize, char)> = rest.char_indices().collect();
    let mut k = 0;
    while k < chars.len() {
        let (pos, _) = chars[k];
        let starts = ["$crate", "crate", "super", "self"]
            .into_iter()
            .find(|w| rest[pos..].starts_with(w) && word_boundary_before(&rest, pos));
        if let Some(word) = starts {
            let mut segments = vec![word.to_string()];
            let mut at = pos + word.len();
            loop {
                let tail = rest[at..].trim_start();
                let Some(after) = tail.strip_prefix("::") else {
                    break;
                };
                let after_trim = after.trim_start();
                let ident: String = after_trim
                    .chars()
                    .take_while(|c| c.is_alphanumeric() || *c == '_')
                    .collect();
                if ident.is_empty() {
                    break;
                }
                at = rest.len() - after_trim.len() + ident.len();
                segments.push(ident);
            }
            if segments.len() > 1 {
                paths.push((pos, segments));
            }
            while k < chars.len() && chars[k].0 < at.max(pos + 1) {
                k += 1;
            }
        } else {
            k += 1;
        }
    }
    paths
}

fn word_boundary_before(text: &str, pos: usize) -> bool {
    !text[..pos]
        .chars()
        .next_back()
        .is_some_and(|c| c.is_alphanumeric() || c == '_' || c == '$')
}

fn find_word(text: &str, word: &str, from: usize) -> Option<usize> {
    let mut start = from;
    while let Some(i) = text[start..].find(word).map(|i| start + i) {
        let after = text[i + word.len()..].chars().next();
        if word_boundary_before(text, i) && after.is_some_and(char::is_whitespace) {
            return Some(i);
        }
        start = i + word.len();
    }
    None
}

/// The paths of a `use` tree (without `use` and `;`); `as` renames dropped.
fn expand_use_tree(tree: &str) -> Vec<Vec<String>> {
    fn split_top(s: &str) -> Vec<&str> {
        let mut parts = Vec::new();
        let (mut depth, mut start) = (0, 0);
        for (i, c) in s.char_indices() {
            match c {
                '{' => depth += 1,
                '}' => depth -= 1,
                ',' if depth == 0 => {
                    parts.push(&s[start..i]);
                    start = i + 1;
                }
                _ => {}
            }
        }
        parts.push(&s[start..]);
        parts
    }
    fn expand(prefix: &[String], tree: &str, out: &mut Vec<Vec<String>>) {
        let tree = tree.trim();
        if tree.is_empty() {
            return;
        }
        if let Some(inner) = tree.strip_prefix('{').and_then(|t| t.strip_suffix('}')) {
            for part in split_top(inner) {
                expand(prefix, part, out);
            }
            return;
        }
        match tree.find("::") {
            Some(i) if !tree[..i].contains('{') => {
                let mut p = prefix.to_vec();
                p.push(tree[..i].trim().to_string());
                expand(&p, &tree[i + 2..], out);
            }
            _ => {
                let name = tree.split_whitespace().next().unwrap_or_default();
                let mut p = prefix.to_vec();
                if name != "self" && name != "*" {
                    p.push(name.to_string());
                }
                out.push(p);
            }
        }
    }
    let tree = tree.trim().trim_start_matches("pub").trim();
    let mut out = Vec::new();
    expand(&[], tree, &mut out);
    out
}

/// The inline modules (`mod name { … }`) around byte offset `at`, outermost
/// first; `None` inside a `#[cfg(test)]` one.
fn inline_module_at(code: &str, at: usize) -> Option<Vec<String>> {
    // (name and whether it is test code, for the modules; None for other
    // braces)
    let mut stack: Vec<Option<(String, bool)>> = Vec::new();
    let mut pending: Option<(String, bool)> = None;
    let bytes = code.as_bytes();
    for i in 0..at.min(code.len()) {
        let c = bytes[i];
        if c == b'm' && code[i..].starts_with("mod ") && word_boundary_before(code, i) {
            let rest = code[i + 4..].trim_start();
            let name: String = rest
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_')
                .collect();
            if rest[name.len()..].trim_start().starts_with('{') {
                let start = code[..i].trim_end().strip_suffix("pub").map_or(i, str::len);
                pending = Some((name, after_cfg_test(code, start)));
            }
        } else if c == b'{' {
            stack.push(pending.take());
        } else if c == b'}' {
            stack.pop();
        }
    }
    let modules: Vec<(String, bool)> = stack.into_iter().flatten().collect();
    if modules.iter().any(|(_, test)| *test) {
        return None;
    }
    Some(modules.into_iter().map(|(name, _)| name).collect())
}

/// Tarjan's strongly connected components.
fn strongly_connected(
    nodes: &BTreeSet<Vec<String>>,
    edges: &BTreeMap<Vec<String>, BTreeSet<Vec<String>>>,
) -> Vec<Vec<Vec<String>>> {
    struct State<'a> {
        edges: &'a BTreeMap<Vec<String>, BTreeSet<Vec<String>>>,
        index: HashMap<&'a [String], usize>,
        low: HashMap<&'a [String], usize>,
        on_stack: BTreeSet<&'a [String]>,
        stack: Vec<&'a [String]>,
        next: usize,
        components: Vec<Vec<Vec<String>>>,
    }
    fn visit<'a>(s: &mut State<'a>, v: &'a [String]) {
        s.index.insert(v, s.next);
        s.low.insert(v, s.next);
        s.next += 1;
        s.stack.push(v);
        s.on_stack.insert(v);
        let edges = s.edges;
        for w in edges.get(v).into_iter().flatten() {
            let w = w.as_slice();
            if !s.index.contains_key(w) {
                visit(s, w);
                let lw = s.low[w];
                let lv = s.low.get_mut(v).expect("visited");
                *lv = (*lv).min(lw);
            } else if s.on_stack.contains(w) {
                let iw = s.index[w];
                let lv = s.low.get_mut(v).expect("visited");
                *lv = (*lv).min(iw);
            }
        }
        if s.low[v] == s.index[v] {
            let mut component = Vec::new();
            while let Some(w) = s.stack.pop() {
                s.on_stack.remove(w);
                component.push(w.to_vec());
                if w == v {
                    break;
                }
            }
            s.components.push(component);
        }
    }
    let mut s = State {
        edges,
        index: HashMap::new(),
        low: HashMap::new(),
        on_stack: BTreeSet::new(),
        stack: Vec::new(),
        next: 0,
        components: Vec::new(),
    };
    for v in nodes {
        if !s.index.contains_key(v.as_slice()) {
            visit(&mut s, v);
        }
    }
    s.components
}

// ---------------------------------------------------------------------------
// Each checker fails on an input that breaks its rule
// ---------------------------------------------------------------------------

/// A synthetic `cargo metadata`: packages with their workspace dependencies
/// (`(name, kind)`), and resolve edges `(from, to, kind)` among all crates.
fn synthetic(packages: &[(&str, &[(&str, &str)])], resolve: &[(&str, &str, &str)]) -> Value {
    let id = |n: &str| format!("path+file:///ws/{n}#0.1.0");
    let mut names: BTreeSet<&str> = packages.iter().map(|(n, _)| *n).collect();
    for (a, b, _) in resolve {
        names.insert(a);
        names.insert(b);
    }
    let members: Vec<String> = packages.iter().map(|(n, _)| id(n)).collect();
    let pkgs: Vec<Value> = names
        .iter()
        .map(|n| {
            let deps: Vec<Value> = packages
                .iter()
                .find(|(p, _)| p == n)
                .map(|(_, d)| *d)
                .unwrap_or_default()
                .iter()
                .map(|(d, kind)| {
                    let kind = if *kind == "normal" { Value::Null } else { json!(kind) };
                    json!({"name": d, "kind": kind, "path": format!("/ws/{d}")})
                })
                .collect();
            json!({"name": n, "id": id(n), "manifest_path": format!("/ws/{n}/Cargo.toml"), "dependencies": deps})
        })
        .collect();
    let nodes: Vec<Value> =
        names
            .iter()
            .map(|n| {
                let deps: Vec<Value> = resolve
                .iter()
                .filter(|(a, _, _)| a == n)
                .map(|(_, b, kind)| {
                    let kind = if *kind == "normal" { Value::Null } else { json!(kind) };
                    json!({"name": b, "pkg": id(b), "dep_kinds": [{"kind": kind, "target": null}]})
                })
                .collect();
                json!({"id": id(n), "deps": deps})
            })
            .collect();
    json!({"packages": pkgs, "workspace_members": members, "resolve": {"nodes": nodes}})
}

#[test]
fn a_command_line_crate_deep_in_a_library_tree_is_caught() {
    let meta = synthetic(
        &[("mstar-kkt", &[]), ("mstar-cli", &[])],
        &[
            ("mstar-kkt", "faer", "normal"),
            ("faer", "clap_builder", "normal"),
            // (Reported as clap_builder only, not as its dependencies too.)
            ("clap_builder", "clap_lex", "normal"),
            // Dev-dependencies and non-libraries are free to use them.
            ("mstar-kkt", "anyhow", "dev"),
            ("mstar-cli", "plotters", "normal"),
        ],
    );
    assert_eq!(
        forbidden_in_library_trees(&meta),
        [
            "library mstar-kkt depends on clap_builder (a command-line crate): mstar-kkt → faer → clap_builder"
        ]
    );
    assert!(is_forbidden("plotters-backend") && !is_forbidden("clapper"));
}

#[test]
fn a_dependency_against_the_order_is_caught() {
    let meta = synthetic(
        &[
            ("mstar-model", &[]),
            (
                "mstar-rk4",
                &[("mstar-model", "normal"), ("mstar-newmark", "normal")],
            ),
            (
                "mstar-newmark",
                &[("mstar-model", "normal"), ("mstar-rk4", "dev")],
            ),
            (
                "mstar",
                &[
                    ("mstar-newmark", "normal"),
                    ("mstar-testkit", "dev"),
                    ("mstar-cli", "dev"),
                ],
            ),
            ("mstar-cli", &[("mstar", "normal")]),
            ("mstar-testkit", &[("mstar", "normal")]),
            ("mstar-unplaced", &[]),
        ],
        &[],
    );
    let v = order_violations(&meta);
    assert_eq!(v.len(), 3, "{v:#?}");
    for expected in [
        "mstar-rk4 (normal dependency) depends on mstar-newmark",
        "mstar (dev dependency) depends on mstar-cli",
        "mstar-unplaced is not in the declared order",
    ] {
        assert!(
            v.iter().any(|m| m.starts_with(expected)),
            "{expected}: {v:#?}"
        );
    }
}

fn files(list: &[(&str, &str)]) -> Vec<(PathBuf, String)> {
    list.iter()
        .map(|(p, t)| (PathBuf::from(p), (*t).to_string()))
        .collect()
}

#[test]
fn a_module_cycle_is_caught() {
    let src = files(&[
        (
            "main.rs",
            "mod draw;\nmod output;\nfn main() { output::say(); }\n",
        ),
        ("draw/mod.rs", "pub mod figure;\npub mod scene;\n"),
        (
            "draw/figure.rs",
            "use super::scene::{Point, hull};\npub struct Figure;\n",
        ),
        (
            "draw/scene.rs",
            "use crate::draw::{figure::{self, Figure}};\npub struct Point;\n",
        ),
        // Root ⇄ output through an item of the root (a macro's $crate).
        ("output.rs", "pub fn say() { crate::hint(); }\n"),
    ]);
    let mut src = src;
    src[0]
        .1
        .push_str("macro_rules! p { () => { $crate::output::say() } }\nfn hint() {}\n");
    assert_eq!(
        module_cycles(&src),
        [vec!["crate", "output"], vec!["draw::figure", "draw::scene"]]
    );
}

#[test]
fn module_paths_in_comments_strings_and_tests_make_no_edge() {
    let src = files(&[
        ("lib.rs", "pub mod a;\npub mod b;\n"),
        (
            "a.rs",
            "//! See [`crate::b::X`].\nuse crate::b::X;\nconst S: &str = \"crate::b\";\n",
        ),
        (
            "b.rs",
            "/* crate::a */\nconst R: &str = r#\"crate::a\"#;\nconst C: char = '\"';\n\
             #[cfg(test)]\nmod tests { use super::*; use super::super::b; }\n",
        ),
    ]);
    assert!(module_cycles(&src).is_empty(), "{:?}", module_cycles(&src));
    // Test code is left out: an inline #[cfg(test)] module, a test file.
    let mut src = src;
    src[2]
        .1
        .push_str("#[cfg(test)]\n#[allow(dead_code)]\nmod more { fn f() { crate::a::g(); } }\n");
    src[0].1.push_str("#[cfg(test)]\nmod c;\n");
    src.push((PathBuf::from("c.rs"), "use crate::a;\n".into()));
    src[1].1.push_str("use crate::c::T;\n");
    assert!(module_cycles(&src).is_empty(), "{:?}", module_cycles(&src));
    src[2].1.push_str("fn f() { crate::a::g(); }\n");
    assert_eq!(module_cycles(&src), [vec!["a", "b"]]);
}

#[test]
fn use_trees_expand_to_every_path() {
    assert_eq!(
        expand_use_tree(" crate::a::{b, c::{self, d as e}, *}"),
        [
            vec!["crate", "a", "b"],
            vec!["crate", "a", "c"],
            vec!["crate", "a", "c", "d"],
            vec!["crate", "a"],
        ]
    );
}

#[test]
fn allowed_cycles_are_allowed_only_in_their_crate() {
    let cycle = ["backend".to_string(), "schur".to_string()];
    assert!(cycle_allowed("mstar-kkt", &cycle));
    assert!(!cycle_allowed("mstar-model", &cycle));
    assert!(!cycle_allowed(
        "mstar-kkt",
        &["backend".to_string(), "solver".to_string()]
    ));
}
