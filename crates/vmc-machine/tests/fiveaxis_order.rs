//! The model order chosen from the probing data, on a machine whose rotary motion errors are of
//! third order (the shipped A/C trunnion with its second-order harmonics turned into third-order
//! ones, twice as large): the data-chosen model characterises at least 95 % over the working
//! volume where the fixed default (harmonics 2) does not. And the probing campaign over the
//! volume (a relocated sphere at placements spread over it) on a B/C machine with 3rd- and
//! 4th-order rotary errors, where the artefact alone falls short.

use nalgebra::Matrix3;

use vmc_identify::identify::placements_in;
use vmc_identify::identify::{identify, IdentifyOptions, Observation};
use vmc_identify::order::{choose_order, parameter_set, OrderOptions};
use vmc_machine::fiveaxis::campaign::{
    parse_csv, placements_w_mm, run, spread_configurations, to_csv,
};
use vmc_machine::fiveaxis::heldout::{judge, HeldOut, HeldOutPlan};
use vmc_machine::fiveaxis::probe::VirtualProbe;
use vmc_machine::fiveaxis::{FiveAxisSpec, TrueMachine};

/// The shipped machine with every rotary motion harmonic of order 2 moved to order 3 and
/// doubled, and the seeded orders up to 3 only.
fn third_order_machine() -> FiveAxisSpec {
    let text = include_str!("../../../machines/trunnion-ac.toml");
    let mut out = String::new();
    for line in text.lines() {
        let line = if line.starts_with("harmonics = ") {
            let mut l = line.replace("order = 2", "order = 3");
            for (a, b) in [
                ("amplitude = 1.0,", "amplitude = 2.0,"),
                ("amplitude = 1.2,", "amplitude = 2.4,"),
                ("amplitude = 1.5,", "amplitude = 3.0,"),
                ("amplitude = 2.0,", "amplitude = 4.0,"),
                ("amplitude = 2.5,", "amplitude = 5.0,"),
                ("amplitude = 3.0,", "amplitude = 6.0,"),
            ] {
                l = l.replace(a, b);
            }
            l
        } else if line.starts_with("random_orders = ") {
            "random_orders = 3".to_string()
        } else {
            line.replace("name = \"trunnion-ac\"", "name = \"trunnion-ac-3rd\"")
        };
        out.push_str(&line);
        out.push('\n');
    }
    FiveAxisSpec::from_toml_str(&out, "trunnion-ac-3rd.toml").unwrap()
}

/// Probes 50 spread configurations of realisation `seed` on the artefact, through the probing
/// file's text.
fn probe(spec: &FiveAxisSpec, seed: u64) -> (TrueMachine, Vec<Observation>) {
    probe_campaign(spec, seed, 50, 0)
}

/// Probes `n` spread configurations of realisation `seed` over the artefact and `placements`
/// placements of a relocated sphere over the volume, through the probing file's text.
fn probe_campaign(
    spec: &FiveAxisSpec,
    seed: u64,
    n: usize,
    placements: usize,
) -> (TrueMachine, Vec<Observation>) {
    let machine = TrueMachine::new(spec, seed).unwrap();
    let probe = VirtualProbe::of(spec, None);
    let targets = placements_w_mm(spec, Some(placements)).unwrap();
    let configs = spread_configurations(spec, &probe, n, &targets);
    assert_eq!(configs.len(), n);
    let rows = run(&machine, &probe, &configs, seed).unwrap();
    let file = parse_csv(&to_csv(spec, seed, &probe, &rows), spec).unwrap();
    let mut obs = file.observations;
    for o in &mut obs {
        o.cov_mm2 += Matrix3::identity() * 1e-10;
    }
    (machine, obs)
}

fn judged(
    spec: &FiveAxisSpec,
    machine: &TrueMachine,
    obs: &[Observation],
    orders: &[u32],
) -> HeldOut {
    let geom = spec.geometry();
    let set = parameter_set(&geom, orders).with_placements(placements_in(obs));
    let id = identify(&geom, &set, obs, &IdentifyOptions::default()).unwrap();
    let values = id.values();
    let model = |pose: &vmc_identify::chain::Pose| set.state_at(&values, pose);
    judge(spec, machine, &model, &HeldOutPlan::default()).unwrap()
}

/// Seeds 1–3, 50 spread configurations, 500 held-out poses over the working volume. Measured:
/// chosen orders [3, 3] on every seed, 95.6 / 97.8 / 98.8 % characterised; the fixed order 2
/// gives 84.0 / 94.1 / 95.7 %.
#[test]
fn on_third_order_rotary_errors_the_data_chosen_order_reaches_95_percent_where_order_2_does_not() {
    let spec = third_order_machine();
    let mut fixed_misses = 0;
    for seed in [1, 2, 3] {
        let (machine, obs) = probe(&spec, seed);
        let choice = choose_order(&spec.geometry(), &obs, &OrderOptions::default()).unwrap();
        let chosen = judged(&spec, &machine, &obs, &choice.orders);
        let fixed = judged(&spec, &machine, &obs, &[2, 2]);
        assert!(
            choice.orders.iter().all(|&h| h >= 3),
            "seed {seed}: {:?}",
            choice.orders
        );
        assert!(
            chosen.characterised_share >= 0.95,
            "seed {seed}: {}",
            chosen.characterised_share
        );
        assert!(
            chosen.after_mean_um < fixed.after_mean_um,
            "seed {seed}: {} vs {}",
            chosen.after_mean_um,
            fixed.after_mean_um
        );
        fixed_misses += usize::from(fixed.characterised_share < 0.95);
    }
    assert!(
        fixed_misses >= 1,
        "the fixed order reached 95 % on every seed"
    );
}

/// Seeds 1 and 5 of the B/C fixture with 3rd- and 4th-order rotary errors and 20–30 µrad
/// squareness, orders chosen from the data. Measured: the artefact alone (50 configurations, as
/// the campaign was) 94.0 / 94.8 %; 80 configurations over the artefact and 4 placements spread
/// over the volume 98.2 / 98.7 %, each region 97.7 % or more.
#[test]
fn probing_over_the_volume_reaches_95_percent_on_every_region_where_the_artefact_alone_does_not() {
    let spec = FiveAxisSpec::from_toml_str(
        include_str!("fixtures/trunnion-bc-high-order.toml"),
        "trunnion-bc-high-order.toml",
    )
    .unwrap();
    for seed in [1, 5] {
        let verdict = |n: usize, placements: usize| {
            let (machine, obs) = probe_campaign(&spec, seed, n, placements);
            let choice = choose_order(&spec.geometry(), &obs, &OrderOptions::default()).unwrap();
            judged(&spec, &machine, &obs, &choice.orders)
        };
        let artefact = verdict(50, 0);
        assert!(
            artefact.characterised_share < 0.95,
            "seed {seed}: the artefact alone reached {}",
            artefact.characterised_share
        );
        let volume = verdict(80, 4);
        assert!(
            volume.characterised_share >= 0.95,
            "seed {seed}: {}",
            volume.characterised_share
        );
        for r in &volume.regions {
            assert!(r.poses > 50, "seed {seed}: {r:?}");
            assert!(r.characterised_share >= 0.95, "seed {seed}: {r:?}");
        }
    }
}
