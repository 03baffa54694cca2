//! The files a user takes to a controller, from a [`TableSet`]: LinuxCNC joint tables with
//! their INI lines, a Siemens CEC program, and a plain-text report of what the tables lose.
//!
//! Nothing here touches the file system: each function returns the files' names and
//! contents ([`OutputFile`]); the application writes them.

use thiserror::Error;

use crate::cec::{write_cec_program, CecDirection, CecError, CecProgram, CecTable};
use crate::linuxcnc::{ini_lines, CompFileError, CompFileType, CompPoint, JointCompTable};
use crate::number::is_plain_name;
use crate::sample::{OwnAxisTable, TableSet, AXIS_NAMES};

/// Name of the Siemens program file (the program `%_N_NC_CEC_INI`).
pub const CEC_FILE_NAME: &str = "NC_CEC.INI";
/// Name of the file holding the INI lines for LinuxCNC.
pub const LINUXCNC_INI_FILE_NAME: &str = "comp-tables.ini";
/// Most joints a LinuxCNC configuration has (its motion controller's limit).
pub const MAX_LINUXCNC_JOINTS: usize = 16;

/// A file to write: its name (no directory) and contents.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct OutputFile {
    /// File name.
    pub name: String,
    /// Text.
    pub contents: String,
}

/// Where the tables come from, written into the files' comments (INI, CEC) and the report.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Provenance {
    /// The model (e.g. its file name and kind).
    pub model: String,
    /// The thermal state (e.g. the readings, or the warm-up program and its duration).
    pub thermal_state: String,
}

/// Options of the LinuxCNC export.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LinuxCncExport {
    /// `COMP_FILE_TYPE` (default: 1, trims: the values read as what they do).
    pub file_type: CompFileType,
    /// Joint number of X, Y, Z (default: 0, 1, 2, a trivkins configuration).
    pub joints: [usize; 3],
}

impl Default for LinuxCncExport {
    fn default() -> Self {
        Self {
            file_type: CompFileType::Trims,
            joints: [0, 1, 2],
        }
    }
}

/// Options of the Siemens CEC export.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CecExport {
    /// Machine axis names of X, Y, Z (default: `AX1`, `AX2`, `AX3`, as in the manual's
    /// example).
    pub axis_names: [String; 3],
    /// The channel of `CHANDATA` (default: 1).
    pub channel: u32,
    /// Also write the cross tables (default: true; false writes the own-axis tables only, e.g.
    /// for a controller configured with few tables).
    pub cross_tables: bool,
}

impl Default for CecExport {
    fn default() -> Self {
        Self {
            axis_names: ["AX1".into(), "AX2".into(), "AX3".into()],
            channel: 1,
            cross_tables: true,
        }
    }
}

/// Problems turning a table set into files.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum ExportError {
    /// A LinuxCNC table or INI value.
    #[error("LinuxCNC table: {0}")]
    Comp(#[from] CompFileError),
    /// A CEC table or program.
    #[error("{0}")]
    Cec(#[from] CecError),
    /// An option that cannot be used.
    #[error("invalid export option `{field}`: {reason}")]
    BadOption {
        /// The option.
        field: &'static str,
        /// What is wrong.
        reason: String,
    },
}

/// The joint table of each axis X, Y, Z (own-axis corrections as trims).
///
/// # Errors
/// A table LinuxCNC would not load (a correction beyond 1 mm, see
/// [`crate::linuxcnc::MAX_TRIM_MM`]).
pub fn joint_tables(set: &TableSet) -> Result<Vec<JointCompTable>, CompFileError> {
    set.own
        .iter()
        .map(|t| {
            let points = t
                .grid
                .positions_mm()
                .into_iter()
                .zip(t.forward_mm.iter().zip(&t.reverse_mm))
                .map(|(nominal_mm, (f, r))| CompPoint {
                    nominal_mm,
                    forward_trim_mm: *f,
                    reverse_trim_mm: *r,
                })
                .collect();
            JointCompTable::new(points)
        })
        .collect()
}

/// The LinuxCNC files: `joint<n>-<axis>.comp` per axis and [`LINUXCNC_INI_FILE_NAME`] with
/// the INI lines that load them, under comments stating the model, the thermal state and
/// what the joint tables leave of the model's error.
///
/// # Errors
/// Repeated joint numbers or one beyond [`MAX_LINUXCNC_JOINTS`]; a table LinuxCNC would not
/// load.
pub fn linuxcnc_files(
    set: &TableSet,
    opts: &LinuxCncExport,
    provenance: &Provenance,
) -> Result<Vec<OutputFile>, ExportError> {
    let j = opts.joints;
    if j.iter().any(|&n| n >= MAX_LINUXCNC_JOINTS) || j[0] == j[1] || j[0] == j[2] || j[1] == j[2] {
        return Err(ExportError::BadOption {
            field: "joints",
            reason: format!("{j:?} (three different joint numbers below {MAX_LINUXCNC_JOINTS})"),
        });
    }
    let mut files = Vec::with_capacity(4);
    let v = &set.volume;
    let mut ini = comment_block(
        "# ",
        &[
            format!(
                "vmc-twin per-joint compensation tables (COMP_FILE_TYPE {}: {})",
                opts.file_type.number(),
                match opts.file_type {
                    CompFileType::Trims => "trims in mm added to the commanded joint position",
                    CompFileType::MeasuredPositions =>
                        "positions reached, mm; trim = nominal - value",
                }
            ),
            format!("model: {}", provenance.model),
            format!("thermal state: {}", provenance.thermal_state),
            format!(
                "axes not sampled held at {}",
                position_text(set.reference_mm)
            ),
            format!(
                "over the volume the model's error reaches {} um (max |E| X/Y/Z); these tables \
                 leave {} um: a joint table carries its axis's own error only",
                triple(v.model_max_abs_um),
                triple(v.own_axis_only.max_abs_um)
            ),
            "add each section's two lines to that joint's section of the machine's INI file; \
             keep BACKLASH at 0: the reverse column holds the reversal"
                .into(),
        ],
    );
    for (k, table) in joint_tables(set)?.iter().enumerate() {
        let name = format!("joint{}-{}.comp", j[k], AXIS_NAMES[k].to_ascii_lowercase());
        ini.push_str(&ini_lines(j[k], &name, opts.file_type)?);
        files.push(OutputFile {
            name,
            contents: table.to_comp_file(opts.file_type),
        });
    }
    files.push(OutputFile {
        name: LINUXCNC_INI_FILE_NAME.into(),
        contents: ini,
    });
    Ok(files)
}

/// The CEC program of the table set: per output axis X, Y, Z its own-axis table (two
/// direction-dependent tables when the model has a reversal on that axis, one for both
/// directions otherwise), then its cross tables along the other axes; header comments name
/// every table.
///
/// # Errors
/// Axis names that are not plain machine axis names or are repeated; channel 0.
pub fn cec_program(
    set: &TableSet,
    opts: &CecExport,
    provenance: &Provenance,
) -> Result<CecProgram, ExportError> {
    let names = &opts.axis_names;
    if names.iter().any(|n| !is_plain_name(n))
        || names[0] == names[1]
        || names[0] == names[2]
        || names[1] == names[2]
    {
        return Err(ExportError::BadOption {
            field: "axis_names",
            reason: format!("{names:?} (three different machine axis names such as AX1)"),
        });
    }
    let mut tables = Vec::new();
    for k in 0..3 {
        tables.extend(own_cec_tables(&set.own[k], &names[k])?);
        if opts.cross_tables {
            for t in set.cross.iter().filter(|t| t.output_axis == k) {
                let g = t.grid;
                let what = format!(
                    "{} along {}, both directions, zero at the reference",
                    AXIS_NAMES[k], AXIS_NAMES[t.input_axis]
                );
                let input = &names[t.input_axis];
                let table = CecTable::new(
                    input,
                    &names[k],
                    g.start_mm,
                    g.step_mm,
                    &t.correction_mm,
                    CecDirection::Both,
                )?;
                tables.push((table, what));
            }
        }
    }
    let v = &set.volume;
    let residual = if opts.cross_tables {
        v.own_and_cross.max_abs_um
    } else {
        v.own_axis_only.max_abs_um
    };
    let mut comment_lines = vec![
        "vmc-twin interpolatory compensation tables: compensation values in mm".to_string(),
        format!("model: {}", ascii(&provenance.model)),
        format!("thermal state: {}", ascii(&provenance.thermal_state)),
        format!(
            "axes not sampled held at {}",
            position_text(set.reference_mm)
        ),
        format!(
            "model max |E| X/Y/Z {} um; left by these tables {} um",
            triple(v.model_max_abs_um),
            triple(residual)
        ),
    ];
    let (tables, described): (Vec<CecTable>, Vec<String>) = tables.into_iter().unzip();
    comment_lines.extend(
        described
            .iter()
            .enumerate()
            .map(|(t, what)| format!("table {t}: {what}")),
    );
    Ok(CecProgram {
        channel: opts.channel,
        comment_lines,
        tables,
    })
}

/// The CEC table(s) of an axis's own error, with their descriptions: one for both directions
/// when the reversal is zero, else one per direction (positive first, as in the manual's
/// direction-dependent example).
fn own_cec_tables(own: &OwnAxisTable, name: &str) -> Result<Vec<(CecTable, String)>, CecError> {
    let g = own.grid;
    let axis = AXIS_NAMES[own.axis];
    let table = |values: &[f64], dir| CecTable::new(name, name, g.start_mm, g.step_mm, values, dir);
    Ok(if own.forward_mm == own.reverse_mm {
        vec![(
            table(&own.forward_mm, CecDirection::Both)?,
            format!("{axis} along {axis}, both directions"),
        )]
    } else {
        vec![
            (
                table(&own.forward_mm, CecDirection::Positive)?,
                format!("{axis} along {axis}, positive direction"),
            ),
            (
                table(&own.reverse_mm, CecDirection::Negative)?,
                format!("{axis} along {axis}, negative direction"),
            ),
        ]
    })
}

/// The CEC program as the file [`CEC_FILE_NAME`].
///
/// # Errors
/// As [`cec_program`].
pub fn cec_files(
    set: &TableSet,
    opts: &CecExport,
    provenance: &Provenance,
) -> Result<Vec<OutputFile>, ExportError> {
    let program = cec_program(set, opts, provenance)?;
    Ok(vec![OutputFile {
        name: CEC_FILE_NAME.into(),
        contents: write_cec_program(&program)?,
    }])
}

/// A plain-text report: every table's grid, its range of corrections and its interpolation
/// check, and the volume check.
pub fn report_text(set: &TableSet, provenance: &Provenance) -> String {
    let mut s = format!(
        "model: {}\nthermal state: {}\naxes not sampled held at {}\nreversal (negative minus \
         positive approach) X/Y/Z: {} um\n\ntable            points  step mm  from … to mm        \
         correction um         interpolation um (at mm)\n",
        clean(&provenance.model),
        clean(&provenance.thermal_state),
        position_text(set.reference_mm),
        triple(set.reversal_shift_mm.map(|r| r * 1e3)),
    );
    let mut row = |label: String,
                   g: crate::sample::Grid,
                   values: &[f64],
                   check: crate::sample::InterpolationCheck| {
        let lo = values.iter().copied().fold(f64::INFINITY, f64::min) * 1e3;
        let hi = values.iter().copied().fold(f64::NEG_INFINITY, f64::max) * 1e3;
        s.push_str(&format!(
            "{label:<16} {:>6} {:>8.3}  {:>8.3} … {:<8.3} {:>8.3} … {:<8.3}  {:.4} ({:.3})\n",
            g.points,
            g.step_mm,
            g.start_mm,
            g.end_mm(),
            lo,
            hi,
            check.max_abs_um,
            check.at_mm
        ));
    };
    for t in &set.own {
        let a = AXIS_NAMES[t.axis];
        row(format!("{a} along {a}"), t.grid, &t.forward_mm, t.check);
    }
    for t in &set.cross {
        row(
            format!(
                "{} along {}",
                AXIS_NAMES[t.output_axis], AXIS_NAMES[t.input_axis]
            ),
            t.grid,
            &t.correction_mm,
            t.check,
        );
    }
    let v = &set.volume;
    s.push_str(&format!(
        "\nover the volume ({} points, positive approach), X/Y/Z, um:\n  model max |E| {}, rms {}\n  \
         left by the own-axis tables (LinuxCNC) max {}, rms {}\n  left by own-axis and cross \
         tables (CEC) max {}, rms {}\n",
        v.points,
        triple(v.model_max_abs_um),
        triple(v.model_rms_um),
        triple(v.own_axis_only.max_abs_um),
        triple(v.own_axis_only.rms_um),
        triple(v.own_and_cross.max_abs_um),
        triple(v.own_and_cross.rms_um),
    ));
    s
}

fn triple(v: [f64; 3]) -> String {
    format!("{:.3} / {:.3} / {:.3}", v[0], v[1], v[2])
}

fn position_text(q: [f64; 3]) -> String {
    format!("X {:.3}, Y {:.3}, Z {:.3} mm", q[0], q[1], q[2])
}

/// A comment-safe copy of `text`: control characters (line breaks) become spaces.
fn clean(text: &str) -> String {
    text.chars()
        .map(|c| if c.is_control() { ' ' } else { c })
        .collect()
}

/// Longest text put into a CEC comment line, characters (NC program lines are limited; a
/// provenance string can be long).
const MAX_CEC_COMMENT_CHARS: usize = 160;

/// An ASCII copy of `text` for a controller's file: `°` → `deg`, `µ` → `u`, other non-ASCII
/// characters and control characters → `?` and space, at most [`MAX_CEC_COMMENT_CHARS`]
/// characters (cut with `...`).
fn ascii(text: &str) -> String {
    let s: String = clean(text)
        .chars()
        .map(|c| match c {
            '°' => "deg".to_string(),
            'µ' | 'μ' => "u".to_string(),
            c if c.is_ascii() => c.to_string(),
            _ => "?".to_string(),
        })
        .collect();
    if s.len() > MAX_CEC_COMMENT_CHARS {
        format!("{}...", &s[..MAX_CEC_COMMENT_CHARS - 3])
    } else {
        s
    }
}

fn comment_block(prefix: &str, lines: &[String]) -> String {
    lines
        .iter()
        .map(|l| format!("{prefix}{}\n", clean(l)))
        .collect()
}

#[cfg(test)]
mod tests;
