//! vmc-twin: a digital twin of a 3-axis vertical machining center.
pub use vmc_predict as predict;

pub mod gcode;
pub mod interp;
pub mod kinematics;
pub mod thermal;
pub mod sensors;
