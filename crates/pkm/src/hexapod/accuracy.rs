//! The hexapod in the accuracy engine, as a strut machine: every joint centre is a
//! parameter (what identification estimates), the drives are the struts' zero
//! lengths, the sensitivities analytic (`accuracy::rebuild::strut_sensitivities`).

crate::accuracy::rebuild::strut_rebuild!(super::Hexapod, 6);
