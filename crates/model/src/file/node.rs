//! A parsed document as a tree of values, each with its place in the file
//! when the format tells it (TOML: byte ranges of keys and values; JSON:
//! only syntax errors have a place), so that every later error can point at
//! the key it is about.

use std::ops::Range;

use super::FileError;

/// A value of the document and where it is.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Node {
    pub(crate) value: Value,
    /// Byte range in the source, when known.
    pub(crate) span: Option<Range<usize>>,
}

/// The kinds of values a document holds.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Value {
    Str(String),
    /// A number; `integer` when it was written without a fraction or exponent.
    Num {
        value: f64,
        integer: bool,
    },
    Bool(bool),
    List(Vec<Node>),
    Table(Vec<Entry>),
    /// Anything else the format has (a TOML date).
    Other(&'static str),
}

/// A key of a table and its value.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Entry {
    pub(crate) key: String,
    pub(crate) key_span: Option<Range<usize>>,
    pub(crate) node: Node,
    /// Added by a command-line override (`--set`), not written in the file:
    /// an unknown key here is the override's error.
    pub(crate) created: bool,
}

impl Value {
    /// What a value of this kind is called in messages.
    pub(crate) fn kind(&self) -> &'static str {
        match self {
            Self::Str(_) => "a string",
            Self::Num { integer: true, .. } => "an integer",
            Self::Num { .. } => "a number",
            Self::Bool(_) => "a boolean",
            Self::List(_) => "an array",
            Self::Table(_) => "a table",
            Self::Other(kind) => kind,
        }
    }
}

/// Parses a TOML document.
pub(crate) fn parse_toml(text: &str, origin: &str) -> Result<Node, FileError> {
    let doc = toml::de::DeTable::parse(text).map_err(|e| {
        let at = e.span().map(|s| s.start);
        // The message's first line; toml adds a rendering of the source.
        let message = e
            .message()
            .lines()
            .next()
            .unwrap_or("invalid TOML")
            .trim()
            .to_string();
        FileError::at(origin, text, at, format!("TOML syntax: {message}"))
    })?;
    let span = doc.span();
    Ok(Node {
        value: Value::Table(toml_table(doc.into_inner())),
        span: Some(span),
    })
}

fn toml_table(table: toml::de::DeTable<'_>) -> Vec<Entry> {
    table
        .into_iter()
        .map(|(key, value)| {
            let key_span = key.span();
            Entry {
                key: key.into_inner().into_owned(),
                key_span: Some(key_span),
                node: toml_node(value),
                created: false,
            }
        })
        .collect()
}

fn toml_node(value: toml::Spanned<toml::de::DeValue<'_>>) -> Node {
    use toml::de::DeValue;
    let span = value.span();
    let value = match value.into_inner() {
        DeValue::String(s) => Value::Str(s.into_owned()),
        DeValue::Integer(i) => i64::from_str_radix(i.as_str(), i.radix()).map_or(
            Value::Other("an integer too large"),
            |v| Value::Num {
                // Integers of the documents are small (counts, every n-th).
                value: v as f64,
                integer: true,
            },
        ),
        DeValue::Float(f) => {
            f.as_str()
                .parse::<f64>()
                .map_or(Value::Other("a malformed number"), |v| Value::Num {
                    value: v,
                    integer: false,
                })
        }
        DeValue::Boolean(b) => Value::Bool(b),
        DeValue::Datetime(_) => Value::Other("a date"),
        DeValue::Array(items) => Value::List(items.into_iter().map(toml_node).collect()),
        DeValue::Table(table) => Value::Table(toml_table(table)),
    };
    Node {
        value,
        span: Some(span),
    }
}

/// Parses a JSON document (syntax errors have a line and column; the values
/// of the tree have none).
pub(crate) fn parse_json(text: &str, origin: &str) -> Result<Node, FileError> {
    let value: serde_json::Value = serde_json::from_str(text).map_err(|e| FileError {
        origin: origin.to_string(),
        place: (e.line() > 0).then_some((e.line(), e.column())),
        message: format!("JSON syntax: {e}"),
        in_override: false,
    })?;
    Ok(json_node(value))
}

fn json_node(value: serde_json::Value) -> Node {
    use serde_json::Value as J;
    let value = match value {
        J::String(s) => Value::Str(s),
        J::Number(n) => match n.as_f64() {
            Some(v) => Value::Num {
                value: v,
                integer: n.is_i64() || n.is_u64(),
            },
            None => Value::Other("a number out of range"),
        },
        J::Bool(b) => Value::Bool(b),
        J::Null => Value::Other("null"),
        J::Array(items) => Value::List(items.into_iter().map(json_node).collect()),
        J::Object(map) => Value::Table(
            map.into_iter()
                .map(|(key, value)| Entry {
                    key,
                    key_span: None,
                    node: json_node(value),
                    created: false,
                })
                .collect(),
        ),
    };
    Node { value, span: None }
}

/// Line and column (both from 1, the column in characters) of byte `offset`.
pub(crate) fn line_column(text: &str, offset: usize) -> (usize, usize) {
    let offset = offset.min(text.len());
    let before = text.get(..offset).unwrap_or(text);
    let line = before.matches('\n').count() + 1;
    let start = before.rfind('\n').map_or(0, |k| k + 1);
    let column = before[start..].chars().count() + 1;
    (line, column)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_and_columns_count_characters() {
        let text = "a = 1\nbé = 2\n";
        assert_eq!(line_column(text, 0), (1, 1));
        assert_eq!(line_column(text, 6), (2, 1));
        // After "bé " (é is two bytes): column 4.
        assert_eq!(line_column(text, 10), (2, 4));
        assert_eq!(line_column(text, 1000), (3, 1));
    }

    #[test]
    fn toml_and_json_give_the_same_tree_but_places() {
        let toml = parse_toml("x = 1\ny = [2.5, \"a\"]\n[t]\nb = true\n", "f.toml").expect("valid");
        let json =
            parse_json(r#"{"x": 1, "y": [2.5, "a"], "t": {"b": true}}"#, "f.json").expect("valid");
        fn strip(n: &Node) -> Node {
            let value = match &n.value {
                Value::List(items) => Value::List(items.iter().map(strip).collect()),
                Value::Table(entries) => {
                    let mut e: Vec<Entry> = entries
                        .iter()
                        .map(|e| Entry {
                            key: e.key.clone(),
                            key_span: None,
                            node: strip(&e.node),
                            created: false,
                        })
                        .collect();
                    e.sort_by(|a, b| a.key.cmp(&b.key));
                    Value::Table(e)
                }
                v => v.clone(),
            };
            Node { value, span: None }
        }
        assert_eq!(strip(&toml), strip(&json));
        let Value::Table(entries) = &toml.value else {
            panic!("a table")
        };
        assert!(
            entries
                .iter()
                .all(|e| e.key_span.is_some() && e.node.span.is_some())
        );
    }

    #[test]
    fn syntax_errors_have_a_line_and_column() {
        let e = parse_toml("a = 1\nb = = 2\n", "m.toml").expect_err("invalid");
        assert_eq!(e.place.map(|p| p.0), Some(2), "{e}");
        assert!(e.to_string().starts_with("m.toml:2:"), "{e}");
        let e = parse_json("{\n  \"a\": 1,\n  \"b\" 2\n}", "m.json").expect_err("invalid");
        assert_eq!(e.place.map(|p| p.0), Some(3), "{e}");
        assert!(e.to_string().starts_with("m.json:3:"), "{e}");
    }
}
