//! Nastran field values: integers, reals in every form Nastran writes them (`7.0`, `7.`, `.7E1`,
//! `0.7+1`, `70.-1`, `7.D0`), character strings and blanks.

/// The value of one field, as Nastran classifies it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Value<'a> {
    Blank,
    Int(i64),
    Real(f64),
    Text(&'a str),
}

/// Classifies a field (already trimmed and upper-cased): a blank, an integer (digits with an
/// optional sign), a real (a decimal point, an optional exponent written `E±n`, `D±n` or just
/// `±n`), otherwise text. A field that is neither number nor name (`1.2.3`, `+-5`) is text too;
/// the accessor that wanted a number says what it found.
pub fn classify(s: &str) -> Value<'_> {
    if s.is_empty() {
        return Value::Blank;
    }
    if let Some(i) = parse_int(s) {
        return Value::Int(i);
    }
    if let Some(r) = parse_real(s) {
        return Value::Real(r);
    }
    Value::Text(s)
}

/// An integer field: an optional sign and digits only.
pub fn parse_int(s: &str) -> Option<i64> {
    let digits = s.strip_prefix(['+', '-']).unwrap_or(s);
    if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    s.parse().ok()
}

/// A real field in Nastran's forms: the mantissa must hold a decimal point; the exponent may be
/// introduced by E or D or by its sign alone (`1.145-7` = 1.145e-7).
pub fn parse_real(s: &str) -> Option<f64> {
    let bytes = s.as_bytes();
    // where the exponent starts: an E or D, or a sign after the first character
    let split = bytes
        .iter()
        .enumerate()
        .skip(1)
        .find(|(_, &b)| matches!(b, b'E' | b'D' | b'+' | b'-'))
        .map(|(i, _)| i);
    let (mantissa, exponent) = match split {
        Some(i) => (&s[..i], Some(&s[i..])),
        None => (s, None),
    };
    let unsigned = mantissa.strip_prefix(['+', '-']).unwrap_or(mantissa);
    if !unsigned.contains('.')
        || unsigned == "."
        || !unsigned.bytes().all(|b| b.is_ascii_digit() || b == b'.')
        || unsigned.matches('.').count() != 1
    {
        return None;
    }
    let e: i32 = match exponent {
        None => 0,
        Some(x) => {
            let x = x.strip_prefix(['E', 'D']).unwrap_or(x);
            parse_int(x)?.try_into().ok()?
        }
    };
    // through the standard parser, correctly rounded (9.83-6 is the double nearest 9.83e-6)
    let v: f64 = format!("{mantissa}e{e}").parse().ok()?;
    v.is_finite().then_some(v)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every real form of the MSC Quick Reference Guide's "Format of Bulk Data Entries" example
    /// (7.0 written eight ways), NASTRAN-95's exponent without E, D exponents, and what is not a
    /// number.
    #[test]
    fn nastran_number_forms() {
        for s in [
            "7.0", "7.", ".7E1", "0.7+1", "70.-1", ".70+1", "7.E+0", "700.E-2", "7.D0", "+7.",
        ] {
            assert_eq!(classify(s), Value::Real(7.0), "{s}");
        }
        assert_eq!(classify("1.145-7"), Value::Real(1.145e-7));
        assert_eq!(classify("-.26795"), Value::Real(-0.26795));
        assert_eq!(classify("1.3+4"), Value::Real(1.3e4));
        assert_eq!(classify("-12"), Value::Int(-12));
        assert_eq!(classify("123456"), Value::Int(123456));
        assert_eq!(classify(""), Value::Blank);
        for s in ["THRU", "1.2.3", "+-5", "1E5", ".", "ENDT", "1.0E", "1.0+"] {
            assert!(matches!(classify(s), Value::Text(_)), "{s}");
        }
    }
}
