//! Strength from the contact analysis: the standard's nominal stresses ([`iso6336`]) and the
//! contact pressure along the path of contact from the LTCA's own load sharing ([`hertz`]), and the
//! safety factors against the material's limits ([`safety`]).

pub mod hertz;
pub mod iso6336;
pub mod safety;
