#![doc = include_str!("../README.md")]

pub mod interp;
pub mod syntax;

pub use interp::{
    run_program, CanonKind, CanonMove, GcodeError, GcodeErrorKind, InterpConfig, Interpreter,
    Plane, SpindleDir,
};
