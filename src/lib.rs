//! # geardyn — spur-gear mesh dynamics
//!
//! One gear pair, three fidelities, one currency: the periodic mesh stiffness k(θ).
//! This crate holds the numerical kernels (no IO, no case schema: geometry, mesh, fe, contact,
//! ltca, explicit, stiffness, lumped, sweep, signal, optimize), the studies that drive them, and the IO
//! edges (`case`, `report`); the `geardyn` binary only parses arguments and wires them.
//!
//! * [`case`] — TOML case files (engineering units at the edge, SI inside), validation,
//!   the embedded default case (the seed paper's pair).
//! * [`geometry`] — rack-generated involute/trochoid teeth, relief, the meshing pair.
//! * [`study`] — one module per command: a checked case and typed options in, a typed result
//!   with a `Serialize` summary out; the models are built through its constructors.
//! * [`report`] — atomic file output, JSON summaries, tables and drawings.
//! * [`samples`] — canonical cases reused by tests, benches and docs.
//! * [`interrupt`] — the stop request (SIGINT/SIGTERM) the long loops poll.
//! * [`resources`] — the memory limit the models check their estimates against, and `--force`.

// Input checks are written `!(x > limit)` on purpose: a NaN must fail them.
#![allow(clippy::neg_cmp_op_on_partial_ord)]
// Units are written in brackets, [m] or [N/m], as the docs of every quantity do; they are not links.
#![allow(rustdoc::broken_intra_doc_links)]

pub mod case;
pub mod contact;
pub mod explicit;
pub mod fe;
pub mod geometry;
pub mod interrupt;
pub mod ltca;
pub mod lumped;
pub mod mesh;
pub mod optimize;
pub mod report;
pub mod resources;
pub mod samples;
pub mod signal;
pub mod stiffness;
pub mod strength;
pub mod study;
pub mod sweep;
