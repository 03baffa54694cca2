//! The probe moves of a `run`, each answered on the twin as the controller latched it: the
//! rows of `probes.csv` and the report's probe table.
//!
//! The values are what the program reads: #5061…#5063 (the latched point in the program's
//! work coordinates and unit of length at the probe) and #5070 (1 tripped, 0 not); beside them
//! the latched point in machine coordinates (mm), the solid touched and the twin's time.

use std::fmt::Write as _;

use vmc_gcode::interp::{LengthUnit, ProbeOutcome, ProbeParams, ProbeRequest};
use vmc_machine::touch_probe::{ProbeMove, ProbeStation};

/// One probe move of the run.
#[derive(Debug, Clone, PartialEq)]
pub struct ProbeRow {
    /// Line of the probe block.
    pub line: usize,
    /// `G38.2` … `G38.5`.
    pub kind: &'static str,
    /// #5070.
    pub tripped: bool,
    /// #5061…#5063, program units.
    pub work: [f64; 3],
    /// The program's unit of length at the probe.
    pub unit: LengthUnit,
    /// The latched point (the target when nothing tripped), machine coordinates, mm.
    pub machine_mm: [f64; 3],
    /// The solid whose contact changed the probe's state (empty if none).
    pub touched: String,
    /// Twin time at the probe, s.
    pub time_s: f64,
}

impl ProbeRow {
    /// The row of `request` answered by `answer` (solid names from `station`), the program
    /// reading `params` in `unit`, at twin time `time_s`.
    pub fn new(
        request: &ProbeRequest,
        answer: &ProbeMove,
        params: ProbeParams,
        unit: LengthUnit,
        station: &ProbeStation,
        time_s: f64,
    ) -> Self {
        let machine_mm = match answer.outcome {
            ProbeOutcome::Tripped { trip_mm, .. } => trip_mm,
            ProbeOutcome::AlreadyInState => request.start_mm,
            ProbeOutcome::NoContact | ProbeOutcome::Standalone => request.end_mm,
        };
        Self {
            line: request.line,
            kind: request.kind.code(),
            tripped: params[9] != 0.0,
            work: [params[0], params[1], params[2]],
            unit,
            machine_mm,
            touched: answer
                .touched
                .map(|i| station.solid_name(i).to_string())
                .unwrap_or_default(),
            time_s,
        }
    }
}

/// The run's probe moves, in order.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ProbeLog {
    /// The rows.
    pub rows: Vec<ProbeRow>,
}

/// The CSV header of `probes.csv`.
pub const PROBES_CSV_HEADER: &str =
    "probe,line,kind,tripped,x,y,z,unit,machine_x_mm,machine_y_mm,machine_z_mm,touched,time_s";

impl ProbeLog {
    /// `probes.csv`: one row per probe move (see the module documentation); names quoted.
    pub fn csv(&self) -> String {
        let mut s = String::from(PROBES_CSV_HEADER);
        s.push('\n');
        for (i, r) in self.rows.iter().enumerate() {
            let _ = writeln!(
                s,
                "{},{},{},{},{:.6},{:.6},{:.6},{},{:.6},{:.6},{:.6},\"{}\",{:.3}",
                i,
                r.line,
                r.kind,
                u8::from(r.tripped),
                r.work[0],
                r.work[1],
                r.work[2],
                r.unit.symbol(),
                r.machine_mm[0],
                r.machine_mm[1],
                r.machine_mm[2],
                r.touched.replace('"', "\"\""),
                r.time_s
            );
        }
        s
    }

    /// The report's probe table (nothing without probe moves).
    pub fn report(&self) -> String {
        if self.rows.is_empty() {
            return String::new();
        }
        let mut s = format!(
            "probe moves on the twin ({}): #5061…#5063 latched, work coordinates, program units; #5070 tripped\n",
            self.rows.len()
        );
        let _ = writeln!(
            s,
            "{:>5} {:>6} {:>6} {:>7} {:>12} {:>12} {:>12}  touched",
            "probe", "line", "kind", "tripped", "X", "Y", "Z"
        );
        for (i, r) in self.rows.iter().enumerate() {
            let _ = writeln!(
                s,
                "{:>5} {:>6} {:>6} {:>7} {:>12.4} {:>12.4} {:>12.4}  {}",
                i,
                r.line,
                r.kind,
                u8::from(r.tripped),
                r.work[0],
                r.work[1],
                r.work[2],
                if r.touched.is_empty() {
                    "-"
                } else {
                    &r.touched
                }
            );
        }
        s
    }
}
