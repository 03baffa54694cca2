#![doc = include_str!("../README.md")]

pub mod interp;
pub mod syntax;

pub use interp::{
    run_program, CallSite, CanonKind, CanonMove, GcodeError, GcodeErrorKind, InterpConfig,
    Interpreter, Plane, ProbeKind, ProbeOutcome, ProbeRequest, ProgramRun, RunEvent, SpindleDir,
};
