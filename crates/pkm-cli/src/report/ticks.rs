//! Axis ticks at round values and their labels, shared by the report's plots.

/// Round tick values in `[lo, hi]`: multiples of 1, 2 or 5 times a power of ten, the
/// finest step giving at most `n + 1` of them.
pub fn linear_ticks(lo: f64, hi: f64, n: usize) -> Vec<f64> {
    let span = hi - lo;
    if !(span.is_finite() && span > 0.0) || n < 2 {
        return vec![lo];
    }
    let base = 10f64.powf((span / n as f64).log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * base)
        .find(|s| (span / s).floor() <= n as f64)
        .unwrap_or(10.0 * base);
    let first = (lo / step).ceil() as i64;
    let last = (hi / step).floor() as i64;
    (first..=last).map(|k| k as f64 * step).collect()
}

/// Tick positions on a log10 axis from `lo` to `hi` (log10 of the values): the log10
/// of round values: powers of ten over three decades or more (every second, third...
/// one over many), else
/// 1, 2, 5 or 1..9 times them, else (less than a step of those) round values on a
/// linear scale.
pub fn log_ticks(lo: f64, hi: f64) -> Vec<f64> {
    if !(lo.is_finite() && hi.is_finite() && hi > lo) {
        return vec![lo];
    }
    let within = |mantissas: &[f64], every: i32| -> Vec<f64> {
        let (k0, k1) = (lo.floor() as i32, hi.ceil() as i32);
        (k0..=k1)
            .filter(|k| k.rem_euclid(every) == 0)
            .flat_map(|k| mantissas.iter().map(move |m| m.log10() + k as f64))
            .filter(|v| (lo..=hi).contains(v))
            .collect()
    };
    let decades = (hi - lo).ceil() as i32;
    if decades >= 3 {
        let every = (1..=decades).find(|e| decades / e < 7).unwrap_or(decades);
        return within(&[1.0], every);
    }
    for mantissas in [
        &[1.0, 2.0, 5.0][..],
        &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0],
    ] {
        let t = within(mantissas, 1);
        if (3..=10).contains(&t.len()) {
            return t;
        }
    }
    let (a, b) = (10f64.powf(lo), 10f64.powf(hi));
    linear_ticks(a, b, 5).into_iter().map(f64::log10).collect()
}

/// A tick label for value `v` on an axis spanning `span`: the fewest decimals that
/// give `v` to a millionth of the span (ticks are round values: `1000`, `-500`, `0.25`,
/// `12.0015`), powers of ten beyond 10^6 and below 10^-3 in exponent form (`1e7`,
/// `2.5e-4`).
pub fn tick(v: f64, span: f64) -> String {
    let a = v.abs();
    let tol = 1e-6 * span.abs().max(f64::MIN_POSITIVE);
    if a <= tol {
        return "0".into();
    }
    if !(1e-3..1e6).contains(&a) {
        let e = format!("{v:.2e}");
        let (m, x) = e.split_once('e').unwrap_or((&e, "0"));
        let m = m.trim_end_matches('0').trim_end_matches('.');
        return format!("{m}e{x}");
    }
    let decimals = (0..9usize)
        .find(|&d| {
            let scale = 10f64.powi(d as i32);
            ((v * scale).round() / scale - v).abs() <= tol
        })
        .unwrap_or(9);
    format!("{v:.decimals$}")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn values(log: &[f64]) -> Vec<String> {
        log.iter()
            .map(|v| tick(10f64.powf(*v), 10f64.powf(*v)))
            .collect()
    }

    #[test]
    fn tick_labels_are_short() {
        let cases = [
            (1000.0, 2000.0, "1000"),
            (-500.0, 2000.0, "-500"),
            (1e-13, 2000.0, "0"),
            (-0.0, 1.0, "0"),
            (0.25, 1.0, "0.25"),
            (2.0000000000000004, 2.0, "2"),
            (1.9999999999999998, 2.0, "2"),
            (0.1 + 0.2, 1.0, "0.3"),
            // A narrow range far from zero keeps the digits that tell ticks apart.
            (12.0015, 0.002, "12.0015"),
            (1000.1, 0.5, "1000.1"),
            (1.25e6, 1e6, "1.25e6"),
            (2.5e-4, 1e-4, "2.5e-4"),
            (1e7, 1e7, "1e7"),
        ];
        for (v, span, want) in cases {
            assert_eq!(tick(v, span), want, "{v} over {span}");
        }
    }

    #[test]
    fn linear_ticks_are_round_and_inside() {
        let t = linear_ticks(1.62, 2.12, 5);
        let labels: Vec<String> = t.iter().map(|v| tick(*v, 0.5)).collect();
        assert_eq!(labels, ["1.7", "1.8", "1.9", "2", "2.1"]);
        let t = linear_ticks(-1000.0, 1000.0, 6);
        assert_eq!(t, [-1000.0, -500.0, 0.0, 500.0, 1000.0]);
        for (lo, hi) in [(0.0, 1e-9), (-3.7, 12.1), (1e5, 1.00001e5), (-1.0, -0.5)] {
            let t = linear_ticks(lo, hi, 6);
            assert!((2..=7).contains(&t.len()), "{lo}..{hi}: {t:?}");
            assert!(t.iter().all(|v| (lo..=hi).contains(v)), "{lo}..{hi}: {t:?}");
        }
        assert_eq!(linear_ticks(3.0, 3.0, 6), [3.0]);
        assert_eq!(linear_ticks(0.0, f64::INFINITY, 6), [0.0]);
    }

    #[test]
    fn log_ticks_name_round_values() {
        // A 6R arm's conditions, 5.7 to 52: 1-2-5 steps.
        assert_eq!(
            values(&log_ticks(5.7f64.log10(), 52f64.log10())),
            ["10", "20", "50"]
        );
        // Six decades: every power of ten; twenty: every third.
        assert_eq!(values(&log_ticks(0.0, 6.0)).len(), 7);
        assert_eq!(
            values(&log_ticks(-0.5, 19.5)),
            ["1", "1000", "1e6", "1e9", "1e12", "1e15", "1e18"]
        );
        // Within one step of 1..9: round values on a linear scale.
        assert_eq!(
            values(&log_ticks(1.62f64.log10(), 2.12f64.log10())),
            ["1.7", "1.8", "1.9", "2", "2.1"]
        );
        // Under a decade: 1..9.
        assert_eq!(
            values(&log_ticks(2.5f64.log10(), 9.5f64.log10())),
            ["3", "4", "5", "6", "7", "8", "9"]
        );
        for (lo, hi) in [(0.1, 0.3), (-2.0, 9.0), (3.0, 3.0001), (0.75, 1.75)] {
            let t = log_ticks(lo, hi);
            assert!(!t.is_empty() && t.len() <= 10, "{lo}..{hi}: {t:?}");
            assert!(t.iter().all(|v| (lo..=hi).contains(v)), "{lo}..{hi}: {t:?}");
        }
    }
}
