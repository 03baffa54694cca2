//! 8 h of machine time with an XY diagonal every 30 min at 1 ms (the `machine_8h_with_diagonals`
//! benchmark, once): for profilers (`valgrind --tool=callgrind`, `perf record`).
use vmc_machine::machine::MachineSpec;
use vmc_twin::benchmark;

fn main() {
    let spec = MachineSpec::reference();
    let workload = benchmark::workload_8h(&spec, 1.0).expect("diagonal plans");
    let n = benchmark::run_8h(&spec, &workload).expect("simulation runs");
    println!("{n} points");
}
