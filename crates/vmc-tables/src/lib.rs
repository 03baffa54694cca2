#![doc = include_str!("../README.md")]

pub mod cec;
pub mod export;
pub mod linuxcnc;
pub mod number;
pub mod readings;
pub mod sample;

#[cfg(test)]
mod testmodel;
