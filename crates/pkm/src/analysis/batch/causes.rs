//! Why the rows of a batch failed, as codes into a table of distinct causes: each
//! violated limit by name, each solver failure by [`Error::category`], interned once
//! per batch (a million failing rows need no million strings).

use serde::Serialize;

use super::filled;
use crate::error::Error;
use crate::limits::{LimitCode, LimitKind, LimitName, Side, Violation};

/// A cause shared by every row of a batch that fails for it (a million rows need no
/// million strings).
///
/// # Examples
///
/// ```
/// use pkm::analysis::batch::inverse_batch;
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/hexapod-linuxcnc.toml"
/// ))
/// .unwrap();
/// // Three poses, two of them beyond the strokes for the same reason.
/// let mut poses = vec![0.0, 0.0, 508.0, 0.0, 0.0, 0.0];
/// poses.extend([0.0, 0.0, 908.0, 0.0, 0.0, 0.0, 0.0, 0.0, 950.0, 0.0, 0.0, 0.0]);
/// let c = inverse_batch(&machine, &poses).unwrap().causes;
/// assert_eq!(c.reasons.len(), 1); // one shared cause
/// assert_eq!((c.reason[1], c.reason[2]), (0, 0));
/// assert_eq!(c.reasons[0].unit, "mm");
/// assert!(c.reasons[0].text.contains("length"));
/// ```
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BatchReason {
    /// The violated limit's name (`strut L2 length`), or the kind of solver failure
    /// ([`Error::category`]: `no solution`, `no solution found (... did not
    /// converge)`) where the row has no solution.
    pub text: String,
    /// Family of the limit; `None` where the row has no solution.
    pub kind: Option<LimitKind>,
    /// Unit of the rows' values and bounds (empty where the row has no solution).
    pub unit: &'static str,
}

/// Why each row of a batch failed, in columns.
///
/// # Examples
///
/// ```
/// use pkm::analysis::batch::inverse_batch;
/// use pkm::analysis::kinematics::inverse;
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/hexapod-linuxcnc.toml"
/// ))
/// .unwrap();
/// let high = [0.0, 0.0, 908.0, 0.0, 0.0, 0.0];
/// let mut poses = vec![0.0, 0.0, 508.0, 0.0, 0.0, 0.0];
/// poses.extend(high);
/// let c = inverse_batch(&machine, &poses).unwrap().causes;
/// // Row 0 is fine: no reason, value or bound.
/// assert_eq!(c.reason[0], -1);
/// assert!(c.value[0].is_nan() && c.violation(0).is_none() && c.message(0).is_none());
/// // Row 1 as the single call reports it: its first violated limit.
/// let v = c.violation(1).unwrap();
/// assert_eq!(v, inverse(&machine, &high).unwrap().violations[0]);
/// assert!((c.excess(1) - (c.value[1] - c.bound[1]).abs()).abs() < 1e-12);
/// assert_eq!(c.message(1).unwrap(), v.to_string());
/// ```
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Causes {
    /// Per row: index into [`Causes::reasons`] of its first violated limit or of why
    /// it has no solution; -1 when it is fine.
    pub reason: Vec<i32>,
    /// Per row: the value found for its first violated limit (user units); NaN when
    /// fine or without solution.
    pub value: Vec<f64>,
    /// Per row: the bound that value crossed (user units); NaN when fine or without
    /// solution.
    pub bound: Vec<f64>,
    /// The distinct causes the rows point to.
    pub reasons: Vec<BatchReason>,
    /// The solver's own message (with its numbers: residual, distances) of every row
    /// without a solution, by row, ascending.
    pub errors: Vec<(usize, String)>,
}

impl Causes {
    pub(super) fn new(n: usize) -> Self {
        Causes {
            reason: filled(n, -1),
            value: filled(n, f64::NAN),
            bound: filled(n, f64::NAN),
            reasons: Vec::new(),
            errors: Vec::new(),
        }
    }

    /// By how much row `i`'s first violated limit is crossed (user units, positive);
    /// NaN when it is fine or has no solution.
    pub fn excess(&self, i: usize) -> f64 {
        (self.value[i] - self.bound[i]).abs()
    }

    /// The first violated limit of row `i`, as [`Violation`] (`None` when it is fine
    /// or has no solution).
    pub fn violation(&self, i: usize) -> Option<Violation> {
        let r = &self.reasons[usize::try_from(self.reason[i]).ok()?];
        let kind = r.kind?;
        let (value, bound) = (self.value[i], self.bound[i]);
        Some(Violation {
            limit: r.text.as_str().into(),
            kind,
            side: if value < bound { Side::Min } else { Side::Max },
            value,
            bound,
            excess: (value - bound).abs(),
            unit: r.unit,
        })
    }

    /// Why row `i` failed, as the single-row call says it (the violated limit with its
    /// value, bound and excess, or the solver's message); `None` when it is fine.
    pub fn message(&self, i: usize) -> Option<String> {
        let r = &self.reasons[usize::try_from(self.reason[i]).ok()?];
        Some(match self.violation(i) {
            Some(v) => v.to_string(),
            None => match self.errors.binary_search_by_key(&i, |e| e.0) {
                Ok(k) => self.errors[k].1.clone(),
                Err(_) => r.text.clone(),
            },
        })
    }
}

/// The hash of the interner's short keys (limit names): multiply-rotate over 8-byte
/// words (as rustc's FxHash); SipHash's resistance to chosen keys is not needed for
/// the limit names of one machine, and it took 5 % of a batch of random hexapod poses
/// (callgrind).
#[derive(Default)]
struct WordHash(u64);

impl std::hash::Hasher for WordHash {
    fn write(&mut self, bytes: &[u8]) {
        for chunk in bytes.chunks(8) {
            let mut word = [0u8; 8];
            word[..chunk.len()].copy_from_slice(chunk);
            self.0 = (self.0.rotate_left(5) ^ u64::from_le_bytes(word))
                .wrapping_mul(0x517c_c1b7_2722_0a95);
        }
    }

    fn finish(&self) -> u64 {
        self.0
    }
}

/// One chunk's distinct causes and the map from them to their indices.
#[derive(Default)]
pub(super) struct Interner {
    pub(super) reasons: Vec<BatchReason>,
    index: std::collections::HashMap<
        (LimitName, Option<LimitKind>),
        i32,
        std::hash::BuildHasherDefault<WordHash>,
    >,
}

impl Interner {
    pub(super) fn code(
        &mut self,
        text: impl Into<LimitName>,
        kind: Option<LimitKind>,
        unit: &'static str,
    ) -> i32 {
        let next = self.reasons.len() as i32;
        *self
            .index
            .entry((text.into(), kind))
            .or_insert_with_key(|(text, kind)| {
                self.reasons.push(BatchReason {
                    text: text.to_string(),
                    kind: *kind,
                    unit,
                });
                next
            })
    }
}

/// The rows of one chunk of [`Causes`], written by one task; `errors` by row within
/// the chunk.
pub(super) struct CauseRows<'a> {
    pub(super) reason: &'a mut [i32],
    pub(super) value: &'a mut [f64],
    pub(super) bound: &'a mut [f64],
    pub(super) table: Interner,
    pub(super) errors: Vec<(usize, String)>,
    /// The table's index of each limit code met so far (-1: not yet).
    pub(super) codes: Vec<i32>,
}

/// Limit codes above this are interned by name each time (a mechanism's own numbering
/// stays far below).
const MAX_CACHED_CODE: usize = 4096;

impl CauseRows<'_> {
    /// Row `i` stopped at the limit of `code`; `describe` names it, called once per
    /// distinct code in the chunk.
    pub(super) fn coded(
        &mut self,
        i: usize,
        code: &LimitCode,
        describe: impl FnOnce() -> Violation,
    ) {
        let id = code.id as usize;
        let known = self.codes.get(id).copied().filter(|c| *c >= 0);
        self.reason[i] = match known {
            Some(c) => c,
            None => {
                let v = describe();
                let c = self.table.code(v.limit, Some(v.kind), v.unit);
                if id < MAX_CACHED_CODE {
                    if id >= self.codes.len() {
                        self.codes.resize(id + 1, -1);
                    }
                    self.codes[id] = c;
                }
                c
            }
        };
        self.value[i] = code.quantity.to_user(code.value);
        self.bound[i] = code.quantity.to_user(code.bound);
    }

    pub(super) fn violation(&mut self, i: usize, v: Violation) {
        self.reason[i] = self.table.code(v.limit, Some(v.kind), v.unit);
        self.value[i] = v.value;
        self.bound[i] = v.bound;
    }

    pub(super) fn error(&mut self, i: usize, e: &Error) {
        self.reason[i] = self.table.code(e.category(), None, "");
        self.errors.push((i, e.to_string()));
    }
}
