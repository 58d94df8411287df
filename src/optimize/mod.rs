//! Optimization kernels: the quadratic programs of the relief optimizer, solved by Clarabel.
//!
//! * [`qp`] — a dense convex QP (equalities and inequalities) through Clarabel's interior-point
//!   solver, with its own KKT check.
//! * [`relief`] — the relief design variables and the modifications they make.
//! * [`robust`] — the trust-region loop that flattens the loaded STE over a load range.

pub mod qp;
pub mod relief;
pub mod robust;
