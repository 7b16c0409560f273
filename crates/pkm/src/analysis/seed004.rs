//! Seed 004's reproduction on a loaded P3RP machine (the head alone or the hybrid
//! machine's head): the paper's numbers beside pkm's ([`crate::p3rp::seed004`]).

use crate::error::Result;
use crate::machine::Machine;
use crate::p3rp::seed004::Reproduced;

/// Every number seed 004 reports, reproduced on `machine`'s head
/// ([`crate::machine::Analysis::Seed004`]).
///
/// # Examples
///
/// ```
/// use pkm::analysis::seed004::reproduction;
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/p3rp-seed004.toml"
/// ))
/// .unwrap();
/// let rows = reproduction(&machine).unwrap();
/// assert_eq!(rows.len(), 10);
/// // The paper's lengths reproduced to 0.1 mm (but a plot reading the paper
/// // contradicts, noted as such).
/// for r in rows.iter().filter(|r| r.unit == "mm" && r.note.is_none()) {
///     assert!(r.paper.iter().zip(&r.pkm).all(|(a, b)| (a - b).abs() < 0.1), "{}", r.quantity);
/// }
/// // Machines without a P3RP head have no such reproduction.
/// let hexapod = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/hexapod-linuxcnc.toml"
/// ))
/// .unwrap();
/// assert!(reproduction(&hexapod).is_err());
/// ```
pub fn reproduction(machine: &Machine) -> Result<Vec<Reproduced>> {
    crate::p3rp::seed004::reproduction(&machine.p3rp_head()?)
}
