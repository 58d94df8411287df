//! Optimization kernels: the quadratic programs of the relief optimizer, solved by Clarabel.
//!
//! * [`qp`] — a dense convex QP (equalities and inequalities) through Clarabel's interior-point
//!   solver, with its own KKT check.
//! * [`relief`] — the relief design variables and the modifications they make.

pub mod qp;
pub mod relief;
