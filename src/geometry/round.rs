//! f64 values rounded to f32 in a chosen direction, for boxes that must hold what they bound.

/// The largest f32 not above `v`.
pub(crate) fn round_down(v: f64) -> f32 {
    let r = v as f32;
    if f64::from(r) > v {
        r.next_down()
    } else {
        r
    }
}

/// The smallest f32 not below `v`.
pub(crate) fn round_up(v: f64) -> f32 {
    let r = v as f32;
    if f64::from(r) < v {
        r.next_up()
    } else {
        r
    }
}
