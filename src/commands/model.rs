//! A trained model loaded for a machine: the file read, the model retooled to the machine's tool
//! offset, its machine identity checked. `run` puts it in the loop; `export` samples tables
//! from it.

use std::io::Write;
use std::path::Path;

use anyhow::{Context, Result};

use crate::files;
use crate::predict::predictor::{self as model_file, AnyPredictor};
use crate::predict::provenance::TrainedOn;
use vmc_machine::machine::MachineSpec;

/// The message of a model whose kinematics or sensors do not fit `machine`.
pub(crate) fn does_not_fit(path: &Path, machine: &MachineSpec) -> String {
    format!(
        "{}: model does not fit machine {}",
        path.display(),
        machine.machine.name
    )
}

/// The model of `path` for `machine` (realisation `seed`), with what it was trained on: retooled
/// to the machine's tool offset when it is a hybrid model (which `out` is told). A model of other
/// kinematics is refused; one calibrated on another machine or realisation is refused unless
/// `allow_other_machine` (then `out` is told).
///
/// # Errors
/// An unreadable or invalid model file, a model that does not fit the machine.
pub(crate) fn load_for_machine(
    machine: &MachineSpec,
    seed: u64,
    path: &Path,
    allow_other_machine: bool,
    out: &mut dyn Write,
) -> Result<(AnyPredictor, Option<TrainedOn>)> {
    // A read error and a content error alike are named by the file, once.
    let (model, trained_on) = files::read_text(path)
        .map_err(anyhow::Error::new)
        .and_then(|text| {
            let model = AnyPredictor::from_json_str(&text)?;
            Ok((model, model_file::file::trained_on(&text)?))
        })
        .with_context(|| path.display().to_string())?;
    let trained_tool_mm = model.geometry().tool_offset_mm;
    let (model, retooled) = model
        .for_machine_geometry(&machine.geometry())
        .with_context(|| does_not_fit(path, machine))?;
    if retooled {
        writeln!(
            out,
            "note: {} was calibrated with tool offset {:?} mm; its elementary errors are \
             synthesised for this machine's tool offset {:?} mm",
            path.display(),
            trained_tool_mm,
            machine.tool.offset_mm
        )?;
    }
    let here = machine.identity(Some(seed));
    match trained_on.as_ref().and_then(|t| t.machine.as_ref()) {
        Some(id) => {
            if let Some(why) = id.difference(&here) {
                if !allow_other_machine {
                    anyhow::bail!(
                        "{}: the model does not belong to this machine: {why}; retrain it on \
                         this machine's calibration, or pass --allow-other-machine to use it \
                         anyway",
                        path.display()
                    );
                }
                writeln!(
                    out,
                    "note: {}: {why} (--allow-other-machine)",
                    path.display()
                )?;
            } else if id.realisation.is_none() {
                writeln!(
                    out,
                    "note: {}: trained on data of an unknown realisation of machine `{}` (its \
                     calibration file had no `# machine:` line): which machine it was is not \
                     checked",
                    path.display(),
                    id.name
                )?;
            }
        }
        None => writeln!(
            out,
            "note: {} records no machine or trained ranges (a model file older than version \
             8): neither is checked",
            path.display()
        )?,
    }
    Ok((model, trained_on))
}
