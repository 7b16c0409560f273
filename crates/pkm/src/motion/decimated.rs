//! A stream thinned to at most a fixed number of evenly spaced items (plot series of
//! runs of any length in flat memory).

/// The thinning both [`Decimated`] and [`DecimatedRows`] apply: every item is kept
/// until `cap`, then every second one is dropped and from there only every second
/// item kept, and so on (the stride doubles each time it fills).
#[derive(Debug, Clone)]
struct Thinning {
    cap: usize,
    stride: u64,
    seen: u64,
}

impl Thinning {
    fn new(cap: usize) -> Self {
        Thinning {
            cap: cap.max(2),
            stride: 1,
            seen: 0,
        }
    }

    /// For the stream's next item, with `kept` items kept so far: whether to drop
    /// every second kept item first, and whether to keep this one.
    fn next(&mut self, kept: usize) -> (bool, bool) {
        // The stride is a power of two: a mask, not a division per item.
        let (mut halve, mut keep) = (false, false);
        if self.seen & (self.stride - 1) == 0 {
            if kept >= self.cap {
                halve = true;
                self.stride *= 2;
            }
            keep = self.seen & (self.stride - 1) == 0;
        }
        self.seen += 1;
        (halve, keep)
    }
}

/// At most `cap` evenly spaced items of a stream of unknown length, in flat memory:
/// every item is kept until `cap`, then every second one is dropped and from there
/// only every second item kept, and so on (the stride doubles each time it fills).
#[derive(Debug, Clone)]
pub struct Decimated<T> {
    rows: Vec<T>,
    thin: Thinning,
}

impl<T> Decimated<T> {
    /// Keeps at most `cap` items (at least 2).
    pub fn new(cap: usize) -> Self {
        Decimated {
            rows: Vec::new(),
            thin: Thinning::new(cap),
        }
    }

    /// The next item of the stream; `item` is called only when it is kept.
    pub fn push(&mut self, item: impl FnOnce() -> T) {
        let (halve, keep) = self.thin.next(self.rows.len());
        if halve {
            let mut k = 0;
            self.rows.retain(|_| {
                k += 1;
                k % 2 == 1
            });
        }
        if keep {
            self.rows.push(item());
        }
    }
}

impl<T> std::ops::Deref for Decimated<T> {
    type Target = [T];
    fn deref(&self) -> &[T] {
        &self.rows
    }
}

impl<T: serde::Serialize> serde::Serialize for Decimated<T> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        self.rows.serialize(s)
    }
}

/// [`Decimated`] rows of `width` numbers each, in one buffer: no allocation per kept
/// row (a motion run's plot rows, one kept every few samples).
#[derive(Debug, Clone)]
pub struct DecimatedRows {
    values: Vec<f64>,
    width: usize,
    thin: Thinning,
}

impl DecimatedRows {
    /// Keeps at most `cap` rows (at least 2) of `width` numbers.
    pub fn new(cap: usize, width: usize) -> Self {
        DecimatedRows {
            values: Vec::new(),
            width,
            thin: Thinning::new(cap),
        }
    }

    /// The next row of the stream; `row` is called, to fill the row's `width`
    /// numbers (zeros on entry), only when it is kept.
    pub fn push(&mut self, row: impl FnOnce(&mut [f64])) {
        let (halve, keep) = self.thin.next(self.len());
        let w = self.width;
        if halve {
            let kept = self.len().div_ceil(2);
            for i in 1..kept {
                self.values.copy_within(2 * i * w..(2 * i + 1) * w, i * w);
            }
            self.values.truncate(kept * w);
        }
        if keep {
            let end = self.values.len();
            self.values.resize(end + w, 0.0);
            row(&mut self.values[end..]);
        }
    }

    /// The number of rows kept.
    pub fn len(&self) -> usize {
        self.values.len().checked_div(self.width).unwrap_or(0)
    }

    /// Whether no row is kept.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The rows kept, in order.
    pub fn iter(&self) -> std::slice::ChunksExact<'_, f64> {
        self.values.chunks_exact(self.width.max(1))
    }
}

impl serde::Serialize for DecimatedRows {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        s.collect_seq(self.iter())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The flat rows keep the rows [`Decimated`] keeps, in order, over streams that
    /// fill the cap zero to six times (and the items themselves thin evenly: the
    /// kept indices are a multiple of the final stride apart).
    #[test]
    fn flat_rows_keep_what_the_items_keep() {
        for cap in [2, 3, 7, 16] {
            for n in [0u64, 1, 2, 5, 16, 17, 100, 1000] {
                let mut items = Decimated::new(cap);
                let mut rows = DecimatedRows::new(cap, 3);
                for k in 0..n {
                    items.push(|| k);
                    rows.push(|r| r.copy_from_slice(&[k as f64, -(k as f64), 0.5]));
                }
                let flat: Vec<Vec<f64>> = rows.iter().map(<[f64]>::to_vec).collect();
                let want: Vec<Vec<f64>> = items
                    .iter()
                    .map(|&k| vec![k as f64, -(k as f64), 0.5])
                    .collect();
                assert_eq!(flat, want, "cap {cap}, {n} items");
                assert_eq!(rows.len(), items.len());
                assert!(items.len() <= cap.max(2));
                let gaps: Vec<u64> = items.windows(2).map(|w| w[1] - w[0]).collect();
                assert!(gaps.windows(2).all(|g| g[0] == g[1]), "{gaps:?}");
                if n as usize > cap {
                    assert!(items.len() * 2 > cap, "cap {cap}, {n}: {}", items.len());
                }
            }
        }
    }
}
