//! How a program was placed on the machine, in one line for the reports of `run` and `check`:
//! the setup file (if any) and the work offsets in use (G54 always, the others when not 0),
//! machine coordinates, mm.

use vmc_machine::setup::{Placement, WORK_OFFSET_NAMES};

/// `placement: setup part.setup.toml; G54 X250 Y180 Z-320 mm (machine coordinates)`.
pub fn placement_line(p: &Placement) -> String {
    let source = match &p.setup_file {
        Some(f) => format!("setup {}", f.display()),
        None => "no setup file".to_string(),
    };
    let offsets: Vec<String> = p
        .work_offsets_mm
        .iter()
        .enumerate()
        .filter(|(i, o)| *i == 0 || o.iter().any(|v| *v != 0.0))
        .map(|(i, o)| {
            let n = |v: f64| vmc_gcode::interp::LengthUnit::Mm.number_mm(v);
            format!(
                "{} X{} Y{} Z{}",
                WORK_OFFSET_NAMES[i],
                n(o[0]),
                n(o[1]),
                n(o[2])
            )
        })
        .collect();
    format!(
        "placement: {source}; {} mm (machine coordinates)",
        offsets.join(", ")
    )
}
