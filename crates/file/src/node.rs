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

/// Parses a TOML document: from [`PARTS_FROM`] bytes on, in parts in
/// parallel when rayon has more than one thread ([`parse_toml_parts`]).
pub(crate) fn parse_toml(text: &str, origin: &str) -> Result<Node, FileError> {
    if text.len() >= PARTS_FROM
        && rayon::current_num_threads() > 1
        && let Some(root) = parse_toml_parts(text, PARTS_FROM / 4)
    {
        return Ok(root);
    }
    parse_toml_whole(text, origin)
}

/// The size from which a TOML document is parsed in parts, bytes.
const PARTS_FROM: usize = 4 << 20;

/// Parses a TOML document in one piece.
fn parse_toml_whole(text: &str, origin: &str) -> Result<Node, FileError> {
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
        value: Value::Table(toml_table(doc.into_inner(), 0)),
        span: Some(span),
    })
}

/// The tree of a TOML document parsed in parts of at least `part_bytes`
/// bytes in parallel, the same as [`parse_toml_whole`] gives, or `None`
/// when the parts do not give it (then the document is parsed whole, which
/// also reports its errors).
///
/// A part after the first starts at a line that starts with `[[` (an array
/// of tables, `[[body]]`), and each is parsed as a document of its own.
/// When every part parses, every boundary is at the start of a statement
/// (a part that ended inside a string, an array or an inline table would
/// not parse), so each part's text means there what it means in the whole
/// document. The root of a later part holds only what its own headers
/// opened: a key new to the parts before is added as it is; an array of
/// tables (`[[key]]`) is appended to the array of tables of the same key
/// before, as the whole document would append it. Anything else (a table
/// `[key]` or `[key.sub]` whose key the parts before have, or an array to
/// append to that is not an array of tables) gives `None`.
fn parse_toml_parts(text: &str, part_bytes: usize) -> Option<Node> {
    use rayon::prelude::*;
    let starts = part_starts(text.as_bytes(), part_bytes.max(1));
    if starts.len() < 2 {
        return None;
    }
    let parts: Vec<Option<(Range<usize>, Vec<Entry>)>> = (0..starts.len())
        .into_par_iter()
        .map(|k| {
            let end = starts.get(k + 1).copied().unwrap_or(text.len());
            let doc = toml::de::DeTable::parse(text.get(starts[k]..end)?).ok()?;
            let span = shift(doc.span(), starts[k]);
            Some((span, toml_table(doc.into_inner(), starts[k])))
        })
        .collect();
    let mut parts = parts.into_iter();
    let (span, mut root) = parts.next()??;
    for part in parts {
        for entry in part?.1 {
            append_tables(text, &mut root, entry)?;
        }
    }
    Some(Node {
        value: Value::Table(root),
        span: Some(span),
    })
}

/// Where the parts of [`parse_toml_parts`] start: 0, then at the first line
/// starting with `[[` at least `part_bytes` after the previous start.
fn part_starts(text: &[u8], part_bytes: usize) -> Vec<usize> {
    let mut starts = vec![0];
    let mut from = part_bytes;
    while from < text.len() {
        let Some(k) = text[from..].windows(3).position(|w| w == b"\n[[") else {
            break;
        };
        // After the newline: a character boundary.
        let start = from + k + 1;
        starts.push(start);
        from = start + part_bytes;
    }
    starts
}

/// Adds the root entry `entry` of a later part to `root` (see
/// [`parse_toml_parts`]): a key not in `root` yet as it is, an array of
/// tables appended to the one of the same key; `None` for anything else.
fn append_tables(text: &str, root: &mut Vec<Entry>, entry: Entry) -> Option<()> {
    match root.binary_search_by(|e| e.key.as_str().cmp(&entry.key)) {
        Ok(k) => {
            let Value::List(tables) = entry.node.value else {
                return None;
            };
            let before = &mut root[k].node;
            if !opened_by_header(text, before.span.as_ref()) {
                return None;
            }
            let Value::List(items) = &mut before.value else {
                return None;
            };
            items.extend(tables);
        }
        Err(k) => root.insert(k, entry),
    }
    Some(())
}

/// Whether a value of the root at `span` is an array of tables: toml gives
/// it the span of its first header `[[key]]`, alone on its line but for
/// blanks, where an array written as a value has `key =` before it.
fn opened_by_header(text: &str, span: Option<&Range<usize>>) -> bool {
    let Some(start) = span.map(|s| s.start) else {
        return false;
    };
    let (Some(before), Some(after)) = (text.get(..start), text.get(start..)) else {
        return false;
    };
    let line = before.rfind('\n').map_or(before, |k| &before[k + 1..]);
    after.starts_with("[[") && line.trim().is_empty()
}

/// `span` moved `by` bytes on.
fn shift(span: Range<usize>, by: usize) -> Range<usize> {
    span.start + by..span.end + by
}

fn toml_table(table: toml::de::DeTable<'_>, offset: usize) -> Vec<Entry> {
    table
        .into_iter()
        .map(|(key, value)| {
            let key_span = shift(key.span(), offset);
            Entry {
                key: key.into_inner().into_owned(),
                key_span: Some(key_span),
                node: toml_node(value, offset),
                created: false,
            }
        })
        .collect()
}

fn toml_node(value: toml::Spanned<toml::de::DeValue<'_>>, offset: usize) -> Node {
    use toml::de::DeValue;
    let span = shift(value.span(), offset);
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
        DeValue::Array(items) => Value::List(
            items
                .into_iter()
                .map(|item| toml_node(item, offset))
                .collect(),
        ),
        DeValue::Table(table) => Value::Table(toml_table(table, offset)),
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

/// Where the spans of values given on the command line start: a span from
/// here on is no place in the file but the value of the `--set` override
/// number `start - OVERRIDES_FROM` (counted over every override applied to
/// the document), so that an error about it names the override instead of
/// a line of the file ([`crate::fields::Doc::error`]). No file is that long.
pub(crate) const OVERRIDES_FROM: usize = usize::MAX / 2;

/// The span that stands for the value of override number `k`.
pub(crate) fn override_span(k: usize) -> Range<usize> {
    let at = OVERRIDES_FROM.saturating_add(k);
    at..at
}

/// Gives `node` and everything in it (keys included) the span `span`: the
/// spans of a value parsed from the command line are places in that text,
/// not in the file.
pub(crate) fn respan(node: &mut Node, span: &Range<usize>) {
    node.span = Some(span.clone());
    match &mut node.value {
        Value::List(items) => items.iter_mut().for_each(|n| respan(n, span)),
        Value::Table(entries) => {
            for e in entries {
                e.key_span = Some(span.clone());
                respan(&mut e.node, span);
            }
        }
        _ => {}
    }
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

    /// Documents whose parts give the whole document's tree, places included.
    #[test]
    fn parts_give_the_whole_tree() {
        let n_four_bar = include_str!("../../../models/n-four-bar.toml");
        let docs = [
            n_four_bar,
            "format = \"x\"\n[[body]]\nname = \"a\"\n[[joint]]\nname = \"j\"\n\n[[body]]\nname = \"b\"\n[simulation]\nh = 1\n",
            "[[a]]\nx = 1\n[a.t]\ny = 2\n  [[a.sub]]\nz = 3\n  [[a]]\nx = 4\n[[b]]\n[[a]]\n[c]\n",
            "s = '''[[a]]'''\n[[a]]\nq = \"\"\"\n  [[a]]\"\"\"\n[[a]]\n",
        ];
        for doc in docs {
            let whole = parse_toml_whole(doc, "m.toml").expect("valid");
            for bytes in [1, 7, 40] {
                let parts = parse_toml_parts(doc, bytes);
                assert_eq!(parts.as_ref(), Some(&whole), "{bytes}: {doc}");
            }
        }
        assert!(part_starts(n_four_bar.as_bytes(), 1).len() > 100);
    }

    /// Where a part could mean something else alone, the parts refuse (and
    /// the whole document is parsed: its tree, or its error).
    #[test]
    fn parts_refuse_what_they_cannot_mean_alone() {
        for (doc, valid) in [
            // A part would end inside a multi-line string, an array.
            ("s = \"\"\"\n[[a]]\n\"\"\"\n", true),
            ("s = '''\n[[a]] in a string'''\n[[a]]\n", true),
            ("x = [\n[[1]],\n]\n", true),
            // A table of an element of an earlier part.
            ("[[a]]\nx = 1\n[[b]]\n[a.t]\ny = 2\n", true),
            ("[[a]]\nx = 1\n[[a.sub]]\ny = 2\n", true),
            // Appending to an array written as a value, or to a table.
            ("a = [{x = 1}]\n[[a]]\nx = 2\n", false),
            ("[a]\nx = 1\n[[a]]\n", false),
        ] {
            assert_eq!(parse_toml_parts(doc, 1), None, "{doc}");
            assert_eq!(parse_toml(doc, "m.toml").is_ok(), valid, "{doc}");
        }
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
