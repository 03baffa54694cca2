//! The studies built on the twin: the virtual [`calibration`] campaign, the compensation
//! [`campaign`] (calibrate, train, evaluate on held-out states, fleets of machines), sensor
//! [`placement`], and the [`chatter`] check of a milling program.

pub mod calibration;
pub mod campaign;
pub mod chatter;
pub mod placement;
pub mod probing;
