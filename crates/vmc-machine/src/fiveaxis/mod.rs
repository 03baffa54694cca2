//! Five-axis machines: the truth of a trunnion machine with ISO 230-7 errors, a virtual touch
//! probe on a reference sphere, the probing campaign and the held-out judge of an identified
//! model.
//!
//! The knowledge side (chain, exact and first-order models, identification) is the
//! `vmc-identify` crate; this module is the twin: it draws the machine's errors ([`truth`]),
//! evaluates them at a pose and hands them to `vmc_identify::htm`'s exact model, and measures
//! with the same noise a real probe has ([`probe`]). Units: mm, rad, degrees for commanded
//! angles; µm in reports.

pub mod campaign;
pub mod heldout;
pub mod identified;
pub mod plan;
pub mod probe;
pub mod run;
pub mod spec;
pub mod tcp_timing;
pub mod truth;

pub use spec::FiveAxisSpec;
pub use truth::TrueMachine;
