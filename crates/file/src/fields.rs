//! Reading the keys of one table of a document: typed values, required and
//! optional keys, and unknown keys reported with the closest known one.

use std::ops::Range;

use super::FileError;
use super::node::{self, Entry, Node, Value};

/// The document being read: its name and text, for the places of errors.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Doc<'a> {
    pub(crate) origin: &'a str,
    pub(crate) text: &'a str,
    /// The `--set` overrides applied to the document, in order: the values
    /// they gave have spans that number them ([`node::override_span`]).
    pub(crate) overrides: &'a [String],
}

impl Doc<'_> {
    /// An error at `span` (when known); about a value an override gave,
    /// the error names the override (`--set KEY=VALUE: …`) and no line.
    pub(crate) fn error(&self, span: Option<&Range<usize>>, message: String) -> FileError {
        match span.and_then(|s| self.override_of(s)) {
            Some(assignment) => FileError::at(
                self.origin,
                "",
                None,
                format!("--set {assignment}: {message}"),
            ),
            None => FileError::at(self.origin, self.text, span.map(|s| s.start), message),
        }
    }

    /// The line of `span` in the file, when it is a place of the file.
    pub(crate) fn line(&self, span: Option<&Range<usize>>) -> Option<usize> {
        span.filter(|s| s.start < node::OVERRIDES_FROM)
            .map(|s| node::line_column(self.text, s.start).0)
    }

    /// The override (`KEY=VALUE`) whose value has the span `span`, if it
    /// is one.
    fn override_of(&self, span: &Range<usize>) -> Option<&str> {
        let k = span.start.checked_sub(node::OVERRIDES_FROM)?;
        // (An override's number out of the list: named by its flag alone.)
        Some(self.overrides.get(k).map_or("", String::as_str))
    }
}

/// The keys of one table, each read at most once; what is left at
/// [`finish`](Self::finish) is an unknown key.
pub(crate) struct Fields<'a> {
    doc: Doc<'a>,
    /// What the table is, for messages: `body 'crank'`, `[simulation]`.
    pub(crate) what: String,
    entries: &'a [Entry],
    span: Option<Range<usize>>,
    used: Vec<bool>,
}

impl<'a> Fields<'a> {
    /// The table `node` (an error if it is not one), described as `what`.
    pub(crate) fn of(doc: Doc<'a>, node: &'a Node, what: String) -> Result<Self, FileError> {
        let Value::Table(entries) = &node.value else {
            return Err(doc.error(
                node.span.as_ref(),
                format!("{what} must be a table, not {}", node.value.kind()),
            ));
        };
        Ok(Self {
            doc,
            what,
            entries,
            span: node.span.clone(),
            used: vec![false; entries.len()],
        })
    }

    /// Where the table is.
    pub(crate) fn span(&self) -> Option<&Range<usize>> {
        self.span.as_ref()
    }

    /// The value of `key`, not marked as read.
    pub(crate) fn peek(&self, key: &str) -> Option<&'a Node> {
        self.entries.iter().find(|e| e.key == key).map(|e| &e.node)
    }

    /// The entry `key`, marked as read.
    pub(crate) fn entry(&mut self, key: &str) -> Option<&'a Entry> {
        let k = self.entries.iter().position(|e| e.key == key)?;
        self.used[k] = true;
        Some(&self.entries[k])
    }

    /// The entry `key`, already read by the caller (a required key, or an
    /// optional one found): an error at the table, not a panic, if it was not.
    pub(crate) fn read_entry(&mut self, key: &str) -> Result<&'a Entry, FileError> {
        let span = self.span.clone();
        let what = self.what.clone();
        self.entry(key).ok_or_else(|| {
            self.doc
                .error(span.as_ref(), format!("{what}: the key '{key}' is missing"))
        })
    }

    /// An error about the value of `key`.
    pub(crate) fn bad(&self, entry: &Entry, why: impl std::fmt::Display) -> FileError {
        let span = entry.node.span.as_ref().or(entry.key_span.as_ref());
        self.doc
            .error(span, format!("{}: {}: {why}", self.what, entry.key))
    }

    /// An error about the value of `key`, read already (at the table if
    /// the key is not there).
    pub(crate) fn bad_key(&self, key: &str, why: impl std::fmt::Display) -> FileError {
        match self.entries.iter().find(|e| e.key == key) {
            Some(e) => self.bad(e, why),
            None => self
                .doc
                .error(self.span.as_ref(), format!("{}: {key}: {why}", self.what)),
        }
    }

    /// Every key of the table with an error placed at its value whose
    /// message is what precedes the key's own ([`Doc::error`]'s `--set …: `
    /// for a value an override gave, else nothing).
    pub(crate) fn places(&self) -> Vec<(String, FileError)> {
        self.entries
            .iter()
            .map(|e| {
                let span = e.node.span.as_ref().or(e.key_span.as_ref());
                (e.key.clone(), self.doc.error(span, String::new()))
            })
            .collect()
    }

    /// The value of `key` read by `parse`, if present.
    pub(crate) fn optional<T>(
        &mut self,
        key: &str,
        parse: impl FnOnce(&'a Node) -> Result<T, String>,
    ) -> Result<Option<T>, FileError> {
        match self.entry(key) {
            Some(e) => parse(&e.node).map(Some).map_err(|why| self.bad(e, why)),
            None => Ok(None),
        }
    }

    /// The value of `key` read by `parse`; an error naming the key if absent.
    pub(crate) fn required<T>(
        &mut self,
        key: &str,
        parse: impl FnOnce(&'a Node) -> Result<T, String>,
    ) -> Result<T, FileError> {
        self.optional(key, parse)?.ok_or_else(|| self.missing(key))
    }

    /// When a missing key (one of `keys`) is likely misspelt as an unread
    /// key of the table: the error about that key, where it is written.
    pub(crate) fn typo_of(&self, keys: &[&str]) -> Option<FileError> {
        let (e, key) = self
            .entries
            .iter()
            .zip(&self.used)
            .filter(|(_, used)| !**used)
            .find_map(|(e, _)| Some((e, closest(&e.key, keys)?)))?;
        Some(self.doc.error(
            e.key_span.as_ref().or(e.node.span.as_ref()),
            format!(
                "{}: unknown key '{}' (did you mean '{key}'?)",
                self.what, e.key
            ),
        ))
    }

    /// The error for a missing key; when an unread key is a likely typo of
    /// it, the error is about that one, where it is written.
    pub(crate) fn missing(&self, key: &str) -> FileError {
        if let Some(typo) = self.typo_of(&[key]) {
            return typo;
        }
        self.doc.error(
            self.span.as_ref(),
            format!("{}: the key '{key}' is missing", self.what),
        )
    }

    /// Checks that every key was read or is one of `known` (read by someone
    /// else): an unknown key is an error naming the known ones (and the
    /// closest, for a typo).
    pub(crate) fn finish(&self, known: &[&str]) -> Result<(), FileError> {
        let unknown = |(e, used): (&Entry, &bool)| !used && !known.contains(&e.key.as_str());
        let Some(k) = self.entries.iter().zip(&self.used).position(unknown) else {
            return Ok(());
        };
        let e = &self.entries[k];
        let hint = closest(&e.key, known)
            .map(|c| format!(" (did you mean '{c}'?)"))
            .unwrap_or_default();
        let given = if e.created { " (given by --set)" } else { "" };
        // A key an override added has no place (its message says so); one
        // inside a value an override gave names the override.
        let span = e.key_span.as_ref().or(e.node.span.as_ref());
        let by_override = e.created || span.is_some_and(|s| s.start >= node::OVERRIDES_FROM);
        let error = self.doc.error(
            span.filter(|_| !e.created),
            format!(
                "{}: unknown key '{}'{given}{hint}; the keys here are: {}",
                self.what,
                e.key,
                known.join(", ")
            ),
        );
        Err(if by_override {
            error.of_override()
        } else {
            error
        })
    }
}

/// The known key closest to `key` by edit distance (Levenshtein, in
/// characters), if it is a likely typo.
fn closest<'k>(key: &str, known: &[&'k str]) -> Option<&'k str> {
    known
        .iter()
        .map(|&k| (strsim::levenshtein(key, k), k))
        // One edit for a short key (`foo` is not a typo of `rho`), a third
        // of a longer one.
        .filter(|&(d, k)| d <= 1.max(k.len() / 3))
        .min()
        .map(|(_, k)| k)
}

/// `x` as written in a message: exponent form outside [1e-4, 1e6), so that
/// 1e308 is not 309 digits.
pub(crate) fn short(x: f64) -> String {
    if x != 0.0 && x.is_finite() && !(1e-4..1e6).contains(&x.abs()) {
        format!("{x:e}")
    } else {
        format!("{x}")
    }
}

/// The largest magnitude a number of a model file may have. The equations
/// of motion multiply given values with each other (`m g l`, `½ m v²`, the
/// KKT matrix's `m / (β h²)`): from 1e100 on, such products overflow double
/// precision (about 1.8e308) and a run would fail with a misleading
/// diagnosis (a singular matrix, NaN), so such values are refused where
/// they are written.
pub const MAX_MAGNITUDE: f64 = 1e100;

/// A finite number of magnitude at most [`MAX_MAGNITUDE`].
pub(crate) fn number(node: &Node) -> Result<f64, String> {
    match node.value {
        Value::Num { value, .. } if value.abs() <= MAX_MAGNITUDE => Ok(value),
        Value::Num { value, .. } if value.is_finite() => Err(format!(
            "{} is out of range: numbers of a model file must be at most 1e100 in magnitude \
             (products of larger values overflow double precision); choose units that bring \
             it nearer 1",
            short(value)
        )),
        Value::Num { value, .. } => Err(format!("must be a finite number, not {value}")),
        ref v => Err(format!("expected a number, found {}", v.kind())),
    }
}

/// A number checked by `ok`, which describes the range in `range`.
pub(crate) fn number_in(
    ok: impl Fn(f64) -> bool,
    range: &str,
) -> impl Fn(&Node) -> Result<f64, String> {
    move |node| {
        let x = number(node)?;
        if ok(x) {
            Ok(x)
        } else {
            Err(format!("must be {range} (got {})", short(x)))
        }
    }
}

/// A whole number of at least `min`, written as an integer or not (`2.0`:
/// in JSON, 2.0 and 2 are the same number).
pub(crate) fn count(min: usize) -> impl Fn(&Node) -> Result<usize, String> {
    move |node| match node.value {
        Value::Num { value, .. } if value >= min as f64 && value < 1e15 && value.fract() == 0.0 => {
            Ok(value as usize)
        }
        Value::Num { value, .. } => Err(format!(
            "must be a whole number of at least {min} (got {})",
            short(value)
        )),
        ref v => Err(format!("expected a whole number, found {}", v.kind())),
    }
}

/// A string.
pub(crate) fn string(node: &Node) -> Result<&str, String> {
    match &node.value {
        Value::Str(s) => Ok(s),
        v => Err(format!("expected a string, found {}", v.kind())),
    }
}

/// One of the strings in `choices`.
pub(crate) fn choice<'c>(choices: &'c [&'c str]) -> impl Fn(&Node) -> Result<&'c str, String> {
    move |node| {
        let s = string(node)?;
        choices
            .iter()
            .find(|&&c| c == s)
            .copied()
            .ok_or_else(|| format!("'{s}' is not one of: {}", choices.join(", ")))
    }
}

/// The items of an array.
pub(crate) fn list(node: &Node) -> Result<&[Node], String> {
    match &node.value {
        Value::List(items) => Ok(items),
        v => Err(format!("expected an array, found {}", v.kind())),
    }
}

/// An array of `N` numbers.
pub(crate) fn numbers<const N: usize>(node: &Node) -> Result<[f64; N], String> {
    let items = list(node)?;
    if items.len() != N {
        return Err(format!("expected {N} numbers, found {}", items.len()));
    }
    let mut out = [0.0; N];
    for (o, item) in out.iter_mut().zip(items) {
        *o = number(item)?;
    }
    Ok(out)
}

/// Two points `[[x, y], [x, y]]`.
pub(crate) fn two_points(node: &Node) -> Result<[[f64; 2]; 2], String> {
    let items = list(node)?;
    if items.len() != 2 {
        return Err(format!(
            "expected two points [[x, y], [x, y]], found {} items",
            items.len()
        ));
    }
    Ok([numbers::<2>(&items[0])?, numbers::<2>(&items[1])?])
}

/// Two names `["a", "b"]`.
pub(crate) fn two_names(node: &Node) -> Result<[&str; 2], String> {
    let items = list(node)?;
    if items.len() != 2 {
        return Err(format!(
            "expected two names [\"a\", \"b\"], found {} items",
            items.len()
        ));
    }
    Ok([string(&items[0])?, string(&items[1])?])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn huge_and_tiny_numbers_are_short() {
        assert_eq!(short(1e308), "1e308");
        assert_eq!(short(-2.5e-300), "-2.5e-300");
        assert_eq!(short(0.25), "0.25");
        assert_eq!(short(0.0), "0");
    }

    #[test]
    fn a_typo_suggests_the_closest_key() {
        assert_eq!(strsim::levenshtein("mas", "mass"), 1);
        assert_eq!(strsim::levenshtein("intertia", "inertia"), 1);
        assert_eq!(closest("mas", &["name", "mass", "inertia"]), Some("mass"));
        assert_eq!(closest("colour", &["name", "mass"]), None);
    }
}
