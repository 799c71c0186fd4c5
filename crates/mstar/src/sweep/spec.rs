//! The parameters of a sweep as the command line writes them:
//! `KEY=V1,V2,…` (values in TOML syntax, commas inside `[…]`, `{…}` and
//! quotes belong to the value) or `KEY=START:STOP:COUNT` (an inclusive
//! linspace).

use super::SweepError;

/// One swept key and its values, each in TOML syntax (or a bare word, taken
/// as a string), as `--set KEY=VALUE` takes them.
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Param {
    /// A dotted path into the model file (`simulation.h`, `body.upper.mass`,
    /// `force.drive.function.constant`; see `docs/model-format.md`).
    pub key: String,
    /// The values, in order.
    pub values: Vec<String>,
}

impl Param {
    /// The key with the values `values` (each written as `--set` takes it:
    /// `1.5`, `"hht"`, `hht`, `[0.0, 1.0]`).
    ///
    /// # Errors
    /// [`SweepError::Spec`] for an empty key or no values.
    pub fn new<V: ToString>(
        key: &str,
        values: impl IntoIterator<Item = V>,
    ) -> Result<Self, SweepError> {
        let key = key.trim();
        let values: Vec<String> = values
            .into_iter()
            .map(|v| v.to_string().trim().to_string())
            .collect();
        let bad = |why: &str| SweepError::Spec {
            spec: format!("{key}={}", values.join(",")),
            why: why.to_string(),
        };
        if key.is_empty() || key.split('.').any(|k| k.trim().is_empty()) {
            return Err(bad(
                "the key is not a dotted path of keys (e.g. body.upper.mass)",
            ));
        }
        if values.is_empty() || values.iter().any(String::is_empty) {
            return Err(bad(
                "every value must be given (KEY=V1,V2,… or KEY=START:STOP:COUNT)",
            ));
        }
        Ok(Self {
            key: key.to_string(),
            values,
        })
    }

    /// Parses `KEY=V1,V2,…` or `KEY=START:STOP:COUNT` (`COUNT` ≥ 2 values
    /// from `START` to `STOP`, both included, evenly spaced); lists and
    /// ranges mix: `KEY=0,1:2:3` is `0, 1, 1.5, 2`.
    ///
    /// # Errors
    /// [`SweepError::Spec`] for a spec without `=`, an empty value or a
    /// malformed range.
    pub fn parse(spec: &str) -> Result<Self, SweepError> {
        let bad = |why: String| SweepError::Spec {
            spec: spec.to_string(),
            why,
        };
        let (key, list) = spec
            .split_once('=')
            .ok_or_else(|| bad("expected KEY=V1,V2,… or KEY=START:STOP:COUNT".into()))?;
        let mut values = Vec::new();
        for item in split_top_level(list) {
            let item = item.trim();
            if is_range(item) {
                values.extend(range(item).map_err(bad)?);
            } else {
                values.push(item.to_string());
            }
        }
        Self::new(key, values).map_err(|e| match e {
            SweepError::Spec { why, .. } => bad(why),
            other => other,
        })
    }
}

/// Splits at the commas outside brackets, braces and quotes.
fn split_top_level(list: &str) -> Vec<&str> {
    let (mut items, mut depth, mut quote, mut start) = (Vec::new(), 0i32, None, 0);
    for (i, c) in list.char_indices() {
        match (quote, c) {
            (Some(q), c) if c == q => quote = None,
            (Some(_), _) => {}
            (None, '"' | '\'') => quote = Some(c),
            (None, '[' | '{') => depth += 1,
            (None, ']' | '}') => depth -= 1,
            (None, ',') if depth == 0 => {
                items.push(&list[start..i]);
                start = i + 1;
            }
            _ => {}
        }
    }
    items.push(&list[start..]);
    items
}

/// Whether a value is written as a range (`a:b:n`): a colon outside a
/// string, an array or a table.
fn is_range(item: &str) -> bool {
    !item.starts_with(['"', '\'', '[', '{']) && item.contains(':')
}

/// The values of `start:stop:count`.
fn range(item: &str) -> Result<Vec<String>, String> {
    let malformed = |why: &str| {
        format!(
            "'{item}' is not a range START:STOP:COUNT (e.g. 1:2:5 is 1, 1.25, 1.5, 1.75, 2): {why}"
        )
    };
    let parts: Vec<&str> = item.split(':').map(str::trim).collect();
    let [start, stop, count] = parts[..] else {
        return Err(malformed("it needs three parts"));
    };
    let number = |s: &str| s.parse::<f64>().ok().filter(|x| x.is_finite());
    let (Some(a), Some(b)) = (number(start), number(stop)) else {
        return Err(malformed("START and STOP must be numbers"));
    };
    let n = count
        .parse::<usize>()
        .ok()
        .filter(|&n| n >= 2)
        .ok_or_else(|| malformed("COUNT must be a whole number ≥ 2"))?;
    if n > super::MAX_RUNS {
        // Before a value is made: 10¹⁵ values do not fit in memory.
        return Err(malformed(&format!(
            "COUNT {n} is more than the {} runs a sweep takes (give COUNT {} or less)",
            super::MAX_RUNS,
            super::MAX_RUNS
        )));
    }
    // Integers stay integers (`output.every=10:100:10`) when both ends are
    // written as integers and the value is one, exactly (|x| ≤ 2⁵³).
    let integers = start.parse::<i64>().is_ok() && stop.parse::<i64>().is_ok();
    Ok((0..n)
        .map(|k| {
            // a (1 − s) + b s: no overflow between finite ends.
            let s = k as f64 / (n - 1) as f64;
            let x = if k + 1 == n { b } else { a * (1.0 - s) + b * s };
            if integers && x.fract() == 0.0 && x.abs() <= 9_007_199_254_740_992.0 {
                format!("{x}")
            } else {
                // A TOML float: `1.5`, `1.0`, `1e19`.
                format!("{x:?}")
            }
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lists_and_ranges() {
        let p = Param::parse("body.upper.mass=1:2:5").expect("a range");
        assert_eq!(p.key, "body.upper.mass");
        assert_eq!(p.values, ["1", "1.25", "1.5", "1.75", "2"]);
        let p = Param::parse("simulation.h=1e-3, 5e-4").expect("a list");
        assert_eq!(p.values, ["1e-3", "5e-4"]);
        let p = Param::parse("joint.j.points=[[0, 1], [2, 3]],[[1, 1], [2, 2]]").expect("arrays");
        assert_eq!(p.values, ["[[0, 1], [2, 3]]", "[[1, 1], [2, 2]]"]);
        let p = Param::parse("x=0,1:2:3").expect("mixed");
        assert_eq!(p.values, ["0", "1", "1.5", "2"]);
        let p = Param::parse("x=0.5:1.5:3").expect("floats");
        assert_eq!(p.values, ["0.5", "1.0", "1.5"]);
        let p = Param::parse("x=1e19:2e19:3").expect("large");
        assert_eq!(p.values, ["1e19", "1.5e19", "2e19"]);
        let p = Param::parse("x=1e308:-1e308:3").expect("extreme");
        assert_eq!(p.values, ["1e308", "0.0", "-1e308"]);
        let p = Param::parse("x=10:30:3").expect("integers");
        assert_eq!(p.values, ["10", "20", "30"]);
        let p = Param::parse("simulation.integrator=\"hht\",newmark").expect("strings");
        assert_eq!(p.values, ["\"hht\"", "newmark"]);
    }

    #[test]
    fn malformed_specs_say_why() {
        for (spec, why) in [
            ("body.upper.mass", "expected KEY=V1"),
            ("body.upper.mass=1:2", "three parts"),
            ("body.upper.mass=1:x:3", "must be numbers"),
            ("body.upper.mass=1:2:1", "COUNT must be a whole number ≥ 2"),
            ("body.upper.mass=1,,2", "every value must be given"),
            ("body..mass=1", "not a dotted path"),
            ("=1", "not a dotted path"),
        ] {
            let e = Param::parse(spec).expect_err(spec).to_string();
            assert!(e.contains(why), "{spec}: {e}");
        }
    }
}
