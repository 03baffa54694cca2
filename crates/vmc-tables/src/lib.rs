#![doc = include_str!("../README.md")]
#![warn(missing_docs)]

pub mod apply;
pub mod cec;
pub mod export;
pub mod linuxcnc;
pub mod number;
pub mod readings;
pub mod sample;

#[cfg(test)]
mod testmodel;
