//! A stream thinned to at most a fixed number of evenly spaced items (plot series of
//! runs of any length in flat memory).

/// At most `cap` evenly spaced items of a stream of unknown length, in flat memory:
/// every item is kept until `cap`, then every second one is dropped and from there
/// only every second item kept, and so on (the stride doubles each time it fills).
#[derive(Debug, Clone)]
pub struct Decimated<T> {
    rows: Vec<T>,
    cap: usize,
    stride: u64,
    seen: u64,
}

impl<T> Decimated<T> {
    /// Keeps at most `cap` items (at least 2).
    pub fn new(cap: usize) -> Self {
        Decimated {
            rows: Vec::new(),
            cap: cap.max(2),
            stride: 1,
            seen: 0,
        }
    }

    /// The next item of the stream; `item` is called only when it is kept.
    pub fn push(&mut self, item: impl FnOnce() -> T) {
        // The stride is a power of two: a mask, not a division per item.
        let mask = self.stride - 1;
        if self.seen & mask == 0 {
            if self.rows.len() >= self.cap {
                let kept: Vec<T> = self.rows.drain(..).step_by(2).collect();
                self.rows = kept;
                self.stride *= 2;
            }
            if self.seen & (self.stride - 1) == 0 {
                self.rows.push(item());
            }
        }
        self.seen += 1;
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
