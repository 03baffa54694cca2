//! vmc-twin: a digital twin of a 3-axis vertical machining center.
//!
//! Truth side (this crate): [`machine`] descriptions, [`kinematics`] (full HTM product),
//! the geometric [`errors`] field, the [`thermal`] network, [`sensors`], the [`twin`] that ties
//! them together, the G-code front end ([`gcode`] syntax, [`interp`] semantics), the [`motion`]
//! planner, the [`sim`] loop, [`report`]s, Rerun [`record`]ings and [`progress`] bars. Knowledge side: the `vmc-predict` crate, re-exported
//! as [`predict`]; it does not depend on this crate (the information boundary, docs/architecture.md).
pub use vmc_dynamics as dynamics;
pub use vmc_identify as identify;
pub use vmc_predict as predict;

pub mod benchmark;
pub mod blade;
pub mod calibration;
pub mod chatter;
pub mod cli;
pub mod collision;
pub mod collision_spec;
pub mod commands;
pub mod cutting;
pub mod errors;
pub mod files;
pub mod fiveaxis;
pub mod gcode;
pub mod instruments;
pub mod interp;
pub mod kinematics;
pub mod machine;
pub mod milling;
pub mod motion;
pub mod placement;
pub mod program;
pub mod progress;
pub mod record;
pub mod report;
pub mod sensors;
pub mod shard;
pub mod sim;
pub mod study;
pub mod thermal;
pub mod tools;
pub mod twin;
