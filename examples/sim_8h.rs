//! 8 h of machine time with an XY diagonal every 30 min at 1 ms (the `machine_8h_with_diagonals`
//! benchmark, once): for profilers (`valgrind --tool=callgrind`, `perf record`).
use vmc_twin::campaign::{self, ThermalCycle};
use vmc_twin::machine::MachineSpec;
use vmc_twin::program;
use vmc_twin::sim::{self, SampleMode, SimConfig};
use vmc_twin::twin::Twin;

fn main() {
    let spec = MachineSpec::reference();
    let plan = program::plan_source(
        include_str!("../trajectories/diag_xy.ngc"),
        "diag_xy.ngc",
        &spec,
        spec.axes.home_mm,
    )
    .expect("diagonal plans");
    let cycle = &ThermalCycle::calibration_set()[2];
    let cfg = SimConfig {
        sample_mode: SampleMode::EveryCycle,
        ..SimConfig::default()
    };
    let mut twin = Twin::new(&spec, 1).expect("reference machine");
    let mut n = 0usize;
    for k in 0..16 {
        campaign::drive(&mut twin, cycle, 0.0, k as f64 * 1800.0, 1.0).expect("drive");
        let mut count = sim::CountPoints::default();
        sim::execute(&mut twin, &plan, &cfg, None, &mut count).expect("run");
        n += count.points;
    }
    println!("{n} points");
}
