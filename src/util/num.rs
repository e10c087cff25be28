//! Numbers in messages: [`short`] prints a float the way a person would write it.

/// `v` as written in a message: plain decimal for everyday magnitudes ("0.0003", "42"),
/// scientific notation for very large or small ones ("1e300", "2.5e-9"), where Rust's
/// `{}` would print every digit of `1e300`.
pub fn short(v: f64) -> String {
    let a = v.abs();
    if v.is_finite() && a != 0.0 && !(1e-4..1e9).contains(&a) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn short_forms() {
        assert_eq!(short(1e300), "1e300");
        assert_eq!(short(-2.5e-9), "-2.5e-9");
        assert_eq!(short(0.0003), "0.0003");
        assert_eq!(short(42.0), "42");
        assert_eq!(short(0.0), "0");
        assert_eq!(short(f64::NAN), "NaN");
        assert_eq!(short(f64::INFINITY), "inf");
    }
}
