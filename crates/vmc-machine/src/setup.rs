//! Placing a program on the machine, as a setup sheet does: where each program zero is (the
//! work offsets G54…G59.3, machine coordinates, mm), which bodies are clamped on the table
//! (fixtures and stock, as in a fixture file), and where the program's subroutine files are.
//!
//! A program is written for its own part zero; the setup says where that zero sits on this
//! machine. Sources, each overriding the one before: the machine file's work offsets (G54…G59),
//! a setup file (TOML: `[work_offsets_mm]` and `bodies`, and for probing `[probe]` and
//! `[[artefacts]]`, see [`SetupFile`] and [`crate::probe_setup`]), and command-line
//! offsets (`G54=X250,Y180,Z-320`, [`parse_work_offset`]); an axis not given keeps the value it
//! had. Subroutine files are looked up in the program's folder first, then in the folders
//! given, in order. All lengths in mm, machine coordinates (the commanded tool tip relative to
//! the table, the interpreter's and planner's frame).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::Deserialize;
use thiserror::Error;
use vmc_gcode::interp::WORK_OFFSETS;

use crate::collision_spec::{validate_bodies, BodySpec, FixtureSpec, MAX_COORD_MM};
use crate::machine::MachineSpec;
use crate::probe_setup::{validate_artefacts, ArtefactSpec, NamedSolid, ProbeSpec, Solid};

/// The names of the work coordinate systems, in the interpreter's order (index 0…8).
pub const WORK_OFFSET_NAMES: [&str; WORK_OFFSETS] = [
    "G54", "G55", "G56", "G57", "G58", "G59", "G59.1", "G59.2", "G59.3",
];

/// A setup that cannot be used.
#[derive(Debug, Error)]
pub enum SetupError {
    /// The file could not be read.
    #[error("{path}: cannot read setup file: {err}")]
    Io {
        /// The file.
        path: String,
        /// Why.
        err: std::io::Error,
    },
    /// Not valid TOML or not the schema (the parser's message has line and column).
    #[error("{path}: {msg}")]
    Parse {
        /// The file.
        path: String,
        /// The TOML parser's message.
        msg: String,
    },
    /// A field has a bad value.
    #[error("{path}: line {line}: field `{field}`: {msg}")]
    Invalid {
        /// The file.
        path: String,
        /// 1-based line of the field.
        line: usize,
        /// Dotted path of the field.
        field: String,
        /// What is wrong.
        msg: String,
    },
    /// A command-line work offset that cannot be read.
    #[error("--work-offset {arg:?}: {msg}")]
    Arg {
        /// The argument as given.
        arg: String,
        /// What is wrong.
        msg: String,
    },
}

/// The setup file as written (see docs/file-formats.md, `setup.toml`).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SetupText {
    #[serde(default)]
    work_offsets_mm: BTreeMap<String, toml::Spanned<[f64; 3]>>,
    #[serde(default)]
    bodies: Vec<toml::Spanned<BodySpec>>,
    #[serde(default)]
    probe: Option<toml::Spanned<ProbeSpec>>,
    #[serde(default)]
    artefacts: Vec<toml::Spanned<ArtefactSpec>>,
}

/// A validated setup file: the work offsets it sets and the bodies on the table.
#[derive(Debug, Clone, PartialEq)]
pub struct SetupFile {
    /// Work offsets it sets (index 0…8 for G54…G59.3), machine coordinates, mm.
    pub work_offsets_mm: [Option<[f64; 3]>; WORK_OFFSETS],
    /// Fixtures and stock, as in a fixture file.
    pub bodies: Vec<BodySpec>,
    /// The touch probe of the G38 moves (`[probe]`), if the file describes one.
    pub probe: Option<ProbeSpec>,
    /// Artefacts on the table a probe may touch (`[[artefacts]]`).
    pub artefacts: Vec<ArtefactSpec>,
}

/// 1-based line of byte `offset` in `text`.
fn line_of(text: &str, offset: usize) -> usize {
    1 + text[..offset.min(text.len())].matches('\n').count()
}

impl SetupFile {
    /// Reads and validates a setup file.
    ///
    /// # Errors
    /// [`SetupError::Io`], and those of [`Self::from_toml_str`].
    pub fn load(path: &Path) -> Result<Self, SetupError> {
        let name = path.display().to_string();
        let text = crate::read::read_text(path).map_err(|err| SetupError::Io {
            path: name.clone(),
            err,
        })?;
        Self::from_toml_str(&text, &name)
    }

    /// Parses and validates setup text; `path` names it in errors.
    ///
    /// # Errors
    /// [`SetupError::Parse`] (TOML or schema, with line and column), [`SetupError::Invalid`]
    /// (an unknown work offset name, a coordinate that is not finite or beyond ±1e5 mm, a bad
    /// body), with the line and the field.
    pub fn from_toml_str(text: &str, path: &str) -> Result<Self, SetupError> {
        let raw: SetupText = toml::from_str(text).map_err(|e| SetupError::Parse {
            path: path.to_string(),
            msg: crate::read::one_line_toml_error(&e),
        })?;
        let invalid =
            |span: std::ops::Range<usize>, field: String, msg: String| SetupError::Invalid {
                path: path.to_string(),
                line: line_of(text, span.start),
                field,
                msg,
            };
        let mut work_offsets_mm = [None; WORK_OFFSETS];
        for (name, value) in &raw.work_offsets_mm {
            let field = format!("work_offsets_mm.{name}");
            let Some(i) = work_offset_index(name) else {
                let msg = format!(
                    "unknown work offset, expected one of {}",
                    WORK_OFFSET_NAMES.join(", ")
                );
                return Err(invalid(value.span(), field, msg));
            };
            let v = *value.get_ref();
            if let Some(a) = (0..3).find(|&a| !(v[a].is_finite() && v[a].abs() <= MAX_COORD_MM)) {
                let msg = format!(
                    "must be a finite number within ±{MAX_COORD_MM} mm, got {}",
                    v[a]
                );
                return Err(invalid(value.span(), format!("{field}[{a}]"), msg));
            }
            work_offsets_mm[i] = Some(v);
        }
        let bodies: Vec<BodySpec> = raw.bodies.iter().map(|b| b.get_ref().clone()).collect();
        if let Err((field, msg)) = validate_bodies(&bodies, "bodies") {
            // `bodies[k]…`: the line of body k.
            let k = field
                .strip_prefix("bodies[")
                .and_then(|r| r.split(']').next())
                .and_then(|k| k.parse::<usize>().ok())
                .unwrap_or(0);
            let span = raw.bodies.get(k).map_or(0..0, |b| b.span());
            return Err(invalid(span, field, msg));
        }
        let probe = raw.probe.as_ref().map(|p| *p.get_ref());
        if let (Some(spec), Some(spanned)) = (&probe, &raw.probe) {
            if let Err((field, msg)) = spec.validate() {
                return Err(invalid(spanned.span(), field, msg));
            }
        }
        let artefacts: Vec<ArtefactSpec> =
            raw.artefacts.iter().map(|a| a.get_ref().clone()).collect();
        if let Err((field, msg)) = validate_artefacts(&artefacts) {
            let k = field
                .strip_prefix("artefacts[")
                .and_then(|r| r.split(']').next())
                .and_then(|k| k.parse::<usize>().ok())
                .unwrap_or(0);
            let span = raw.artefacts.get(k).map_or(0..0, |a| a.span());
            return Err(invalid(span, field, msg));
        }
        Ok(Self {
            work_offsets_mm,
            bodies,
            probe,
            artefacts,
        })
    }
}

/// Index 0…8 of a work offset name (`G54` … `G59.3`, any case).
pub fn work_offset_index(name: &str) -> Option<usize> {
    WORK_OFFSET_NAMES
        .iter()
        .position(|n| n.eq_ignore_ascii_case(name.trim()))
}

/// A command-line work offset `G54=X250,Y180,Z-320` (axes in any order, any subset, mm):
/// the index of the offset and the axes it sets.
///
/// # Errors
/// [`SetupError::Arg`]: no `=`, an unknown offset name, an axis other than X Y Z, an axis
/// given twice, a value that is not a finite number within ±1e5 mm, no axis.
pub fn parse_work_offset(arg: &str) -> Result<(usize, [Option<f64>; 3]), SetupError> {
    let err = |msg: String| SetupError::Arg {
        arg: arg.to_string(),
        msg,
    };
    let (name, axes) = arg
        .split_once('=')
        .ok_or_else(|| err("expected G5x=X…,Y…,Z… (e.g. G54=X250,Y180,Z-320)".into()))?;
    let i = work_offset_index(name).ok_or_else(|| {
        err(format!(
            "unknown work offset {name:?}, expected one of {}",
            WORK_OFFSET_NAMES.join(", ")
        ))
    })?;
    let mut values = [None; 3];
    for item in axes.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        let mut chars = item.chars();
        let letter = chars.next().map(|c| c.to_ascii_uppercase());
        let a = match letter {
            Some('X') => 0,
            Some('Y') => 1,
            Some('Z') => 2,
            _ => {
                return Err(err(format!(
                    "{item:?}: expected an axis X, Y or Z and a value in mm"
                )))
            }
        };
        let v: f64 = chars
            .as_str()
            .trim_start_matches('=')
            .parse()
            .map_err(|_| err(format!("{item:?}: not a number")))?;
        if !(v.is_finite() && v.abs() <= MAX_COORD_MM) {
            return Err(err(format!("{item:?}: must be within ±{MAX_COORD_MM} mm")));
        }
        if values[a].replace(v).is_some() {
            return Err(err(format!("axis {} given twice", ['X', 'Y', 'Z'][a])));
        }
    }
    if values.iter().all(Option::is_none) {
        return Err(err("no axis given (e.g. G54=X250,Y180,Z-320)".into()));
    }
    Ok((i, values))
}

/// Where a program sits on the machine and where its subroutine files are: what the
/// interpreter and the collision check need (see the module documentation).
#[derive(Debug, Clone, PartialEq)]
pub struct Placement {
    /// Work offsets G54…G59.3, machine coordinates, mm.
    pub work_offsets_mm: [[f64; 3]; WORK_OFFSETS],
    /// Folders searched for `<name>.ngc` after the program's own folder, in order.
    pub subroutine_dirs: Vec<PathBuf>,
    /// Fixtures and stock of the setup file (none without one).
    pub bodies: Vec<BodySpec>,
    /// The setup file used, if any (reports name it).
    pub setup_file: Option<PathBuf>,
    /// The setup file's touch probe (`None`: the typical probe, see [`TouchProbe::of_placement`](crate::touch_probe::TouchProbe::of_placement)).
    pub probe: Option<ProbeSpec>,
    /// The setup file's artefacts.
    pub artefacts: Vec<ArtefactSpec>,
}

impl Placement {
    /// The machine file's work offsets (G59.1…G59.3 at 0), no extra subroutine folder, no
    /// bodies: a program placed as the machine file alone places it.
    pub fn of_machine(machine: &MachineSpec) -> Self {
        let mut work_offsets_mm = [[0.0; 3]; WORK_OFFSETS];
        let from_machine = &machine.axes.work_offsets_mm;
        work_offsets_mm[..from_machine.len()].copy_from_slice(from_machine);
        Self {
            work_offsets_mm,
            subroutine_dirs: Vec::new(),
            bodies: Vec::new(),
            setup_file: None,
            probe: None,
            artefacts: Vec::new(),
        }
    }

    /// This placement with a setup file's offsets and bodies.
    pub fn with_setup(mut self, setup: SetupFile, path: &Path) -> Self {
        for (i, v) in setup.work_offsets_mm.iter().enumerate() {
            if let Some(v) = v {
                self.work_offsets_mm[i] = *v;
            }
        }
        self.bodies = setup.bodies;
        self.probe = setup.probe;
        self.artefacts = setup.artefacts;
        self.setup_file = Some(path.to_path_buf());
        self
    }

    /// This placement with one work offset's axes set (see [`parse_work_offset`]).
    pub fn with_work_offset(mut self, index: usize, axes_mm: [Option<f64>; 3]) -> Self {
        for (a, v) in axes_mm.iter().enumerate() {
            if let Some(v) = v {
                self.work_offsets_mm[index][a] = *v;
            }
        }
        self
    }

    /// The subroutine folders of `program`: its own folder, then [`Self::subroutine_dirs`].
    pub fn search_path(&self, program: Option<&Path>) -> Vec<PathBuf> {
        let own = program.map(|p| p.parent().unwrap_or(Path::new("")).to_path_buf());
        own.into_iter()
            .chain(self.subroutine_dirs.iter().cloned())
            .collect()
    }

    /// What a probe's ball can touch: the artefacts, the setup's bodies (fixtures and stock),
    /// `extra` bodies (a fixture file's) and the machine's own (its `[collision]` table).
    pub fn probe_solids(&self, machine: &MachineSpec, extra: &[BodySpec]) -> Vec<NamedSolid> {
        let artefacts = self.artefacts.iter().map(|a| NamedSolid {
            name: a.name.clone(),
            solid: a.solid(),
        });
        let machine_bodies = machine.collision.iter().flat_map(|c| c.bodies.iter());
        let bodies = self
            .bodies
            .iter()
            .chain(extra)
            .chain(machine_bodies)
            .map(|b| NamedSolid {
                name: b.name.clone(),
                solid: Solid::of_body(b),
            });
        artefacts.chain(bodies).collect()
    }

    /// The setup's bodies and those of a fixture file, as one fixture (`None` if neither has
    /// any).
    pub fn fixture(&self, file: Option<FixtureSpec>) -> Option<FixtureSpec> {
        let mut bodies = self.bodies.clone();
        bodies.extend(file.map(|f| f.bodies).unwrap_or_default());
        (!bodies.is_empty()).then_some(FixtureSpec { bodies })
    }
}

/// The setup file beside a program: `<stem>.setup.toml` in its folder (`part.ngc` →
/// `part.setup.toml`), if that file exists.
pub fn setup_beside(program: &Path) -> Option<PathBuf> {
    let stem = program.file_stem()?.to_str()?;
    let path = program.with_file_name(format!("{stem}.setup.toml"));
    path.is_file().then_some(path)
}

#[cfg(test)]
#[path = "setup_tests.rs"]
mod tests;
