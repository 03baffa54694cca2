//! The probe moves of a `run`, each answered on the twin as the controller latched it: the
//! rows of `probes.csv` and the report's probe table.
//!
//! The values are what the program reads: #5061…#5063 (the latched point in the program's
//! work coordinates and unit of length at the probe) and #5070 (1 tripped, 0 not); beside them
//! the latched point in machine coordinates (mm), the solid touched and the twin's time; for a
//! touch of a reference artefact, what the controller measured from it
//! ([`super::probe_update`]). `probes.csv` is written as the rows come; the rows are held for
//! the report's table and `summary.json` (one per probe move). The probing cost is the machine
//! time of the program's probe moves (their planned duration at the probe feed).

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::PathBuf;

use serde::Serialize;

use super::probe_update::ReferenceTouch;
use crate::files::AtomicFile;

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
    /// The programmed target, machine coordinates, mm.
    pub target_mm: [f64; 3],
    /// The solid whose contact changed the probe's state (empty if none).
    pub touched: String,
    /// Twin time at the probe, s.
    pub time_s: f64,
    /// What the controller measured, for a touch of a reference artefact.
    pub reference: Option<ReferenceTouch>,
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
            target_mm: request.end_mm,
            touched: answer
                .touched
                .map(|i| station.solid_name(i).to_string())
                .unwrap_or_default(),
            time_s,
            reference: None,
        }
    }
}

/// The run's probe moves, in order, and `probes.csv` as they come.
#[derive(Default)]
pub struct ProbeLog {
    /// The rows.
    pub rows: Vec<ProbeRow>,
    /// Machine time of the probe moves, s.
    probe_time_s: f64,
    /// Whether reference touches update the compensator's drift.
    updates: bool,
    /// `probes.csv`: where, whether it may replace a file; opened at the first row.
    csv_path: Option<(PathBuf, bool)>,
    csv: Option<AtomicFile>,
}

/// The CSV header of `probes.csv`.
pub const PROBES_CSV_HEADER: &str =
    "probe,line,kind,tripped,x,y,z,unit,machine_x_mm,machine_y_mm,machine_z_mm,touched,time_s,deviation_um";

impl ProbeLog {
    /// A log writing `probes.csv` to `path` (if any; replacing a file if `force`) once the
    /// first probe move comes.
    pub fn new(path: Option<PathBuf>, force: bool) -> Self {
        Self {
            csv_path: path.map(|p| (p, force)),
            ..Self::default()
        }
    }

    /// Notes whether reference touches update the compensator's drift.
    pub fn set_updates(&mut self, on: bool) {
        self.updates = on;
    }

    /// Adds `s` of probe moves' machine time.
    pub fn add_probe_time_s(&mut self, s: f64) {
        self.probe_time_s += s;
    }

    /// Adds a probe move (with the controller's measurement of a reference touch) and writes
    /// its `probes.csv` row.
    ///
    /// # Errors
    /// `probes.csv` that may not be written.
    pub fn push(
        &mut self,
        mut row: ProbeRow,
        reference: Option<ReferenceTouch>,
    ) -> anyhow::Result<()> {
        row.reference = reference;
        if self.csv.is_none() {
            if let Some((path, force)) = &self.csv_path {
                let mut f = AtomicFile::create(path, *force)?;
                writeln!(f, "{PROBES_CSV_HEADER}")?;
                self.csv = Some(f);
            }
        }
        if let Some(f) = self.csv.as_mut() {
            f.write_all(csv_row(self.rows.len(), &row).as_bytes())?;
        }
        self.rows.push(row);
        Ok(())
    }

    /// Names `probes.csv` (if written); its path.
    ///
    /// # Errors
    /// The file cannot be completed.
    pub fn finish_csv(&mut self) -> anyhow::Result<Option<PathBuf>> {
        match self.csv.take() {
            Some(f) => {
                let path = f.path().to_path_buf();
                f.finish()?;
                Ok(Some(path))
            }
            None => Ok(None),
        }
    }

    /// The probe results and the probing cost for `summary.json` (None without probe moves);
    /// `program_s` is the measured program's machine time, s.
    pub fn summary(&self, program_s: f64) -> Option<ProbingSummary<'_>> {
        (!self.rows.is_empty()).then(|| ProbingSummary {
            probe_moves: self.rows.len(),
            probe_time_s: self.probe_time_s,
            program_time_s: program_s,
            cost_min_per_h: self.cost_min_per_h(program_s),
            drift_updates: self.updates,
            reference_touches: self.rows.iter().filter(|r| r.reference.is_some()).count(),
            probes: self.rows.iter().map(ProbeJson::of).collect(),
        })
    }

    fn cost_min_per_h(&self, program_s: f64) -> f64 {
        if program_s > 0.0 {
            self.probe_time_s / 60.0 / (program_s / 3600.0)
        } else {
            0.0
        }
    }
}

/// The `probing` object of `summary.json` (docs/file-formats.md).
#[derive(Debug, Serialize)]
pub struct ProbingSummary<'a> {
    /// Probe moves run.
    pub probe_moves: usize,
    /// Their machine time, s.
    pub probe_time_s: f64,
    /// The measured program's machine time, s.
    pub program_time_s: f64,
    /// Machine minutes of probing per hour of the program.
    pub cost_min_per_h: f64,
    /// Whether reference touches updated the compensator's drift.
    pub drift_updates: bool,
    /// Touches of reference artefacts measured.
    pub reference_touches: usize,
    /// Each probe move.
    pub probes: Vec<ProbeJson<'a>>,
}

/// One probe move in `summary.json`.
#[derive(Debug, Serialize)]
pub struct ProbeJson<'a> {
    /// Line of the probe block.
    pub line: usize,
    /// `G38.2` … `G38.5`.
    pub kind: &'static str,
    /// The programmed target, machine coordinates, mm.
    pub target_mm: [f64; 3],
    /// Whether the probe tripped (#5070).
    pub tripped: bool,
    /// The latched point (the target when nothing tripped), machine coordinates, mm.
    pub trip_mm: [f64; 3],
    /// The solid touched (empty if none).
    pub touched: &'a str,
    /// Twin time at the probe, s.
    pub time_s: f64,
    /// The controller's measurement of a reference touch.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reference: Option<&'a ReferenceTouch>,
}

impl<'a> ProbeJson<'a> {
    fn of(r: &'a ProbeRow) -> Self {
        ProbeJson {
            line: r.line,
            kind: r.kind,
            target_mm: r.target_mm,
            tripped: r.tripped,
            trip_mm: r.machine_mm,
            touched: &r.touched,
            time_s: r.time_s,
            reference: r.reference.as_ref(),
        }
    }
}

/// One `probes.csv` row of probe move `i` (names quoted).
fn csv_row(i: usize, r: &ProbeRow) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{},{},{},{},{:.6},{:.6},{:.6},{},{:.6},{:.6},{:.6},\"{}\",{:.3},{}",
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
        r.time_s,
        r.reference
            .as_ref()
            .map_or(String::new(), |t| format!("{:.3}", t.deviation_um))
    );
    s
}

impl ProbeLog {
    /// The report's probe table and the probing cost, `program_s` the measured program's
    /// machine time (nothing without probe moves).
    pub fn report(&self, program_s: f64) -> String {
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
        let mut last_drift = None;
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
            if let Some(t) = &r.reference {
                let _ = write!(
                    s,
                    "{:>39}reference along {}: probed − expected {:+.2} µm",
                    "", t.axis, t.deviation_um
                );
                if let Some(d) = t.drift_after_um {
                    let _ = write!(
                        s,
                        "; drift {} X {:+.2} Y {:+.2} Z {:+.2} µm",
                        if t.applied { "now" } else { "(not applied)" },
                        d[0],
                        d[1],
                        d[2]
                    );
                    last_drift = Some(d);
                }
                s.push('\n');
            }
        }
        let _ = writeln!(
            s,
            "probing cost: {:.1} s of probe moves in {:.1} min of program ({:.2} machine min per hour)",
            self.probe_time_s,
            program_s / 60.0,
            self.cost_min_per_h(program_s)
        );
        if self.rows.iter().any(|r| r.reference.is_some()) {
            let _ = writeln!(
                s,
                "drift updates from reference touches: {}{}",
                if self.updates {
                    "on"
                } else {
                    "off (--probe-update off, or no --compensate)"
                },
                last_drift
                    .filter(|_| self.updates)
                    .map_or(String::new(), |d| format!(
                        "; drift at the end X {:+.2} Y {:+.2} Z {:+.2} µm",
                        d[0], d[1], d[2]
                    ))
            );
        }
        s
    }
}
