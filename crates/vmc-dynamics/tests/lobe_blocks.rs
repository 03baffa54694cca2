//! Blocks of a list of speeds give the lobe points of the whole list bit for bit, whatever the
//! split: what lets `lobes --shard I/N` merge into exactly the unsharded lobes. On the
//! Insperger–Stépán benchmark (N = 2, K_t = 6e8 N/m², K_n = 2e8 N/m², f_n = 922 Hz,
//! ζ = 0.011, m = 0.03993 kg) at a_e/D = 0.05 down milling, where Hopf and flip lobes alternate.

use std::ops::Range;

use vmc_dynamics::lobes::lobes_block;
use vmc_dynamics::milling::{MillingSdm, SdmOptions, TRACE_RUN};
use vmc_dynamics::*;

fn tool() -> Tool {
    Tool::new(2, 16.0, 6e8, 2e8)
}

fn modes() -> TipModes {
    TipModes::x_only(vec![Mode::from_mass(922.0, 0.011, 0.03993)])
}

/// `count` speeds evenly from 5000 to 25 000 rpm.
fn speeds(count: usize) -> Vec<f64> {
    (0..count)
        .map(|i| 5000.0 + 20_000.0 * i as f64 / (count - 1) as f64)
        .collect()
}

/// The `index`-th of `count` contiguous blocks of `len` items (as `--shard` splits them).
fn block(index: usize, count: usize, len: usize) -> Range<usize> {
    (index * len / count)..((index + 1) * len / count)
}

/// The points as bits, for exact comparison (`None` stays `None`).
fn bits(points: &[Option<LobePoint>]) -> Vec<Option<[u64; 3]>> {
    points
        .iter()
        .map(|p| {
            p.map(|p| {
                [
                    p.spindle_rpm.to_bits(),
                    p.critical_depth_mm.to_bits(),
                    p.chatter_frequency_hz.to_bits(),
                ]
            })
        })
        .collect()
}

#[test]
fn every_split_of_the_speeds_gives_the_points_of_the_whole_list_bit_for_bit() {
    let speeds = speeds(43);
    let lobes_of = |method, b: Range<usize>| {
        lobes_block(method, &tool(), &modes(), 0.05, Milling::Down, &speeds, b).unwrap()
    };
    for method in [Method::Sdm, Method::Zoa] {
        let whole = lobes_of(method, 0..speeds.len());
        assert_eq!(whole.len(), speeds.len());
        let flat: Vec<LobePoint> = whole.iter().flatten().copied().collect();
        let listed = lobes(method, &tool(), &modes(), 0.05, Milling::Down, &speeds).unwrap();
        assert_eq!(
            listed, flat,
            "{method:?}: lobes is the flattened whole block"
        );
        // 50 blocks of 43 speeds: seven are empty.
        for count in [2, 3, 5, 7, 50] {
            let joined: Vec<Option<LobePoint>> = (0..count)
                .flat_map(|i| lobes_of(method, block(i, count, speeds.len())))
                .collect();
            assert_eq!(bits(&joined), bits(&whole), "{method:?} in {count} blocks");
        }
    }
    // The time domain treats each speed on its own: two speeds in two blocks.
    let two = [9000.0, 10_000.0];
    let td = |b| {
        lobes_block(
            Method::Time,
            &tool(),
            &modes(),
            0.05,
            Milling::Down,
            &two,
            b,
        )
    };
    let whole = td(0..2).unwrap();
    let joined = [td(0..1).unwrap(), td(1..2).unwrap()].concat();
    assert_eq!(bits(&joined), bits(&whole));
}

#[test]
fn the_trace_starts_afresh_at_each_run_of_the_list() {
    let speeds = speeds(3 * TRACE_RUN);
    let sdm = MillingSdm::new(
        &tool(),
        &modes(),
        0.05,
        Milling::Down,
        SdmOptions::default(),
    )
    .unwrap();
    let second_run = TRACE_RUN..2 * TRACE_RUN;
    let in_list = sdm
        .trace_block(&speeds, second_run.clone(), Some(1.0), 20.0, 1e-3)
        .unwrap();
    let alone = sdm
        .trace_block(&speeds[second_run], 0..TRACE_RUN, Some(1.0), 20.0, 1e-3)
        .unwrap();
    assert_eq!(bits(&in_list), bits(&alone));
    // A block inside a run is traced from the run's first speed.
    let inside = sdm
        .trace_block(&speeds, TRACE_RUN + 3..TRACE_RUN + 5, Some(1.0), 20.0, 1e-3)
        .unwrap();
    assert_eq!(bits(&inside), bits(&alone[3..5]));
}

#[test]
fn a_block_beyond_the_list_is_refused() {
    let speeds = speeds(5);
    let e = lobes_block(
        Method::Sdm,
        &tool(),
        &modes(),
        0.05,
        Milling::Down,
        &speeds,
        3..6,
    );
    assert_eq!(
        e.unwrap_err().to_string(),
        "end of the block of speeds must be <= 5, got 6"
    );
    let e = lobes_block(
        Method::Zoa,
        &tool(),
        &modes(),
        0.05,
        Milling::Down,
        &speeds,
        0..9,
    );
    assert!(e.is_err());
    assert_eq!(
        lobes_block(
            Method::Sdm,
            &tool(),
            &modes(),
            0.05,
            Milling::Down,
            &speeds,
            5..5
        ),
        Ok(vec![])
    );
}
