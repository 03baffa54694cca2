//! The compiled hybrid model behind a C ABI, for a controller's real-time thread: what a
//! LinuxCNC HAL component (a `.comp` shim around this static library) calls at the servo rate.
//!
//! A controller's servo thread knows, at every period: the commanded tool position (mm), the
//! commanded spindle speed (rpm) and axis speeds (mm/min), its clock (s), and the latest
//! temperature readings (°C), which its sensors refresh at their own, much slower, rate. The
//! component turns these into per-axis corrections (mm) to add to the commanded position (in
//! LinuxCNC, through the axes' external offsets):
//!
//! - at a **sample** (the caller flags new readings), the readings are observed at that time,
//!   with the spindle speed and the axis feeds averaged over the servo periods since the previous
//!   sample (each period's commands held over it: the mean |speed| the model's filters want,
//!   see `vmc_predict::history`);
//! - at **every period**, the compensation's fixed point `q = p − E(q, T)` is solved for the
//!   commanded position `p` under the readings held ([`vmc_predict::compiled`]), and the
//!   correction is `q − p`.
//!
//! The C functions (header `include/vmc_rtcomp.h`): [`ffi::vmc_comp_new`] (allocates: at load
//! time only), [`ffi::vmc_comp_update`] (no allocation, no lock, no panic on any input: bad
//! input gives zero corrections and a status), [`ffi::vmc_comp_free`], and small helpers
//! (sensor names, tool offset). A handle is used by one thread at a time.
//!
//! What a real-time build needs beyond this crate: `panic = "abort"` (a profile setting, so in
//! the workspace's root manifest, e.g. a profile `[profile.rt] inherits = "release"`,
//! `panic = "abort"`, built with `cargo build -p vmc-rtcomp --profile rt`); no path here
//! panics or allocates after [`ffi::vmc_comp_new`], and the tests check the latter.

pub mod ffi;
mod rt;

pub use rt::{Inputs, Outputs, RtComp, Status};
