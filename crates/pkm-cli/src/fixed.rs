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

/// Two ASCII digits of every number 0..100.
const PAIRS: [[u8; 2]; 100] = {
    let mut t = [[0u8; 2]; 100];
    let mut i = 0;
    while i < 100 {
        t[i] = [b'0' + (i / 10) as u8, b'0' + (i % 10) as u8];
        i += 1;
    }
    t
};

/// Appends `v` with six decimals, exactly as `{:.6}` formats it.
///
/// The fast path needs neither `floor` nor `round` (libm calls on the baseline x86-64
/// target): `s = |v| 1e6 < 1e13` truncates exactly to an integer `n`, `s - n` is then
/// exact, and away from a tie `round(s)` is `n` or `n + 1` by that fraction.
#[inline]
pub fn push_fixed6(buf: &mut Vec<u8>, v: f64) {
    let a = v.abs();
    if a < 1e7 {
        let s = a * 1e6;
        let n = s as u64;
        let frac = s - n as f64;
        if (frac - 0.5).abs() > 2e-3 {
            let n = n + u64::from(frac > 0.5);
            if v.is_sign_negative() {
                buf.push(b'-');
            }
            push_u64(buf, n / 1_000_000);
            let f = (n % 1_000_000) as usize;
            let (hi, lo) = (f / 10_000, f % 10_000);
            buf.push(b'.');
            buf.extend_from_slice(&PAIRS[hi]);
            buf.extend_from_slice(&PAIRS[lo / 100]);
            buf.extend_from_slice(&PAIRS[lo % 100]);
            return;
        }
    }
    use std::io::Write as _;
    let _ = write!(buf, "{v:.6}");
}

/// Appends the decimal digits of `n`.
#[inline]
pub fn push_u64(buf: &mut Vec<u8>, mut n: u64) {
    if n < 10 {
        buf.push(b'0' + n as u8);
        return;
    }
    let mut digits = [0u8; 20];
    let mut k = digits.len();
    while n >= 100 {
        k -= 2;
        digits[k..k + 2].copy_from_slice(&PAIRS[(n % 100) as usize]);
        n /= 100;
    }
    if n >= 10 {
        k -= 2;
        digits[k..k + 2].copy_from_slice(&PAIRS[n as usize]);
    } else {
        k -= 1;
        digits[k] = b'0' + n as u8;
    }
    buf.extend_from_slice(&digits[k..]);
}

#[cfg(test)]
mod tests {
    use super::*;

    fn same(v: f64) {
        let mut b = Vec::new();
        push_fixed6(&mut b, v);
        assert_eq!(
            String::from_utf8(b).unwrap(),
            format!("{v:.6}"),
            "{v:e} ({:#x})",
            v.to_bits()
        );
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
        for n in [
            0u64,
            7,
            10,
            99,
            100,
            101,
            999,
            1000,
            12_345,
            1_000_000,
            u64::MAX,
            u64::MAX / 10,
        ] {
            let mut b = Vec::new();
            push_u64(&mut b, n);
            assert_eq!(String::from_utf8(b).unwrap(), n.to_string());
        }
    }
}
