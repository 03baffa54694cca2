//! The knowledge side of vmc-twin.
//!
//! This crate is the information boundary made structural: it does not depend on the twin crate,
//! so nothing in it can name the twin's error functions, thermal nodes, parameters or seeds. It
//! sees only what a real controller sees: nominal machine geometry, calibration datasets and
//! sensor readings.
pub mod compiled;
pub mod controller;
pub mod dataset;
pub mod drift;
pub mod guard;
pub mod history;
pub mod linreg;
pub mod metrics;
pub mod nn;
pub mod predictor;
pub mod provenance;
pub mod rc_identify;
pub mod selection;
pub mod synthesis;
pub mod thermal_fit;
