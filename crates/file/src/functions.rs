//! Time functions of drivers and loads: `{ constant = v }`, `{ linear = {
//! value, rate } }`, `{ harmonic = { offset, amplitude, omega, phase } }`,
//! `{ table = [[t, v], ...] }`, or a bare number for a constant.

use super::FileError;
use super::fields::{Doc, Fields, list, number, numbers};
use super::node::{Node, Value};
use mstar_model::planar::TimeFunction;

/// The kinds of functions, the key of the one-entry table that gives one.
const KINDS: [&str; 4] = ["constant", "linear", "harmonic", "table"];

/// Reads the function `node`, described as `what` in errors.
pub(crate) fn read(doc: Doc<'_>, node: &Node, what: String) -> Result<TimeFunction, FileError> {
    if let Value::Num { .. } = node.value {
        return number(node)
            .map(TimeFunction::Constant)
            .map_err(|why| doc.error(node.span.as_ref(), format!("{what}: {why}")));
    }
    let Value::Table(entries) = &node.value else {
        return Err(doc.error(
            node.span.as_ref(),
            format!(
                "{what}: expected a function, {{ constant = v }} or one of {}, found {}",
                KINDS.join(", "),
                node.value.kind()
            ),
        ));
    };
    // A key an override added beside the function's own, or in place of
    // it, is the override's error.
    let added = |e: FileError| {
        if entries.iter().any(|e| e.created) {
            e.of_override()
        } else {
            e
        }
    };
    let [entry] = entries.as_slice() else {
        return Err(added(doc.error(
            node.span.as_ref(),
            format!(
                "{what}: a function is a table with one key, one of: {}",
                KINDS.join(", ")
            ),
        )));
    };
    let inner = &entry.node;
    let place = inner.span.as_ref().or(entry.key_span.as_ref());
    let function = match entry.key.as_str() {
        "constant" => number(inner)
            .map(TimeFunction::Constant)
            .map_err(|why| doc.error(place, format!("{what}: constant: {why}")))?,
        "linear" => linear(doc, inner, format!("{what}: linear"))?,
        "harmonic" => harmonic(doc, inner, format!("{what}: harmonic"))?,
        "table" => table(inner).map_err(|why| doc.error(place, format!("{what}: table: {why}")))?,
        other => {
            return Err(added(doc.error(
                entry.key_span.as_ref(),
                format!(
                    "{what}: unknown function '{other}'; the functions are: {}",
                    KINDS.join(", ")
                ),
            )));
        }
    };
    match function.problem() {
        Some(problem) => Err(doc.error(place, format!("{what}: {problem}"))),
        None => Ok(function),
    }
}

/// `{ value, rate }`: `value + rate · t`.
fn linear(doc: Doc<'_>, node: &Node, what: String) -> Result<TimeFunction, FileError> {
    let mut f = Fields::of(doc, node, what)?;
    let value = f.optional("value", number)?.unwrap_or(0.0);
    let rate = f.required("rate", number)?;
    f.finish(&["value", "rate"])?;
    Ok(TimeFunction::Linear { value, rate })
}

/// `{ offset, amplitude, omega, phase }`: `offset + amplitude sin(omega t + phase)`.
fn harmonic(doc: Doc<'_>, node: &Node, what: String) -> Result<TimeFunction, FileError> {
    let mut f = Fields::of(doc, node, what)?;
    let offset = f.optional("offset", number)?.unwrap_or(0.0);
    let amplitude = f.required("amplitude", number)?;
    let omega = f.required("omega", number)?;
    let phase = f.optional("phase", number)?.unwrap_or(0.0);
    f.finish(&["offset", "amplitude", "omega", "phase"])?;
    Ok(TimeFunction::Sine {
        offset,
        amplitude,
        omega,
        phase,
    })
}

/// `[[t, v], ...]`, piecewise linear.
fn table(node: &Node) -> Result<TimeFunction, String> {
    let points = list(node)?
        .iter()
        .map(|p| numbers::<2>(p).map(|[t, v]| (t, v)))
        .collect::<Result<Vec<_>, String>>()
        .map_err(|why| format!("each point is [t, value]: {why}"))?;
    Ok(TimeFunction::Table(points))
}
