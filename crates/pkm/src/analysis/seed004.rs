//! Seed 004's reproduction on a loaded P3RP machine (the head alone or the hybrid
//! machine's head): the paper's numbers beside pkm's ([`crate::p3rp::seed004`]).

use crate::error::Result;
use crate::machine::Machine;
use crate::p3rp::seed004::Reproduced;

/// Every number seed 004 reports, reproduced on `machine`'s head
/// ([`crate::machine::Analysis::Seed004`]).
pub fn reproduction(machine: &Machine) -> Result<Vec<Reproduced>> {
    crate::p3rp::seed004::reproduction(&machine.p3rp_head()?)
}
