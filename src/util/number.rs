//! Numbers as messages show them: a value read from a damaged or hostile
//! file can be 1e300, which `{}` prints as 301 digits.

/// `v` as a message shows it: plain where that is short (`0.5`, `-1`,
/// `2400`), in exponent form past six digits either side of the point
/// (`1e300`, `5e-324`), `NaN`/`inf` as they are.
pub fn shown(v: f64) -> String {
    let a = v.abs();
    if v.is_finite() && a != 0.0 && !(1e-4..1e6).contains(&a) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

#[cfg(test)]
mod tests {
    use super::shown;

    #[test]
    fn extremes_are_short_and_ordinary_values_plain() {
        assert_eq!(shown(1e300), "1e300");
        assert_eq!(shown(-1e308), "-1e308");
        assert_eq!(shown(5e-324), "5e-324");
        assert_eq!(shown(1.5e-7), "1.5e-7");
        assert_eq!(shown(0.5), "0.5");
        assert_eq!(shown(-1.0), "-1");
        assert_eq!(shown(2400.0), "2400");
        assert_eq!(shown(0.0), "0");
        assert_eq!(shown(f64::INFINITY), "inf");
        assert_eq!(shown(f64::NAN), "NaN");
    }
}
