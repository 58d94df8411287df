//! Explicit dynamics: corotational Q8 bodies with lumped mass ([`body`]), the per-DOF
//! central-difference updates on the CPU's vector width ([`kicks`]), central-difference
//! integration of one body with its critical step ([`solver`]), the meshing pair on rigid hubs
//! with penalty/Coulomb contact and its energy account ([`pair`]), its two gears on two threads
//! in lock-step ([`lockstep`]), the transfer of a run's state between meshes of a gear
//! ([`remesh`]), and the scenes of a case with the analysis of their DTE
//! ([`scene`]).

pub mod body;
pub mod far;
pub mod kicks;
pub mod lockstep;
pub mod pair;
pub mod reduced;
pub mod remesh;
pub mod scene;
pub mod solver;
