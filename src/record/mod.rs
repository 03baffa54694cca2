//! Rerun recordings: a run or a whole campaign written headless to an `.rrd` file
//! that `rerun FILE.rrd` opens with a ready layout.
//!
//! The simulation core does not know Rerun: a [`Recorder`] is a [`vmc_machine::sim::Observer`]. It
//! turns measurement points, thermal steps, node temperatures (truth, for display only), motion
//! samples and events into entities:
//!
//! | entity | archetype | content |
//! |---|---|---|
//! | `machine/{bed,column,saddle,table,head}` | `Boxes3D` (+ animated `Transform3D`) | the machine, moved by the commanded axis positions |
//! | `machine/head/tool` | `Cylinders3D` | the tool |
//! | `paths/{commanded,actual_uncompensated,actual_compensated}` | `LineStrips3D` | tool paths in the workpiece frame (riding the table), errors magnified ×K |
//! | `paths/measured` | `Points3D` | measurement points |
//! | `paths/events` | `Points3D` | events with a place (contacts, …), highlighted |
//! | `errors/vectors/{before,after}` | `Arrows3D` | error vectors ×K at the measurement points |
//! | `errors/{before,after}/{ex,ey,ez,norm}` | `Scalars` | errors, µm |
//! | `thermal/sensors/<name>` | `Scalars` | sensor readings, °C |
//! | `thermal/nodes` | `Points3D` | thermal nodes coloured by temperature (19 → 31 °C, blue → red) |
//! | `events` | `TextLog` | run starts and events |
//! | `report` | `TextDocument` | the run's report (markdown) |
//! | `legend` | `TextDocument` | colours and magnification |
//! | `runs/seed<s>/<state>/<diagonal>/{before,after}` | `Scalars` | campaign only: \|E\| of every held-out hybrid run (see [`campaign`]) |
//!
//! The milling-dynamics commands write their own recordings ([`dynamics`]: lobe diagram, one
//! cut's vibration, forces and spectra; [`modal_fit`]: a measured and a fitted receptance).
//!
//! Timelines: `sim_time` (duration, s of twin time), `sample` (measurement point index) and, for
//! straight-line tests such as the diagonals, `diagonal_mm` (position along the line from the
//! first measurement point, mm, rounded). Scene units are metres (see [`scene`]).
//!
//! Magnification: drawn paths and arrows show `p + K·E` with `K` = [`DEFAULT_MAGNIFY`] = 2000
//! unless set: a 20 µm error becomes 40 mm, 8 % of a 500 mm travel — plainly visible, while the
//! 40 µm errors of a warm machine (80 mm) still leave the path's shape readable.
//!
//! Files: the recording is written to a temporary file next to the target and renamed when
//! complete (the `.rrd` footer is written when the stream closes), so a failed run never leaves
//! a half-written file under the requested name. [`check_rrd_path`] validates the target
//! before any simulation starts.

pub mod campaign;
pub mod chatter;
pub mod check;
pub mod drift;
pub mod dynamics;
pub mod fiveaxis;
pub mod fleet;
pub mod layout;
pub mod modal_fit;
mod recorder;
pub mod scene;
mod series;

use std::path::{Path, PathBuf};

use rerun::{RecordingStream, RecordingStreamBuilder};
use thiserror::Error;

use crate::report::norm;
use vmc_machine::motion::{Plan, SegmentKind};

pub use recorder::Recorder;

/// Default error magnification of drawn paths and arrows.
pub const DEFAULT_MAGNIFY: f64 = 2000.0;

/// Rerun application id of every vmc-twin recording.
pub const APP_ID: &str = "vmc_twin";

/// Temperature range of the node colour ramp, °C.
pub const NODE_TEMP_RANGE_DEGC: (f64, f64) = (19.0, 31.0);

/// Why a recording could not be written.
#[derive(Debug, Error)]
pub enum RecordError {
    /// The output path cannot be used.
    #[error("{path}: {msg}")]
    Path {
        /// The requested file.
        path: PathBuf,
        /// Why.
        msg: String,
    },
    /// The file exists and overwriting was not allowed.
    #[error("{0}: already exists (pass --force to overwrite)")]
    Exists(PathBuf),
    /// The output may not be written (an input, a link, a device; see `crate::files`).
    #[error(transparent)]
    Output(#[from] crate::files::OutputError),
    /// The Rerun SDK refused something.
    #[error("recording {path}: {msg}")]
    Rerun {
        /// The requested file.
        path: PathBuf,
        /// The SDK's message.
        msg: String,
    },
    /// A bad setting.
    #[error("recording settings: {0}")]
    Settings(String),
    /// A replayed run did not reproduce the evaluated one.
    #[error("recording: {0}")]
    Replay(String),
    /// The twin that draws the motion could not be built.
    #[error("recording: {0}")]
    Twin(#[from] vmc_machine::twin::TwinError),
}

/// Checks up front that a recording can be written to `path`: the name ends in `.rrd`, the
/// folder exists and is writable, and the file does not exist unless `force`.
pub fn check_rrd_path(path: &Path, force: bool) -> Result<(), RecordError> {
    let bad = |msg: String| RecordError::Path {
        path: path.to_path_buf(),
        msg,
    };
    if path.extension().and_then(|e| e.to_str()) != Some("rrd") {
        return Err(bad(
            "a Rerun recording file name must end in .rrd".to_string()
        ));
    }
    if path.is_dir() {
        return Err(bad("is a directory, not a file".to_string()));
    }
    let dir = parent_dir(path);
    if !dir.is_dir() {
        return Err(bad(format!(
            "directory {} does not exist (create it first)",
            dir.display()
        )));
    }
    if path.exists() && !force {
        return Err(RecordError::Exists(path.to_path_buf()));
    }
    if std::fs::symlink_metadata(path).is_ok_and(|m| !m.file_type().is_file()) {
        return Err(RecordError::Path {
            path: path.to_path_buf(),
            msg: "is not a regular file (a link, device or pipe); a recording is written only \
                  to a regular file"
                .to_string(),
        });
    }
    crate::files::check_writable(path, force)?;
    // Writable? Create and remove a probe file (permissions alone do not tell, e.g. for root or
    // read-only mounts).
    let probe = dir.join(format!(".{}.probe-{}", file_name(path), std::process::id()));
    match std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&probe)
    {
        Ok(_) => {
            let _ = std::fs::remove_file(&probe);
            Ok(())
        }
        Err(e) => Err(bad(format!(
            "cannot write in directory {}: {e}",
            dir.display()
        ))),
    }
}

fn parent_dir(path: &Path) -> PathBuf {
    path.parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."))
        .to_path_buf()
}

fn file_name(path: &Path) -> String {
    path.file_name()
        .map(|n| n.to_string_lossy().to_string())
        .unwrap_or_default()
}

/// An `.rrd` file being written: a Rerun stream into a temporary file, renamed on
/// [`RrdFile::finish`]. Dropped unfinished, it removes the temporary file.
pub struct RrdFile {
    rec: RecordingStream,
    tmp: PathBuf,
    path: PathBuf,
    force: bool,
    done: bool,
}

impl RrdFile {
    /// Opens a recording for `path` (checked with [`check_rrd_path`]) with a fixed recording id
    /// (the same inputs give the same id) and the default layout `blueprint`.
    pub fn create(
        path: &Path,
        force: bool,
        recording_id: &str,
        blueprint: rerun::blueprint::Blueprint,
    ) -> Result<Self, RecordError> {
        check_rrd_path(path, force)?;
        let tmp = parent_dir(path).join(format!(".{}.tmp-{}", file_name(path), std::process::id()));
        let rec = RecordingStreamBuilder::new(APP_ID)
            .recording_id(recording_id)
            .enabled(true)
            .with_blueprint(blueprint)
            .save(&tmp)
            .map_err(|e| RecordError::Rerun {
                path: path.to_path_buf(),
                msg: e.to_string(),
            })?;
        // Only the simulation's own timelines: no wall clock, no log tick.
        rec.set_log_time_enabled(false);
        rec.set_log_tick_enabled(false);
        Ok(RrdFile {
            rec,
            tmp,
            path: path.to_path_buf(),
            force,
            done: false,
        })
    }

    /// The stream to log to.
    pub fn stream(&self) -> &RecordingStream {
        &self.rec
    }

    /// The target path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Wraps an SDK error with the file name.
    pub fn err(&self, e: impl std::fmt::Display) -> RecordError {
        RecordError::Rerun {
            path: self.path.clone(),
            msg: e.to_string(),
        }
    }

    /// Closes the stream (writes the footer) and moves the file into place. Returns its size in
    /// bytes.
    pub fn finish(mut self) -> Result<u64, RecordError> {
        self.done = true;
        self.rec.flush_blocking().map_err(|e| self.err(e))?;
        // Drops the file sink: its writer thread writes the footer and closes the file.
        self.rec.finalize_deferred_sinks();
        let result = (|| {
            let size = std::fs::metadata(&self.tmp)
                .map_err(|e| self.err(format!("temporary file {}: {e}", self.tmp.display())))?
                .len();
            if size == 0 {
                return Err(self.err("the Rerun SDK wrote an empty file"));
            }
            crate::files::publish(&self.tmp, &self.path, self.force)?;
            Ok(size)
        })();
        // After a hard link the temporary name remains: remove it in every case.
        let _ = std::fs::remove_file(&self.tmp);
        result
    }
}

impl Drop for RrdFile {
    fn drop(&mut self) {
        if !self.done {
            self.rec.finalize_deferred_sinks();
            let _ = std::fs::remove_file(&self.tmp);
        }
    }
}

/// A run's report for the recording: the text report (as printed) in a code block, with the
/// magnification and the colour legend.
pub fn run_markdown(report_text: &str, magnify: f64, compensated: bool) -> String {
    let after = if compensated {
        "green: actual path with compensation; "
    } else {
        ""
    };
    format!(
        "# vmc-twin run\n\nErrors magnified **×{magnify:.0}** in the 3-D view (20 µm → {:.0} mm). \
         Grey: commanded path; red: actual path without compensation; {after}arrows: error \
         vectors at the measurement points.\n\n```text\n{report_text}```\n",
        20e-3 * magnify
    )
}

/// A straight-line test (a diagonal): positions along it give the `diagonal_mm` timeline.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Diagonal {
    /// First measurement point, mm.
    pub start_mm: [f64; 3],
    /// Unit direction towards the last measurement point.
    pub dir: [f64; 3],
    /// Length from the first to the last point, mm.
    pub length_mm: f64,
}

impl Diagonal {
    /// The line through `points` if there are at least two distinct points and every point lies
    /// within 0.01 mm of the line from the first to the last.
    pub fn through(points: &[[f64; 3]]) -> Option<Self> {
        let diag = Self::between(*points.first()?, *points.last()?)?;
        points.iter().all(|p| diag.holds(*p)).then_some(diag)
    }

    /// The line from `first_mm` to `last_mm`, if they are distinct (a stream of points is
    /// checked against it one by one with [`Self::holds`]).
    pub fn between(first_mm: [f64; 3], last_mm: [f64; 3]) -> Option<Self> {
        let d = [0, 1, 2].map(|a| last_mm[a] - first_mm[a]);
        let length_mm = norm(d);
        if length_mm < 1e-6 {
            return None;
        }
        Some(Diagonal {
            start_mm: first_mm,
            dir: d.map(|c| c / length_mm),
            length_mm,
        })
    }

    /// Whether `p_mm` lies on the line (within 0.01 mm).
    pub fn holds(&self, p_mm: [f64; 3]) -> bool {
        let s = self.position_mm(p_mm);
        let off = [0, 1, 2].map(|a| p_mm[a] - self.start_mm[a] - s * self.dir[a]);
        norm(off) < 0.01
    }

    /// The line through a plan's dwell (measurement) points, if they are collinear.
    pub fn of_plan(plan: &Plan) -> Option<Self> {
        let pts: Vec<[f64; 3]> = plan
            .segments()
            .iter()
            .filter(|s| s.kind == SegmentKind::Dwell)
            .map(|s| s.end_mm)
            .collect();
        Self::through(&pts)
    }

    /// Signed distance of `p_mm` along the line from the first point, mm.
    pub fn position_mm(&self, p_mm: [f64; 3]) -> f64 {
        (0..3)
            .map(|a| (p_mm[a] - self.start_mm[a]) * self.dir[a])
            .sum()
    }
}

/// Settings of a [`Recorder`].
#[derive(Debug, Clone, Copy)]
pub struct RecordSettings {
    /// Error magnification of drawn paths and arrows (default [`DEFAULT_MAGNIFY`]).
    pub magnify: f64,
    /// Interval of machine poses during measured runs, s (default 0.05).
    pub motion_sample_s: f64,
    /// Interval of machine poses, sensor readings and node temperatures during warm-ups and
    /// thermal histories, s (default 10).
    pub history_sample_s: f64,
    /// Most path vertices drawn per strip (longer paths are thinned evenly; default 4000).
    pub max_path_vertices: usize,
}

impl Default for RecordSettings {
    fn default() -> Self {
        RecordSettings {
            magnify: DEFAULT_MAGNIFY,
            motion_sample_s: 0.05,
            history_sample_s: 10.0,
            max_path_vertices: 4000,
        }
    }
}

impl RecordSettings {
    /// Checks the settings.
    pub fn validate(&self) -> Result<(), RecordError> {
        if !(self.magnify > 0.0 && self.magnify.is_finite()) {
            return Err(RecordError::Settings(format!(
                "magnification must be > 0, got {}",
                self.magnify
            )));
        }
        for (name, v) in [
            ("motion sample interval", self.motion_sample_s),
            ("history sample interval", self.history_sample_s),
        ] {
            if !(v > 0.0 && v.is_finite()) {
                return Err(RecordError::Settings(format!(
                    "{name} must be > 0 s, got {v}"
                )));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests;
