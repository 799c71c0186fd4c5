//! Numeric keys of a model document by their dotted path, as `--set
//! KEY=VALUE` names them (`settings::apply_override`): a key of a table, or
//! the `name` of an element of an array of tables (`body.crank.mass`). Used
//! by `mstar run --sensitivity KEY` to read a parameter's value.

use crate::node::{Node, Value};

/// How many of the closest keys an error suggests.
const SUGGESTED: usize = 5;

/// The number at the dotted path `key` of `root`.
///
/// # Errors
/// A message for a path that is malformed, names nothing, or names a value
/// that is not a number, with the closest numeric keys of the document.
pub(crate) fn number(root: &Node, key: &str) -> Result<f64, String> {
    let parts: Vec<&str> = key.split('.').map(str::trim).collect();
    let found = if parts.iter().any(|p| p.is_empty()) {
        None
    } else {
        parts.iter().try_fold(root, |node, part| child(node, part))
    };
    match found.map(|n| &n.value) {
        Some(Value::Num { value, .. }) => Ok(*value),
        Some(other) => Err(format!(
            "'{key}' is {}, not a number; {}",
            other.kind(),
            suggestions(root, key)
        )),
        None => Err(not_given(root, key, &parts)),
    }
}

/// The message for a path that names nothing: when its element is there
/// but does not give the last key (a default: a joint's `length` from the
/// initial pose), what to write in the file; the closest keys.
fn not_given(root: &Node, key: &str, parts: &[&str]) -> String {
    let element = match parts.split_last() {
        Some((last, parent)) if !parent.is_empty() && !last.is_empty() => parent
            .iter()
            .try_fold(root, |node, part| child(node, part))
            .filter(|n| matches!(n.value, Value::Table(_)))
            // (A key of the element one edit or a third away is a typo of
            // it, not a default: the closest keys say so.)
            .filter(|n| !has_close_key(n, last))
            .map(|_| (parent.join("."), *last)),
        _ => None,
    };
    match element {
        Some((parent, last)) => format!(
            "the model has no numeric key '{key}': '{parent}' does not give '{last}' (its value is a default, such as a length taken from the initial pose); write '{last} = <value>' in the file to make it a key; {}",
            suggestions(root, key)
        ),
        None => format!(
            "the model has no numeric key '{key}'; {}",
            suggestions(root, key)
        ),
    }
}

/// Whether the table `node` has a key within a typo of `key` (one edit for
/// a short key, a third of a longer one).
fn has_close_key(node: &Node, key: &str) -> bool {
    let Value::Table(entries) = &node.value else {
        return false;
    };
    entries
        .iter()
        .any(|e| strsim::levenshtein(&e.key, key) <= 1.max(e.key.len() / 3))
}

/// The node `part` names inside `node`: a key of a table, or the element of
/// an array whose `name` it is.
fn child<'n>(node: &'n Node, part: &str) -> Option<&'n Node> {
    match &node.value {
        Value::Table(entries) => entries.iter().find(|e| e.key == part).map(|e| &e.node),
        Value::List(items) => items.iter().find(|n| name_of(n) == Some(part)),
        _ => None,
    }
}

/// The `name` of an element of an array of tables.
fn name_of(node: &Node) -> Option<&str> {
    let Value::Table(entries) = &node.value else {
        return None;
    };
    entries
        .iter()
        .find(|e| e.key == "name")
        .and_then(|e| match &e.node.value {
            Value::Str(s) => Some(s.as_str()),
            _ => None,
        })
}

/// Every numeric key of the document, by its dotted path.
fn numeric_keys(node: &Node, prefix: &str, out: &mut Vec<String>) {
    let join = |k: &str| {
        if prefix.is_empty() {
            k.to_string()
        } else {
            format!("{prefix}.{k}")
        }
    };
    match &node.value {
        Value::Num { .. } if !prefix.is_empty() => out.push(prefix.to_string()),
        Value::Table(entries) => {
            for e in entries {
                numeric_keys(&e.node, &join(&e.key), out);
            }
        }
        Value::List(items) => {
            for item in items {
                if let Some(name) = name_of(item) {
                    numeric_keys(item, &join(name), out);
                }
            }
        }
        _ => {}
    }
}

/// "the closest numeric keys are: …", by edit distance to `key`.
fn suggestions(root: &Node, key: &str) -> String {
    let mut keys = Vec::new();
    numeric_keys(root, "", &mut keys);
    // The run's settings are no parameters of the model.
    keys.retain(|k| !k.starts_with("simulation.") && !k.starts_with("output."));
    if keys.is_empty() {
        return "the model has no numeric keys".into();
    }
    keys.sort_by_key(|k| (strsim::levenshtein(key, k), k.clone()));
    keys.truncate(SUGGESTED);
    format!(
        "the closest numeric keys are: {} (a key of a table, or an element's name then its key, as --set takes)",
        keys.join(", ")
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn doc() -> Node {
        crate::node::parse_toml(
            "gravity = [0.0, -9.81]\n[[body]]\nname = \"crank\"\nmass = 0.5\n\
             [[joint]]\nname = \"rod\"\ntype = \"distance\"\nlength = 0.8\n\
             [simulation]\nh = 1e-3\n",
            "t.toml",
        )
        .expect("the document parses")
    }

    /// An element that does not give the key: what to write in the file.
    #[test]
    fn a_key_left_to_its_default_says_to_write_it() {
        let e = number(&doc(), "body.crank.inertia").expect_err("not given");
        assert!(
            e.starts_with(
                "the model has no numeric key 'body.crank.inertia': 'body.crank' does not give 'inertia'"
            ) && e.contains("write 'inertia = <value>' in the file"),
            "{e}"
        );
    }

    #[test]
    fn reads_a_number_by_its_dotted_path() {
        assert_eq!(number(&doc(), "body.crank.mass"), Ok(0.5));
        assert_eq!(number(&doc(), "joint.rod.length"), Ok(0.8));
        assert_eq!(number(&doc(), "simulation.h"), Ok(1e-3));
    }

    #[test]
    fn a_wrong_key_names_the_closest_numeric_keys() {
        let e = number(&doc(), "body.crank.mas").expect_err("a typo");
        assert!(
            e.starts_with("the model has no numeric key 'body.crank.mas'"),
            "{e}"
        );
        assert!(
            e.contains("closest numeric keys are: body.crank.mass,"),
            "{e}"
        );
        let e = number(&doc(), "joint.rod.type").expect_err("a string");
        assert!(
            e.starts_with("'joint.rod.type' is a string, not a number"),
            "{e}"
        );
        let e = number(&doc(), "body..mass").expect_err("an empty key");
        assert!(e.contains("no numeric key 'body..mass'"), "{e}");
    }
}
