//! vmc-machine: the simulated machine of vmc-twin — the truth side.
//!
//! Machine descriptions ([`machine`], loaded from `machines/*.toml`), the kinematic chain and
//! its full HTM product ([`kinematics`]), the geometric error field ([`errors`]), the lumped
//! [`thermal`] network, the [`sensors`] and the virtual [`instruments`] that measure it, the
//! [`twin`] that ties them together, the [`motion`] planner, the [`sim`] loop, [`tools`], the [`touch_probe`],
//! [`collision`] checks ([`collision_spec`] for fixtures and stock), the twin side of cutting
//! ([`cutting`] engagement, [`milling`] tools, the piezo [`blade`]), the five-axis truth
//! ([`fiveaxis`]) and the programs that run on it ([`program`]: G-code through `vmc-gcode` into a
//! timed plan). Text inputs are read through [`read`].
//!
//! The knowledge side (`vmc-predict`, `vmc-identify`, `vmc-dynamics`) never depends on this
//! crate; this crate uses it only for the interfaces the machine offers a controller (the
//! `Controller` trait, the sensor readings' form) and the nominal geometry both sides share.

pub mod blade;
pub mod collision;
pub mod collision_spec;
pub mod cutting;
pub mod errors;
pub mod fiveaxis;
pub mod instruments;
pub mod kinematics;
pub mod machine;
pub mod milling;
pub mod motion;
pub mod plausible;
pub mod probe_setup;
pub mod program;
pub mod read;
pub mod sensors;
pub mod setup;
pub mod sim;
pub mod thermal;
pub mod tools;
pub mod touch_probe;
pub mod twin;
