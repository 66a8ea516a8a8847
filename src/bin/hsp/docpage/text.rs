//! Text for the page: numbers printed short and HTML escaping.

/// A number printed short: four significant digits, no trailing zeros, scientific notation
/// outside 1e-3 to 1e5 (`23153293.32444247` -> `2.315e7`, `3.9062499999999994e-5` -> `3.906e-5`).
pub fn short(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let a = v.abs();
    if (1e-3..1e5).contains(&a) {
        let decimals = (3 - a.log10().floor() as i32).max(0) as usize;
        let s = format!("{v:.decimals$}");
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        }
    } else {
        let s = format!("{v:.3e}");
        let (mantissa, exponent) = s.split_once('e').unwrap_or((&s, "0"));
        let mantissa = mantissa.trim_end_matches('0').trim_end_matches('.');
        format!("{mantissa}e{exponent}")
    }
}

/// A number from the XML printed short (non-numbers as they are).
pub fn short_text(s: &str) -> String {
    s.parse::<f64>()
        .map(short)
        .unwrap_or_else(|_| s.to_string())
}

/// Text made safe for HTML.
pub fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_are_printed_short() {
        assert_eq!(short(23153293.32444247), "2.315e7");
        assert_eq!(short(3.9062499999999994e-5), "3.906e-5");
        assert_eq!(short(0.0025), "0.0025");
        assert_eq!(short(2.0), "2");
        assert_eq!(short(-150.0), "-150");
        assert_eq!(short(57.29577951308232), "57.3");
        assert_eq!(short(1e-6), "1e-6");
        assert_eq!(short(0.0), "0");
    }
}
