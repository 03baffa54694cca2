//! Prints the tables' report for the synthetic machine's trained hybrid model (see
//! `support/synthetic.rs`): what each table loses to interpolation, and what the per-joint
//! (LinuxCNC) and the own-axis-plus-cross (CEC) configurations leave of the model's error over
//! the volume.
//!
//! `cargo run -p vmc-tables --release --example synthetic_tables`

#[path = "support/synthetic.rs"]
mod synthetic;

use vmc_tables::export::{report_text, Provenance};
use vmc_tables::sample::sample_tables;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut model = synthetic::model_at_state();
    let set = sample_tables(&mut model, &synthetic::spec())?;
    let provenance = Provenance {
        model: "hybrid trained on the synthetic machine".into(),
        thermal_state: "steady readings S1=25.5 S2=23.1 Amb=20.4 degC".into(),
    };
    print!("{}", report_text(&set, &provenance));
    Ok(())
}
