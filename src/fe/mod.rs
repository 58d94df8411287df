//! Finite elements: the Q8 plane element, sparse assembly and the factorized stiffness.
//!
//! * [`q8`] — 8-node serendipity quadrilateral, plane stress / plane strain with thickness B.
//! * [`assembly`] — global stiffness (faer sparse), constraints, Cholesky, solves.
//! * [`modal`] — the lowest modes of K φ = ω² M φ by shift-invert Lanczos.
//! * [`recovery`] — stresses at the nodes (the surface) from the displacements.

pub mod assembly;
pub mod modal;
pub mod q8;
pub mod recovery;

pub use assembly::{FactorizedStiffness, FeError};
pub use q8::{elasticity_matrix, MassLumping, PlaneState};
