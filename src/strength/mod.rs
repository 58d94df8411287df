//! Strength from the contact analysis: the standard's nominal stresses ([`iso6336`]) and the
//! contact pressure along the path of contact from the LTCA's own load sharing ([`hertz`]).

pub mod hertz;
pub mod iso6336;
