//! The studies built on the twin: the virtual [`calibration`] campaign, the compensation
//! [`campaign`] (calibrate, train, evaluate on held-out states, fleets of machines), sensor
//! [`placement`], the [`chatter`] check of a milling program, and the static compensation
//! [`tables`] against the live hybrid.

pub mod calibration;
pub mod campaign;
pub mod chatter;
pub mod placement;
pub mod probing;
pub mod tables;
