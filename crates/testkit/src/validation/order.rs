//! Rows for a second-order method: the errors at `h` and `h/2` and the
//! order they show.

use super::Row;

/// The order row of errors `coarse` (at `h`) and `fine` (at `h/2`): the
/// observed order `log₂(coarse/fine)` must be 2 within `0.2` (a first-order
/// error, or a wrong reference that the error stalls on, shows 1 or 0).
pub(super) fn order_row(
    model: &str,
    quantity: &str,
    reference: &str,
    h: f64,
    coarse: f64,
    fine: f64,
) -> Row {
    let order = (coarse / fine).log2();
    Row {
        model: model.to_string(),
        quantity: format!("order of {quantity} (h = {h:e} → {:e})", h / 2.0),
        reference: format!("2 ({reference})"),
        ours: format!("{order:.3} ({coarse:.2e} → {fine:.2e})"),
        error: (order - 2.0).abs(),
        tolerance: 0.2,
    }
}

/// Like [`order_row`] for a quantity that may converge faster than the
/// method's order (a multiplier of a prescribed motion): the observed order
/// must be at least 2 − 0.2.
pub(super) fn order_at_least_row(
    model: &str,
    quantity: &str,
    reference: &str,
    h: f64,
    coarse: f64,
    fine: f64,
) -> Row {
    let mut row = order_row(model, quantity, reference, h, coarse, fine);
    let order = (coarse / fine).log2();
    row.reference = format!("≥ 2 ({reference})");
    row.error = if order.is_nan() {
        f64::NAN
    } else {
        (2.0 - order).max(0.0)
    };
    row
}
