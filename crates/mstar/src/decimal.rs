//! Numbers as the output files write them: shortest round-trip decimals,
//! plain for `1e-4 ≤ |x| < 1e15` (and 0), exponent notation otherwise, in
//! the layout of Rust's `{}` and `{:e}`. The digits are `zmij`'s
//! (Schubfach), a few times faster than the standard library's formatting,
//! which took a third of a run that writes every tenth step
//! (docs/performance.md, "Writing numbers"). Both give the fewest digits
//! that read back as the same number; where two such are equally near it
//! (a tie, rare), the two may write different last digits.

use std::fmt::Write as _;

/// The most significant digits of an `f64` in shortest form (17), with room.
const MAX_DIGITS: usize = 24;

/// Appends `x` in the output files' form (see the module documentation):
/// the text of `write!(out, "{x}")` in the plain range and
/// `write!(out, "{x:e}")` outside it but for the last digit of a tie; `0`
/// for both zeros.
pub(crate) fn push_number(out: &mut String, x: f64) {
    if x == 0.0 {
        out.push('0');
        return;
    }
    if !x.is_finite() {
        let _ = write!(out, "{x}");
        return;
    }
    let plain = (1e-4..1e15).contains(&x.abs());
    let mut buffer = zmij::Buffer::new();
    let text = buffer.format_finite(x);
    // zmij writes plain decimals for a first digit's exponent in −5..=15
    // (`1.0` for an integer, where `{}` writes `1`) and `1.5e+20`, `5e-324`
    // outside (where `{:e}` writes no `+`): most numbers need no more than
    // that; those of 1e-5 ≤ |x| < 1e-4 and 1e15 ≤ |x| < 1e16 are rewritten.
    match (plain, text.split_once('e')) {
        (true, None) => out.push_str(text.strip_suffix(".0").unwrap_or(text)),
        (false, Some((mantissa, power))) => {
            out.push_str(mantissa);
            out.push('e');
            out.push_str(power.trim_start_matches('+'));
        }
        _ => {
            let digits = Digits::parse(text);
            if x.is_sign_negative() {
                out.push('-');
            }
            if plain {
                digits.push_plain(out);
            } else {
                digits.push_exponent(out);
            }
        }
    }
}

/// A nonzero finite number's significant digits `d₀d₁…` (no leading or
/// trailing zeros) and the decimal exponent of `d₀`: `|x| = d₀.d₁… × 10^e`.
struct Digits {
    digits: [u8; MAX_DIGITS],
    len: usize,
    exponent: i32,
}

impl Digits {
    /// From a shortest decimal as `zmij` writes it: an optional sign, digits
    /// with an optional point, an optional `e±N`.
    fn parse(text: &str) -> Self {
        let text = text.trim_start_matches('-');
        let (mantissa, power) = match text.split_once(['e', 'E']) {
            Some((m, p)) => (m, p.trim_start_matches('+').parse::<i32>().unwrap_or(0)),
            None => (text, 0),
        };
        let integer_len = mantissa.find('.').unwrap_or(mantissa.len());
        let mut d = Self {
            digits: [0; MAX_DIGITS],
            len: 0,
            // The first digit's exponent before leading zeros are dropped.
            exponent: i32::try_from(integer_len).unwrap_or(0) - 1 + power,
        };
        for b in mantissa.bytes().filter(u8::is_ascii_digit) {
            if d.len == 0 && b == b'0' {
                d.exponent -= 1;
            } else if d.len < MAX_DIGITS {
                d.digits[d.len] = b;
                d.len += 1;
            }
        }
        while d.len > 1 && d.digits[d.len - 1] == b'0' {
            d.len -= 1;
        }
        d
    }

    fn significant(&self) -> &str {
        // ASCII digits only.
        std::str::from_utf8(&self.digits[..self.len]).unwrap_or("0")
    }

    /// `ddd.ddd`, `ddd000` or `0.000ddd` (no exponent, no trailing `.0`).
    fn push_plain(&self, out: &mut String) {
        let s = self.significant();
        if self.exponent < 0 {
            out.push_str("0.");
            for _ in 0..(-self.exponent - 1) {
                out.push('0');
            }
            out.push_str(s);
            return;
        }
        let integer = usize::try_from(self.exponent).unwrap_or(0) + 1;
        if s.len() <= integer {
            out.push_str(s);
            for _ in s.len()..integer {
                out.push('0');
            }
        } else {
            out.push_str(&s[..integer]);
            out.push('.');
            out.push_str(&s[integer..]);
        }
    }

    /// `d.ddde-N` / `de N` as `{:e}` writes it (no `+`, no leading zeros).
    fn push_exponent(&self, out: &mut String) {
        let s = self.significant();
        out.push_str(&s[..1]);
        if s.len() > 1 {
            out.push('.');
            out.push_str(&s[1..]);
        }
        let _ = write!(out, "e{}", self.exponent);
    }
}

#[cfg(test)]
mod tests {
    use super::push_number;
    use proptest::prelude::*;

    /// The standard library's text, the form the files had before: the
    /// independent reference.
    fn reference(x: f64) -> String {
        let x = if x == 0.0 { 0.0 } else { x };
        if x == 0.0 || (1e-4..1e15).contains(&x.abs()) || !x.is_finite() {
            format!("{x}")
        } else {
            format!("{x:e}")
        }
    }

    fn ours(x: f64) -> String {
        let mut s = String::new();
        push_number(&mut s, x);
        s
    }

    /// The standard library's text, or, in a tie, text of the same layout
    /// and length that reads back as the same number.
    fn check(x: f64) -> Result<(), String> {
        let (a, b) = (ours(x), reference(x));
        if a == b {
            return Ok(());
        }
        let same_value = a.parse::<f64>().ok() == b.parse::<f64>().ok() && !x.is_nan();
        let (last_a, last_b) = (a.find('e'), b.find('e'));
        let tie = same_value
            && a.len() == b.len()
            && last_a == last_b
            && a[last_a.unwrap_or(a.len())..] == b[last_b.unwrap_or(b.len())..];
        if tie {
            Ok(())
        } else {
            Err(format!("{x:e}: {a} against {b}"))
        }
    }

    #[test]
    fn edges_read_back_as_the_standard_library_writes_them() {
        let mut cases = vec![
            0.0,
            -0.0,
            1.0,
            -1.0,
            0.1,
            0.5,
            1.5,
            100.0,
            123_456.789,
            1e-4,
            9.999_999_999_999_999e-5,
            1e15,
            999_999_999_999_999.9,
            1e14,
            f64::MIN_POSITIVE,
            5e-324,
            f64::MAX,
            f64::MIN,
            f64::EPSILON,
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            2.9802322387695312e-8,
            6.62607015e-34,
            544_431_068_535_091.6,
        ];
        for k in -330..=310 {
            let p = 10f64.powi(k);
            cases.extend([p, -p, p.next_up(), p.next_down(), 1.5 * p, 0.999 * p]);
        }
        for x in cases {
            assert_eq!(check(x), Ok(()));
        }
        // A tie: 2⁻²⁵ = 2.98023223876953125e-8 exactly, between two
        // 17-digit decimals.
        assert_eq!(ours(2f64.powi(-25)), "2.9802322387695312e-8");
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(20_000))]

        #[test]
        fn any_bit_pattern_is_written_as_the_standard_library_does(bits in any::<u64>()) {
            let x = f64::from_bits(bits);
            prop_assert_eq!(check(x), Ok(()));
        }

        #[test]
        fn the_plain_range_is_written_as_the_standard_library_does(m in 1.0f64..10.0, k in -5i32..16) {
            let x = m * 10f64.powi(k);
            prop_assert_eq!(check(x), Ok(()));
            prop_assert_eq!(check(-x), Ok(()));
        }
    }
}
