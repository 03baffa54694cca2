//! The C functions (declared in `include/vmc_rtcomp.h`): thin wrappers around [`RtComp`] that
//! check every pointer and length before use.
//!
//! A handle is created by [`vmc_comp_new`] (or [`vmc_comp_new_err`]) and released by
//! [`vmc_comp_free`]; between the two, one thread at a time calls the others with it.

use std::ffi::c_char;

use crate::rt::{Inputs, Outputs, RtComp, Status};

/// The model file text at `json` (`len` bytes, UTF-8, no NUL needed), or a message.
///
/// # Safety
/// `json` is null or points to `len` readable bytes.
unsafe fn model_text<'a>(json: *const u8, len: usize) -> Result<&'a str, String> {
    if json.is_null() {
        return Err("the model text pointer is null".into());
    }
    // SAFETY: non-null, and the caller vouches for `len` readable bytes.
    let bytes = unsafe { std::slice::from_raw_parts(json, len) };
    std::str::from_utf8(bytes).map_err(|e| format!("the model text is not UTF-8: {e}"))
}

/// Loads the model file text at `json` (`len` bytes, the file `train` writes) and returns a
/// handle, or null when it cannot be used (not a model file, not a hybrid model, …; use
/// [`vmc_comp_new_err`] for the reason). Allocates: call it at load time, not in the real-time
/// thread.
///
/// # Safety
/// `json` is null or points to `len` readable bytes.
#[no_mangle]
pub unsafe extern "C" fn vmc_comp_new(json: *const u8, len: usize) -> *mut RtComp {
    // SAFETY: passed on; a null message buffer is never written.
    unsafe { vmc_comp_new_err(json, len, std::ptr::null_mut(), 0) }
}

/// As [`vmc_comp_new`]; on failure, also writes the reason, NUL-terminated and cut to fit, into
/// `err` (`err_cap` bytes; nothing is written when `err` is null or `err_cap` is 0).
///
/// # Safety
/// `json` is null or points to `len` readable bytes; `err` is null or points to `err_cap`
/// writable bytes.
#[no_mangle]
pub unsafe extern "C" fn vmc_comp_new_err(
    json: *const u8,
    len: usize,
    err: *mut c_char,
    err_cap: usize,
) -> *mut RtComp {
    // SAFETY: the caller's contract on `json`.
    let made = unsafe { model_text(json, len) }
        .and_then(|text| RtComp::new(text).map_err(|e| e.to_string()));
    match made {
        Ok(comp) => Box::into_raw(Box::new(comp)),
        Err(message) => {
            if !err.is_null() && err_cap > 0 {
                let n = message.len().min(err_cap - 1);
                // SAFETY: `err` has `err_cap` writable bytes and `n + 1 ≤ err_cap`.
                unsafe {
                    std::ptr::copy_nonoverlapping(message.as_ptr().cast::<c_char>(), err, n);
                    *err.add(n) = 0;
                }
            }
            std::ptr::null_mut()
        }
    }
}

/// One servo period: takes the sample in `inputs` when it flags one, compensates the commanded
/// position, writes the corrections and the status into `outputs` and returns the status
/// (`VMC_COMP_*`). No allocation, no lock. A null handle or pointer, or bad input, gives
/// `VMC_COMP_BAD_INPUT` and zero corrections (`outputs` is written when it is not null).
///
/// # Safety
/// `comp` is null or a handle from [`vmc_comp_new`] not yet freed, used by no other thread
/// meanwhile; `inputs` is null or points to a `VmcCompInputs` whose `temps_degc`, when
/// `new_sample` is nonzero, is null or points to `n_temps` readable doubles; `outputs` is null
/// or points to a writable `VmcCompOutputs`.
#[no_mangle]
pub unsafe extern "C" fn vmc_comp_update(
    comp: *mut RtComp,
    inputs: *const Inputs,
    outputs: *mut Outputs,
) -> i32 {
    // SAFETY: the caller's contract: valid or null, and not shared meanwhile.
    let (comp, inputs) = unsafe { (comp.as_mut(), inputs.as_ref()) };
    let out = match (comp, inputs) {
        (Some(comp), Some(i)) => {
            let temps = if i.new_sample == 0 {
                Ok(None)
            } else if i.temps_degc.is_null() {
                Err(())
            } else {
                // SAFETY: non-null, `n_temps` readable doubles by the caller's contract.
                Ok(Some(unsafe {
                    std::slice::from_raw_parts(i.temps_degc, i.n_temps)
                }))
            };
            match temps {
                Ok(temps) => comp.update(
                    i.time_s,
                    temps,
                    i.commanded_mm,
                    i.spindle_rpm,
                    i.axis_feed_mm_per_min,
                ),
                Err(()) => bad_input(),
            }
        }
        _ => bad_input(),
    };
    // SAFETY: null or a writable `Outputs` by the caller's contract.
    if let Some(o) = unsafe { outputs.as_mut() } {
        *o = out;
    }
    out.status
}

/// Zero corrections and `VMC_COMP_BAD_INPUT`.
fn bad_input() -> Outputs {
    Outputs {
        status: Status::BadInput as i32,
        ..Outputs::default()
    }
}

/// Number of sensors the model reads (the `n_temps` of every sample); 0 for a null handle.
///
/// # Safety
/// `comp` is null or a live handle.
#[no_mangle]
pub unsafe extern "C" fn vmc_comp_n_sensors(comp: *const RtComp) -> usize {
    // SAFETY: the caller's contract.
    unsafe { comp.as_ref() }.map_or(0, RtComp::n_sensors)
}

/// Name of sensor `index` (model order) as a NUL-terminated string owned by the handle (valid
/// until [`vmc_comp_free`]); null for a null handle or an index out of range.
///
/// # Safety
/// `comp` is null or a live handle.
#[no_mangle]
pub unsafe extern "C" fn vmc_comp_sensor_name(comp: *const RtComp, index: usize) -> *const c_char {
    // SAFETY: the caller's contract.
    unsafe { comp.as_ref() }
        .and_then(|c| c.sensor_name(index))
        .map_or(std::ptr::null(), |n| n.as_ptr())
}

/// Follows a tool change (the tool tip from the spindle gauge point, mm, in the spindle frame;
/// a vertical mill: `(0, 0, −gauge length)`). Returns `VMC_COMP_OK`, or `VMC_COMP_BAD_INPUT`
/// for a null handle or a component that is not finite (nothing changes then). No allocation.
///
/// # Safety
/// `comp` is null or a live handle used by no other thread meanwhile.
#[no_mangle]
pub unsafe extern "C" fn vmc_comp_set_tool_offset(
    comp: *mut RtComp,
    x_mm: f64,
    y_mm: f64,
    z_mm: f64,
) -> i32 {
    // SAFETY: the caller's contract.
    match unsafe { comp.as_mut() }.map(|c| c.set_tool_offset_mm([x_mm, y_mm, z_mm])) {
        Some(Ok(())) => Status::Ok as i32,
        _ => Status::BadInput as i32,
    }
}

/// Releases a handle (null: nothing). Deallocates: call it at unload time.
///
/// # Safety
/// `comp` is null or a handle from [`vmc_comp_new`] not yet freed; it is not used afterwards.
#[no_mangle]
pub unsafe extern "C" fn vmc_comp_free(comp: *mut RtComp) {
    if !comp.is_null() {
        // SAFETY: a live handle made by `Box::into_raw` in `vmc_comp_new_err`.
        drop(unsafe { Box::from_raw(comp) });
    }
}
