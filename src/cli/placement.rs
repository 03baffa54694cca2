//! Command-line options that place a program on the machine, shared by `interpret`, `run` and
//! `check`: a setup file (`--setup`, default `<program>.setup.toml` beside the program), work
//! offsets (`--work-offset G54=X…,Y…,Z…`) and subroutine folders (`--subroutines DIR`), see
//! [`vmc_machine::setup`]. Offsets in machine coordinates, mm.

use std::path::{Path, PathBuf};

use anyhow::Result;
use vmc_gcode::interp::WORK_OFFSETS;
use vmc_machine::setup::{parse_work_offset, setup_beside, Placement, SetupFile};

/// Where the program sits and where its subroutine files are.
#[derive(clap::Args, Debug, Clone, Default)]
pub struct PlacementArgs {
    /// Setup file (TOML: work offsets G54…G59.3, fixtures and stock); default:
    /// `<program>.setup.toml` beside the program, if there is one.
    #[arg(long, value_name = "FILE")]
    pub setup: Option<PathBuf>,
    /// Where a program zero sits, machine coordinates, mm: `G54=X250,Y180,Z-320`
    /// (repeatable; an axis not given keeps its value from the setup or machine file).
    #[arg(long = "work-offset", value_name = "G5x=X…,Y…,Z…")]
    pub work_offset: Vec<String>,
    /// Folder searched for subroutine files `<name>.ngc` after the program's own folder
    /// (repeatable, searched in order).
    #[arg(long = "subroutines", value_name = "DIR")]
    pub subroutines: Vec<PathBuf>,
}

impl PlacementArgs {
    /// The placement of `program` on a machine whose own work offsets are
    /// `machine_offsets_mm`: the setup file's offsets over them, then the command line's.
    ///
    /// # Errors
    /// An unreadable or invalid setup file (line and field), a bad `--work-offset`, a
    /// `--subroutines` that is not a folder.
    pub fn placement(
        &self,
        program: &Path,
        machine_offsets_mm: [[f64; 3]; WORK_OFFSETS],
    ) -> Result<Placement> {
        let mut placement = Placement {
            work_offsets_mm: machine_offsets_mm,
            subroutine_dirs: Vec::new(),
            bodies: Vec::new(),
            setup_file: None,
            probe: None,
            artefacts: Vec::new(),
        };
        if let Some(path) = self.setup.clone().or_else(|| setup_beside(program)) {
            placement = placement.with_setup(SetupFile::load(&path)?, &path);
        }
        for arg in &self.work_offset {
            let (index, axes_mm) = parse_work_offset(arg)?;
            placement = placement.with_work_offset(index, axes_mm);
        }
        for dir in &self.subroutines {
            if !dir.is_dir() {
                anyhow::bail!("--subroutines {}: not a folder", dir.display());
            }
        }
        placement.subroutine_dirs = self.subroutines.clone();
        Ok(placement)
    }
}

/// A machine file's work offsets G54…G59 as the nine of G54…G59.3 (G59.1…G59.3 at 0).
pub fn nine_offsets(first_six_mm: [[f64; 3]; 6]) -> [[f64; 3]; WORK_OFFSETS] {
    let mut all = [[0.0; 3]; WORK_OFFSETS];
    all[..6].copy_from_slice(&first_six_mm);
    all
}
