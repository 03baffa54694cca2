//! The measured program of `vmc-twin run`, streamed: it is interpreted, planned and checked
//! piece by piece once up front ([`scan`]: its length, whether it dwells, where it measures),
//! then again as it runs ([`run_measured`]), each piece simulated as soon as it is planned,
//! with one simulation clock (the twin's) and one point index across the pieces. The points
//! go to the run log as they are taken ([`crate::report::RunLog`]); the terminal table waits
//! in an unnamed temporary file until the summary is known ([`Spill`]).
//!
//! What is still held for the whole run: the program's parsed text (O-word loops and
//! subroutines jump back in it) and, with a recording of a program with dwells, the dwell
//! points (to find the diagonal they lie on). Pieces end with a partial thermal step, as the
//! warm-ups' do (see `vmc_machine::program::PlanPieces`); a program of at most
//! `MOVES_PER_PIECE` moves is one piece, simulated exactly as a whole plan.

use std::io::{BufRead, Seek, Write};

use anyhow::{Context, Result};

use vmc_machine::motion::SegmentKind;
use vmc_machine::program::{self, PlanStream};
use vmc_machine::sensors::SensorReadings;
use vmc_machine::sim::{self, Observer, PointRecord, RunStart, SimConfig, SimEvent};
use vmc_machine::twin::Twin;

use super::probe_update::{DriftCompensator, DriftUpdates};

/// The measured program and what it runs on.
pub(super) struct Measured<'a> {
    /// The program file.
    pub program: &'a std::path::Path,
    /// The machine.
    pub machine: &'a vmc_machine::machine::MachineSpec,
    /// The tool table.
    pub tools: &'a vmc_machine::tools::ToolTable,
    /// Where the program sits.
    pub placement: &'a vmc_machine::setup::Placement,
    /// Seed of the probe's trip scatter.
    pub seed: u64,
    /// Update the compensator's drift from touches of reference artefacts.
    pub probe_update: bool,
}

/// The probe station of the program's G38 moves (the setup's probe and what it can touch).
fn station(cfg: &Measured<'_>) -> Result<vmc_machine::touch_probe::ProbeStation> {
    Ok(vmc_machine::touch_probe::ProbeStation::of_placement(
        cfg.placement,
        cfg.machine,
        &[],
        cfg.seed,
    )?)
}

/// What the measured program is, from one pass over its pieces.
pub(super) struct ProgramScan {
    /// Where it starts (where the warm-ups end), machine coordinates, mm.
    pub start_mm: [f64; 3],
    /// Its duration, s.
    pub duration_s: f64,
    /// Whether it has a G4 dwell.
    pub has_dwell: bool,
    /// Its dwell points (only when asked for: a recording's diagonal), mm.
    pub dwell_points_mm: Vec<[f64; 3]>,
    /// The text's hash, to notice a file changed between the scan and the run.
    fingerprint: u64,
    /// Per piece, the hash of the lines and kinds of its moves: the run must take the path the
    /// scan took (a program branching on probed values may not).
    path: Vec<u64>,
}

/// The hash of the lines and kinds of `piece`'s moves (not their positions, which differ by
/// the probes' µm between the scan and the run).
fn path_hash(piece: &vmc_machine::motion::Plan) -> u64 {
    use std::hash::{Hash, Hasher};
    let mut h = std::collections::hash_map::DefaultHasher::new();
    for s in piece.segments() {
        (s.line, std::mem::discriminant(&s.kind), s.probe).hash(&mut h);
    }
    h.finish()
}

/// The program's pieces, each planned and checked and then dropped; `dwell_points` keeps the
/// dwell points.
pub(super) fn scan(
    cfg: &Measured<'_>,
    start_mm: [f64; 3],
    dwell_points: bool,
) -> Result<ProgramScan> {
    // Probe moves end where the nominal machine's probe trips.
    let station = station(cfg)?;
    let mut stream = stream(cfg, start_mm)?;
    let mut scan = ProgramScan {
        start_mm,
        duration_s: 0.0,
        has_dwell: false,
        dwell_points_mm: Vec::new(),
        fingerprint: stream.fingerprint(),
        path: Vec::new(),
    };
    while let Some(piece) = stream.next() {
        let piece = piece?;
        if let Some(request) = stream.pending_probe() {
            stream.answer_probe(station.nominal(&request).outcome)?;
        }
        scan.duration_s += piece.duration_s();
        scan.path.push(path_hash(&piece));
        for s in piece.segments() {
            if matches!(s.kind, SegmentKind::Dwell) {
                scan.has_dwell = true;
                if dwell_points {
                    scan.dwell_points_mm.push(s.end_mm);
                }
            }
        }
    }
    Ok(scan)
}

fn stream<'a>(cfg: &Measured<'a>, start_mm: [f64; 3]) -> Result<PlanStream<'a>> {
    Ok(PlanStream::load(
        cfg.program,
        cfg.machine,
        start_mm,
        cfg.tools,
        cfg.placement,
        program::MOVES_PER_PIECE,
    )?
    .answering_probes())
}

/// Runs the measured program on `twin` piece by piece, telling `obs` (the run log, the
/// recorder, the progress) its start and every point, numbered across the pieces.
pub(super) fn run_measured(
    cfg: &Measured<'_>,
    scan: &ProgramScan,
    twin: &mut Twin,
    sim_cfg: &SimConfig,
    mut controller: Option<&mut DriftCompensator>,
    obs: &mut dyn Observer,
    probes: &mut super::probe_log::ProbeLog,
) -> Result<()> {
    let name = cfg.program.display().to_string();
    let mut station = station(cfg)?;
    let updates = DriftUpdates::new(&cfg.placement.artefacts, *station.probe(), cfg.probe_update);
    probes.set_updates(cfg.probe_update && controller.is_some() && updates.any_reference());
    let mut stream = stream(cfg, scan.start_mm)?;
    anyhow::ensure!(
        stream.fingerprint() == scan.fingerprint,
        "{name}: the program file changed while the run was starting; run again"
    );
    obs.on_run_start(&RunStart {
        label: name.clone(),
        time_s: twin.time_s(),
        duration_s: scan.duration_s,
        measured: true,
    });
    let mut numbered = Numbered {
        inner: obs,
        offset: 0,
        seen: 0,
    };
    let mut last_probe_line = None;
    let mut pieces = 0usize;
    while let Some(piece) = stream.next() {
        let piece = piece?;
        if scan.path.get(pieces) != Some(&path_hash(&piece)) {
            return Err(other_path(&name, last_probe_line));
        }
        pieces += 1;
        probes.add_probe_time_s(
            piece
                .segments()
                .iter()
                .filter(|s| s.probe)
                .map(|s| s.duration_s)
                .sum(),
        );
        let ctrl = controller
            .as_deref_mut()
            .map(|c| c as &mut dyn sim::Controller);
        sim::execute(twin, &piece, sim_cfg, ctrl, &mut numbered).with_context(|| name.clone())?;
        numbered.offset = numbered.seen;
        // A probe move: the twin moves the probe through its drifted geometry now.
        if let Some(request) = stream.pending_probe() {
            let answer = station.on_twin(twin, &request)?;
            // The controller evaluates a reference touch when it latches, before the moves
            // after it are planned and compensated.
            let reference = updates.on_probe(
                controller.as_deref_mut(),
                &station,
                &request,
                &answer,
                twin.time_s(),
            );
            let (params, unit) = stream.answer_probe(answer.outcome)?;
            let row = super::probe_log::ProbeRow::new(
                &request,
                &answer,
                params,
                unit,
                &station,
                twin.time_s(),
            );
            probes.push(row, reference)?;
            last_probe_line = Some(request.line);
        }
    }
    if pieces != scan.path.len() {
        return Err(other_path(&name, last_probe_line));
    }
    Ok(())
}

/// The error of a run that left the path its first pass took.
fn other_path(name: &str, last_probe_line: Option<usize>) -> anyhow::Error {
    anyhow::anyhow!(
        "{name}: the program took another path on the twin than in its first pass on the \
         nominal machine{} (it branches on probed values, which differ by the machine's µm); \
         such a program cannot be run: its sampling and size are decided by the first pass",
        last_probe_line.map_or(String::new(), |l| format!(
            " after the probe move at line {l}"
        ))
    )
}

/// Numbers the points of successive pieces on from the previous pieces' (each piece's
/// execution counts from 0).
struct Numbered<'o> {
    inner: &'o mut dyn Observer,
    offset: usize,
    seen: usize,
}

impl Observer for Numbered<'_> {
    fn on_run_start(&mut self, start: &RunStart) {
        self.inner.on_run_start(start);
    }
    fn on_point(&mut self, point: &PointRecord, readings: &SensorReadings) {
        let mut p = point.clone();
        p.index += self.offset;
        self.seen = p.index + 1;
        self.inner.on_point(&p, readings);
    }
    fn on_thermal_step(&mut self, time_s: f64, readings: &SensorReadings) {
        self.inner.on_thermal_step(time_s, readings);
    }
    fn on_node_temps(&mut self, time_s: f64, node_temps_degc: &[f64]) {
        self.inner.on_node_temps(time_s, node_temps_degc);
    }
    fn motion_sample_interval_s(&self) -> Option<f64> {
        self.inner.motion_sample_interval_s()
    }
    fn on_motion_sample(&mut self, time_s: f64, axis_mm: [f64; 3]) {
        self.inner.on_motion_sample(time_s, axis_mm);
    }
    fn on_event(&mut self, event: &SimEvent) {
        self.inner.on_event(event);
    }
}

/// Where a measured run's rows go as the points come: the terminal table (spilled until the
/// report is printed) and, with `--out`, `samples.csv` (a temporary file named when the run
/// has succeeded, see [`crate::files::AtomicFile`]).
pub(super) struct Rows {
    /// The terminal table's rows.
    pub table: Spill,
    /// `samples.csv` being written.
    pub csv: Option<crate::files::AtomicFile>,
    /// The paths of `samples.csv` and `summary.json`, if written.
    pub out_files: Option<(std::path::PathBuf, std::path::PathBuf)>,
}

impl Rows {
    /// Opens the table's temporary file and `samples.csv`'s (if `out_files`).
    ///
    /// # Errors
    /// A temporary file that cannot be created, `samples.csv` that may not be written.
    pub fn new(
        out_files: Option<(std::path::PathBuf, std::path::PathBuf)>,
        force: bool,
    ) -> Result<Self> {
        let csv = match &out_files {
            Some((csv, _)) => Some(crate::files::AtomicFile::create(csv, force)?),
            None => None,
        };
        Ok(Self {
            table: Spill::new()?,
            csv,
            out_files,
        })
    }

    /// A run log writing into these rows, with the compensated columns if `compensated`.
    pub fn log(&mut self, compensated: bool) -> crate::report::RunLog<'_> {
        crate::report::RunLog::new(
            compensated,
            self.table.writer(),
            self.csv.as_mut().map(|f| f as &mut dyn Write),
        )
    }
}

/// Rows of the terminal table written as the points come, read back when the report is
/// printed: an unnamed temporary file (removed from its folder as soon as it is opened, so
/// nothing is left behind whatever happens to the run).
pub(super) struct Spill {
    file: std::io::BufWriter<std::fs::File>,
}

/// Most rows of the point table a recording's report holds (the rest are in `samples.csv`).
pub(super) const RECORDED_TABLE_ROWS: usize = 2000;

impl Spill {
    /// Opens the temporary file in the system's temporary folder.
    pub fn new() -> Result<Self> {
        static SPILLS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
        let n = SPILLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let path =
            std::env::temp_dir().join(format!(".vmc-twin-run-table-{}-{n}", std::process::id()));
        let file = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .create_new(true)
            .open(&path)
            .with_context(|| format!("{}: cannot create a temporary file", path.display()))?;
        let _ = std::fs::remove_file(&path);
        Ok(Self {
            file: std::io::BufWriter::new(file),
        })
    }

    /// The writer the rows go to.
    pub fn writer(&mut self) -> &mut dyn Write {
        &mut self.file
    }

    /// The file, flushed and rewound for reading.
    fn rewound(&mut self) -> Result<&mut std::fs::File> {
        self.file.flush()?;
        let f = self.file.get_mut();
        f.rewind()?;
        Ok(f)
    }

    /// Copies every row to `out`.
    pub fn copy_to(&mut self, out: &mut dyn Write) -> Result<()> {
        std::io::copy(self.rewound()?, out)?;
        Ok(())
    }

    /// The first `max_rows` lines, and a line saying how many more there are.
    pub fn head(&mut self, max_rows: usize) -> Result<String> {
        let mut text = String::new();
        let mut more = 0usize;
        let file: &mut std::fs::File = self.rewound()?;
        for (i, line) in std::io::BufReader::new(file).lines().enumerate() {
            let line = line?;
            // The header line, then the rows.
            if i <= max_rows {
                text.push_str(&line);
                text.push('\n');
            } else {
                more += 1;
            }
        }
        if more > 0 {
            text.push_str(&format!(
                "… {more} more rows (in samples.csv with --out, and in the printed report)\n"
            ));
        }
        Ok(text)
    }
}
