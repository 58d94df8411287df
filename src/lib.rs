//! # geardyn — spur-gear mesh dynamics
//!
//! One gear pair, three fidelities, one currency: the periodic mesh stiffness k(θ).
//! This crate holds the numerical kernels (no IO) and the IO edges (`case`, `report`);
//! the `geardyn` binary only wires them.
//!
//! * [`case`] — TOML case files (engineering units at the edge, SI inside), validation,
//!   the embedded default case (the seed paper's pair).
//! * [`geometry`] — rack-generated involute/trochoid teeth, relief, the meshing pair.
//! * [`report`] — atomic file output, JSON summaries, tables and drawings.
//! * [`samples`] — canonical cases reused by tests, benches and docs.

pub mod case;
pub mod geometry;
pub mod report;
pub mod samples;
