//! The fast path of the row parser: plain decimal numbers read straight from the bytes.
//!
//! [`fast_row`] reads one whole line of `width` numbers separated by commas (spaces and tabs
//! around them allowed, CRLF or LF or end of text after the last) and gives up (`None`) on
//! anything else, leaving the line to the general parser, which accepts the same and more and
//! words the errors. A number is taken here only when it can be rounded exactly as `str::parse`
//! would: at most 19 significant digits, mantissa at most 2^53 and a decimal exponent within
//! +-22, so that `m * 10^e` or `m / 10^-e` is one correctly rounded IEEE operation on exact
//! operands (Clinger's fast path). The result is therefore bit-identical to `str::parse::<f64>`.

/// The powers of ten that `f64` holds exactly.
const POW10: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16, 1e17, 1e18,
    1e19, 1e20, 1e21, 1e22,
];
/// Largest mantissa that `f64` holds exactly.
const MAX_EXACT_MANTISSA: u64 = 1 << 53;
/// Most digits that fit a `u64` mantissa whatever they are.
const MAX_DIGITS: usize = 19;

/// Reads decimal digits from `i`, accumulating into `mantissa`; returns the index after them.
#[inline]
fn digits(b: &[u8], mut i: usize, mantissa: &mut u64) -> usize {
    while let Some(&c) = b.get(i) {
        let d = c.wrapping_sub(b'0');
        if d > 9 {
            break;
        }
        *mantissa = mantissa.wrapping_mul(10).wrapping_add(u64::from(d));
        i += 1;
    }
    i
}

/// Skips an optional sign at `*i`; true for `-`.
#[inline]
fn sign(b: &[u8], i: &mut usize) -> bool {
    match b.get(*i) {
        Some(b'-') => {
            *i += 1;
            true
        }
        Some(b'+') => {
            *i += 1;
            false
        }
        _ => false,
    }
}

/// Reads `[+-]digits[.digits][(e|E)[+-]digits]` at `i`; `None` when it is not of that form or
/// not exactly representable on the fast path. Returns the value and the index after it.
#[inline]
fn fast_number(b: &[u8], mut i: usize) -> Option<(f64, usize)> {
    let negative = sign(b, &mut i);
    let mut mantissa = 0_u64;
    let int_start = i;
    i = digits(b, i, &mut mantissa);
    let mut n_digits = i - int_start;
    let mut exponent = 0_i64;
    if b.get(i) == Some(&b'.') {
        let frac_start = i + 1;
        i = digits(b, frac_start, &mut mantissa);
        n_digits += i - frac_start;
        exponent = -((i - frac_start) as i64);
    }
    if n_digits == 0 || n_digits > MAX_DIGITS {
        return None;
    }
    if matches!(b.get(i), Some(b'e' | b'E')) {
        i += 1;
        let negative_exp = sign(b, &mut i);
        let exp_start = i;
        let mut e = 0_u64;
        i = digits(b, i, &mut e);
        if i == exp_start || i - exp_start > 4 {
            return None;
        }
        exponent += if negative_exp { -(e as i64) } else { e as i64 };
    }
    if mantissa > MAX_EXACT_MANTISSA {
        return None;
    }
    let scale = *POW10.get(exponent.unsigned_abs() as usize)?;
    let magnitude = if exponent >= 0 {
        mantissa as f64 * scale
    } else {
        mantissa as f64 / scale
    };
    Some((if negative { -magnitude } else { magnitude }, i))
}

/// Index of the first byte at or after `i` that is not a space or tab.
#[inline]
fn skip_blanks(b: &[u8], mut i: usize) -> usize {
    while matches!(b.get(i), Some(b' ' | b'\t')) {
        i += 1;
    }
    i
}

/// Reads one line starting at `start` and pushes one value onto each of `cols`; returns the index
/// after its line ending. `None`: not a plain line of `cols.len()` numbers. Values may already
/// have been pushed onto some columns then: the caller truncates them.
#[inline]
pub(super) fn fast_row(b: &[u8], start: usize, cols: &mut [Vec<f64>]) -> Option<usize> {
    let mut i = start;
    let last = cols.len().checked_sub(1)?;
    for (k, col) in cols.iter_mut().enumerate() {
        let (value, end) = fast_number(b, skip_blanks(b, i))?;
        i = skip_blanks(b, end);
        if k < last {
            if b.get(i) != Some(&b',') {
                return None;
            }
            i += 1;
        }
        col.push(value);
    }
    if b.get(i) == Some(&b'\r') {
        i += 1;
    }
    match b.get(i) {
        None => Some(i),
        Some(b'\n') => Some(i + 1),
        Some(_) => None,
    }
}

#[cfg(test)]
mod tests {
    use super::fast_number;

    /// Every number the fast path takes equals `str::parse` to the bit.
    #[test]
    fn fast_path_is_bit_identical_to_std() {
        let mut rng = crate::rng::Rng::new(7);
        let mut taken = 0;
        for _ in 0..200_000 {
            let x = (rng.normal() * 10f64.powi((rng.uniform() * 30.0) as i32 - 15)).to_string();
            let e = format!("{:e}", rng.normal() * 1e-3);
            let fixed = format!("{:.*}", (rng.uniform() * 12.0) as usize, rng.normal() * 1000.0);
            for text in [x, e, fixed] {
                if let Some((v, end)) = fast_number(text.as_bytes(), 0) {
                    assert_eq!(end, text.len(), "{text}");
                    assert_eq!(v.to_bits(), text.parse::<f64>().unwrap().to_bits(), "{text}");
                    taken += 1;
                }
            }
        }
        assert!(taken > 300_000, "fast path took only {taken} of 600000");
    }

    /// Random strings over the number alphabet, and numbers at the edges of the fast path (19
    /// digits, 2^53, 10^+-22, leading zeros, lone signs and dots): whatever the fast path takes
    /// is a whole number token that `str::parse` reads to the same bits.
    #[test]
    fn fast_path_matches_std_on_adversarial_strings() {
        const ALPHABET: &[u8] = b"0123456789000999..eE+-";
        let mut rng = crate::rng::Rng::new(11);
        let mut pick = |n: usize| (rng.next_u64() % n as u64) as usize;
        let mut texts: Vec<String> = Vec::new();
        for _ in 0..300_000 {
            let len = 1 + pick(24);
            texts.push(
                (0..len)
                    .map(|_| char::from(ALPHABET[pick(ALPHABET.len())]))
                    .collect(),
            );
        }
        for digits in 15..=21 {
            for lead in ["", "0.", "-0.000", "+", "9", "."] {
                for exp in ["", "e-22", "e22", "e-23", "e+23", "E-0", "e0000"] {
                    let nines = "9".repeat(digits);
                    let ones = format!("1{}", "0".repeat(digits - 1));
                    for body in [
                        nines,
                        ones,
                        "9007199254740992".to_owned(),
                        "9007199254740993".to_owned(),
                    ] {
                        texts.push(format!("{lead}{body}{exp}"));
                    }
                }
            }
        }
        let mut taken = 0;
        for text in &texts {
            // A separator after the text, as in a row: the fast path must stop there.
            let row = format!("{text},");
            let Some((value, end)) = fast_number(row.as_bytes(), 0) else {
                continue;
            };
            assert!(end <= text.len(), "{text}: read past the cell");
            let token = &text[..end];
            let std_value: f64 = token
                .parse()
                .unwrap_or_else(|_| panic!("fast path took {token:?}"));
            assert_eq!(value.to_bits(), std_value.to_bits(), "{token}");
            taken += usize::from(end == text.len());
        }
        assert!(taken > 10_000, "fast path took only {taken} whole strings");
    }

    #[test]
    fn fast_path_refuses_what_it_cannot_round_exactly() {
        for text in [
            "",
            "-",
            ".",
            "1e",
            "1e+",
            "12345678901234567890",
            "9007199254740993",
            "1e23",
            "nan",
            "inf",
        ] {
            assert_eq!(fast_number(text.as_bytes(), 0), None, "{text}");
        }
        assert_eq!(fast_number(b"+1.5e-3,", 0), Some((1.5e-3, 7)));
        assert_eq!(fast_number(b"-8.5e-05", 0), Some((-8.5e-05, 8)));
        assert_eq!(fast_number(b"2.", 0), Some((2.0, 2)));
        assert_eq!(fast_number(b".25", 0), Some((0.25, 3)));
    }
}
