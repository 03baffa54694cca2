//! The knowledge side of five-axis geometric error identification (ISO 230-7).
//!
//! A five-axis machine is described by its chain (`w C A Y X b Z t`: the workpiece on a C table
//! on an A trunnion carried by the Y and X slides, Z carrying the tool) and its nominal geometry
//! ([`chain`]). Its geometric errors ([`errors`]) are the 21 errors of the linear axes, the six
//! motion errors of each rotary axis as functions of its angle, the location errors of the axis
//! average lines and the assembly errors of the workpiece and tool sides.
//!
//! What a touch probe reads when it probes a reference sphere at a configuration follows from
//! the exact homogeneous-transform product ([`htm`]); its first-order form `δq = S·E`
//! ([`sensitivity`]) is what identification inverts ([`identify`]), after the sphere centre of
//! each configuration has been fitted to the probed points ([`sphere`]). [`design`] chooses the
//! configurations worth probing; [`order`] chooses the harmonic orders of the rotary motion
//! errors from the probing data by cross-validation over configurations.
//!
//! Like `vmc-predict`, this crate does not depend on the twin: it sees probing data and nominal
//! geometry only. Everything here is pure numerics (no files, no printing). Units: mm, rad
//! (degrees only in [`chain::Pose`] angles as commanded).

pub mod chain;
pub mod design;
pub mod errors;
pub mod htm;
pub mod identify;
pub mod inverse;
pub mod inverse_pose;
pub mod order;
pub mod sensitivity;
pub mod sphere;
