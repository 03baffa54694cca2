//! Compensation tables for real controllers (crate doc: README).
pub mod cec;
pub mod linuxcnc;
pub mod number;
