//! Fast fixed-point formatting of the CSV outputs: `push_fixed6(buf, v)` appends exactly
//! what `format!("{v:.6}")` gives (std's correctly rounded decimal), about ten times
//! faster. Series of millions of rows (`pkm motion`'s actuators.csv: 26 numbers per
//! sample; `pkm workspace`'s points.csv) spent most of their time in std's exact
//! formatting.
//!
//! The fast path scales `|v| < 1e7` by 1e6 and rounds to an integer. The product's
//! rounding error is below 1.2e-3 of the last digit there, so the integer is the
//! correctly rounded one unless the scaled value lies within 2e-3 of a tie (`.5`);
//! those values, larger ones and non-finite ones take std's path.

/// Appends `v` with six decimals, exactly as `{:.6}` formats it.
#[inline]
pub fn push_fixed6(buf: &mut String, v: f64) {
    let a = v.abs();
    if a < 1e7 {
        let s = a * 1e6;
        let frac = s - s.floor();
        if (frac - 0.5).abs() > 2e-3 {
            let n = s.round() as u64;
            if v.is_sign_negative() {
                buf.push('-');
            }
            push_u64(buf, n / 1_000_000);
            buf.push('.');
            let f = n % 1_000_000;
            let mut digits = [b'0'; 6];
            let mut f = f;
            for d in digits.iter_mut().rev() {
                *d = b'0' + (f % 10) as u8;
                f /= 10;
            }
            // ASCII digits.
            buf.push_str(std::str::from_utf8(&digits).unwrap_or("000000"));
            return;
        }
    }
    use std::fmt::Write as _;
    let _ = write!(buf, "{v:.6}");
}

/// Appends the decimal digits of `n`.
#[inline]
pub fn push_u64(buf: &mut String, mut n: u64) {
    let mut digits = [0u8; 20];
    let mut k = digits.len();
    loop {
        k -= 1;
        digits[k] = b'0' + (n % 10) as u8;
        n /= 10;
        if n == 0 {
            break;
        }
    }
    buf.push_str(std::str::from_utf8(&digits[k..]).unwrap_or("0"));
}

#[cfg(test)]
mod tests {
    use super::*;

    fn same(v: f64) {
        let mut b = String::new();
        push_fixed6(&mut b, v);
        assert_eq!(b, format!("{v:.6}"), "{v:e} ({:#x})", v.to_bits());
    }

    #[test]
    fn equals_std_formatting() {
        for v in [
            0.0,
            -0.0,
            1.0,
            -1.0,
            0.5e-6,
            -0.5e-6,
            // Below a tie, but the scaled product rounds onto it.
            3.5e-6,
            2.4999999999999998e-06,
            1.5e-6,
            2.5e-6,
            0.0000004999,
            -1e-9,
            123.4565,
            123.4575,
            9_999_999.999_999_5,
            1e7,
            -1e7,
            1e300,
            f64::MIN_POSITIVE,
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ] {
            same(v);
        }
        // Random bit patterns and random values at every scale, ties included (every
        // multiple of 0.5e-6 with a short binary expansion).
        let mut x = 0x9e37_79b9_7f4a_7c15u64;
        for i in 0..500_000u64 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let u = (x >> 11) as f64 / (1u64 << 53) as f64;
            let scale = 10f64.powi((i % 16) as i32 - 8);
            same((u - 0.5) * scale);
            same(f64::from_bits(x));
            same((x % 20_000_000) as f64 * 0.5e-6 - 5.0);
            same((x % 4096) as f64 / 1024.0 - 2.0);
        }
    }

    #[test]
    fn integers() {
        for n in [0u64, 7, 10, 99, 1_000_000, u64::MAX] {
            let mut b = String::new();
            push_u64(&mut b, n);
            assert_eq!(b, n.to_string());
        }
    }
}
