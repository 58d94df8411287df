//! Canonical problems shared by tests, benchmarks and docs.
//!
//! The seed paper's pair comes from the embedded default case file (`data/cases/paper36.toml`),
//! so there is one definition of it.

use crate::case::Case;
use crate::geometry::{BasicRack, FlankReliefSpec, GearPair, GearSpec};

/// The embedded default case: the seed paper's pair (Z1 = Z2 = 36, m = 3.18 mm, α = 20°).
pub fn paper36_case() -> Case {
    Case::embedded_default().expect("the embedded default case is valid")
}

/// Rack and the two gear specs of the paper's pair.
pub fn paper36_specs() -> (BasicRack, GearSpec, GearSpec) {
    let spec = paper36_case().pair_spec;
    (spec.rack, spec.gears[0], spec.gears[1])
}

/// The paper's pair, checked.
pub fn paper36_pair() -> GearPair {
    paper36_case().pair
}

/// The paper's relief on one gear: 20 µm tip and 10 µm root, linear, long relief
/// (variant `tip20-root10` of the default case).
pub fn paper_relief() -> FlankReliefSpec {
    let case = paper36_case();
    let variant = case
        .relief_variant("tip20-root10")
        .expect("the default case has the paper's relief");
    variant.requests[0]
}
