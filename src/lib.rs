//! vmc-twin: the application — command line, use cases, studies, recordings and reports.
//!
//! The workspace's crates are its sides (docs/architecture.md):
//! - `vmc-gcode`: RS274/NGC syntax and the modal interpreter, knowing no machine;
//! - `vmc-machine`: the simulated machine, the truth side;
//! - `vmc-predict`, `vmc-identify`, `vmc-dynamics`: the knowledge side (error prediction and
//!   compensation, five-axis identification, milling dynamics and chatter control), re-exported
//!   here as [`predict`], [`identify`] and [`dynamics`]; none depends on the machine;
//! - this crate: the [`cli`] and its [`commands`] (the use cases), the [`studies`], Rerun
//!   [`record`]ings, [`report`]s, [`shard`]s of a study and their merge, output [`files`],
//!   [`progress`] bars and the [`benchmark`] figures. It is the only crate that knows Rerun,
//!   output files and terminals.
pub use vmc_dynamics as dynamics;
pub use vmc_identify as identify;
pub use vmc_predict as predict;

pub mod benchmark;
pub mod cli;
pub mod commands;
pub mod files;
pub mod progress;
pub mod record;
pub mod report;
pub mod shard;
pub mod studies;
