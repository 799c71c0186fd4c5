//! A TOML model file rewritten with a new initial pose, everything else of
//! the text (comments, order, other keys) kept: `mstar equilibrium
//! --write-model`.

use toml_edit::{Array, DocumentMut, Item, Value};

/// The TOML text `text` of a model file with the initial pose of the
/// elements in `poses` replaced: `(name, values)` with the element's
/// coordinates in the model's order. A `[[body]]` with 3 values gets `pose
/// = [x, y, θ]` (planar), with 7 `position = [x, y, z]` and `orientation =
/// [e0, e1, e2, e3]` (spatial); a `[[point_mass]]` gets `position`.
///
/// # Errors
/// A message when the text is not TOML, or when an element is missing or
/// has a number of values that fits no pose.
pub fn with_initial_pose(text: &str, poses: &[(String, Vec<f64>)]) -> Result<String, String> {
    let mut doc: DocumentMut = text
        .parse()
        .map_err(|e| format!("not a TOML model file: {e}"))?;
    for (name, values) in poses {
        set_pose(&mut doc, name, values)?;
    }
    Ok(doc.to_string())
}

/// Sets the pose keys of the element `name`.
fn set_pose(doc: &mut DocumentMut, name: &str, values: &[f64]) -> Result<(), String> {
    for kind in ["body", "point_mass"] {
        let Some(tables) = doc.get_mut(kind).and_then(Item::as_array_of_tables_mut) else {
            continue;
        };
        let found = tables
            .iter_mut()
            .find(|t| t.get("name").and_then(Item::as_str) == Some(name));
        let Some(table) = found else {
            continue;
        };
        let keys: &[(&str, std::ops::Range<usize>)] = match (kind, values.len()) {
            ("body", 3) => &[("pose", 0..3)],
            ("body", 7) => &[("position", 0..3), ("orientation", 3..7)],
            ("point_mass", 2 | 3) => &[("position", 0..values.len())],
            _ => {
                return Err(format!(
                    "[[{kind}]] '{name}': {} coordinates fit no pose",
                    values.len()
                ));
            }
        };
        for (key, range) in keys {
            let array: Array = values[range.clone()].iter().copied().collect();
            table.insert(key, Item::Value(Value::Array(array)));
        }
        return Ok(());
    }
    Err(format!(
        "no [[body]] or [[point_mass]] named '{name}' in the file"
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The pose keys change, the comments and other keys stay.
    #[test]
    fn pose_replaced_comments_kept() {
        let text = "# a comment\n[[body]]\nname = \"bob\" # the bob\nmass = 1.0\npose = [1.0, 0.0, 1.5]\n\n[[point_mass]]\nname = \"p\"\nposition = [0.0, 0.0]\n";
        let poses = vec![
            ("bob".to_string(), vec![0.0, -1.0, 0.25]),
            ("p".to_string(), vec![2.0, 3.5]),
        ];
        let out = with_initial_pose(text, &poses).unwrap_or_default();
        assert!(
            out.contains("# a comment") && out.contains("# the bob"),
            "{out}"
        );
        assert!(out.contains("pose = [0.0, -1.0, 0.25]"), "{out}");
        assert!(out.contains("position = [2.0, 3.5]"), "{out}");
        assert!(out.contains("mass = 1.0"), "{out}");
        let missing = with_initial_pose(text, &[("nobody".to_string(), vec![0.0; 3])]);
        assert!(missing.is_err_and(|e| e.contains("'nobody'")));
    }
}
