//! Helpers shared by the differential tests against LinuxCNC's interpreter.
#![allow(dead_code, unused_imports)] // each test crate uses its own subset

pub mod rs274;
mod temp_dir;
pub use temp_dir::TempDir;
