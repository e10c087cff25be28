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

/// The longest time budget any minutes input may give: a year (525,960 minutes). Beyond
/// it a budget is a typo, and at 1e18 minutes it no longer fits a `Duration`.
pub const MAX_MINUTES: f64 = 525_960.0;

/// Checks a time budget in minutes: finite, positive and at most [`MAX_MINUTES`]; `Err`
/// says so, with `m` as [`short`] writes it.
pub fn check_minutes(m: f64) -> Result<(), String> {
    if m.is_finite() && m > 0.0 && m <= MAX_MINUTES {
        Ok(())
    } else {
        Err(format!(
            "{} must be a positive number of minutes, at most {MAX_MINUTES} (a year)",
            short(m)
        ))
    }
}

/// A config value's range check: `Ok` when `v` is finite and in `[lo, hi]`, else the
/// field and "V is outside [LO, HI]UNIT" with `v` as [`short`] writes it (`unit` starts
/// with its space, or is empty). The `(field, message)` form is what the environment's
/// config sections return from `validate`.
pub fn within(
    field: &'static str,
    v: f64,
    lo: f64,
    hi: f64,
    unit: &str,
) -> Result<(), (&'static str, String)> {
    if v.is_finite() && (lo..=hi).contains(&v) {
        Ok(())
    } else {
        Err((field, format!("{} is outside [{lo}, {hi}]{unit}", short(v))))
    }
}

/// [`within`] for the half-open range `(lo, hi]`: `Ok` when `lo < v <= hi` (so never for
/// NaN or an infinite `v`), else the field and "V is outside (LO, HI]UNIT".
pub fn within_above(
    field: &'static str,
    v: f64,
    lo: f64,
    hi: f64,
    unit: &str,
) -> Result<(), (&'static str, String)> {
    if v > lo && v <= hi {
        Ok(())
    } else {
        Err((field, format!("{} is outside ({lo}, {hi}]{unit}", short(v))))
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

    #[test]
    fn within_accepts_the_closed_range_and_names_the_field() {
        assert!(within("a", 0.0, 0.0, 1.0, "").is_ok());
        assert!(within("a", 1.0, 0.0, 1.0, " m").is_ok());
        assert_eq!(
            within("a.b", 1e300, 0.0, 0.05, " m"),
            Err(("a.b", "1e300 is outside [0, 0.05] m".to_string()))
        );
        assert_eq!(
            within("a", f64::NAN, 0.0, 1.0, "").unwrap_err().1,
            "NaN is outside [0, 1]"
        );
        assert!(within("a", -0.1, 0.0, 1.0, "").is_err());
    }

    #[test]
    fn range_checks_name_the_field_and_the_range() {
        assert!(within("a", 1.0, 0.0, 1.0, "").is_ok());
        assert_eq!(
            within("a", 0.25 + 1.0, 0.0, 1.0, " m"),
            Err(("a", "1.25 is outside [0, 1] m".to_string()))
        );
        assert!(within_above("b", 5.0, 0.0, 5.0, "").is_ok());
        for v in [0.0, -1.0, 5.5, f64::NAN, f64::INFINITY] {
            let e = within_above("b", v, 0.0, 5.0, " s").unwrap_err();
            assert_eq!(e, ("b", format!("{} is outside (0, 5] s", short(v))));
        }
    }
}
