//! Identification from 450 probed points (50 configurations × 9 points): the 50 sphere fits plus
//! the identification (SVD, relations, covariance, Gauss–Newton refinement on the exact model).
//! Target < 100 ms. Measured on the 2-core development machine: see docs/results.md.

use criterion::{criterion_group, criterion_main, Criterion};
use nalgebra::{Matrix3, Vector3};
use vmc_identify::chain::{Chain, Geometry, Pose, RotaryAxis, RotaryGeometry};
use vmc_identify::errors::ParameterSet;
use vmc_identify::identify::{identify, IdentifyOptions, Observation};
use vmc_identify::inverse::{linear_axes_for, nominal_linear_axes};
use vmc_identify::sphere::{default_directions, fit_centre};

fn geometry() -> Geometry {
    Geometry {
        chain: Chain::parse("w C A Y X b Z t").unwrap(),
        rotary: vec![
            RotaryGeometry {
                axis: RotaryAxis::C,
                point_mm: [0.0, 0.0, -450.0],
            },
            RotaryGeometry {
                axis: RotaryAxis::A,
                point_mm: [0.0, 0.0, -500.0],
            },
        ],
        tool_offset_mm: [0.0, 0.0, -150.0],
        datum_mm: [150.0, 0.0, -350.0],
    }
}

/// 50 configurations, each 9 points on the 14.5 mm contact sphere around the exact reading.
fn probed_points() -> Vec<([f64; 2], Vec<Vector3<f64>>)> {
    let g = geometry();
    let set = ParameterSet::location_and_assembly(&g);
    let values: Vec<f64> = (0..set.len())
        .map(|j| if set.params[j].component.is_angle() { 2e-5 } else { 0.02 } * if j % 2 == 0 { 1.0 } else { -1.0 })
        .collect();
    (0..50)
        .map(|i| {
            let rot = [
                (i as f64 * 0.618_033_988_75).fract() * 360.0,
                -100.0 + 120.0 * (i as f64 + 0.5) / 50.0,
            ];
            let q = linear_axes_for(&g, rot, Vector3::zeros(), &|p: &Pose| {
                set.state_at(&values, p)
            })
            .unwrap();
            let pts = default_directions()
                .iter()
                .map(|n| Vector3::from(q) + n * 14.5)
                .collect();
            (rot, pts)
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let g = geometry();
    let set = ParameterSet::location_and_assembly(&g);
    let data = probed_points();
    c.bench_function("identify_450_points", |b| {
        b.iter(|| {
            let obs: Vec<Observation> = data
                .iter()
                .map(|(rot, pts)| {
                    let fit = fit_centre(pts, 14.5).unwrap();
                    Observation {
                        target_w_mm: [0.0; 3],
                        rotary_deg: *rot,
                        nominal_mm: nominal_linear_axes(&g, *rot, Vector3::zeros()),
                        measured_mm: fit.centre_mm.into(),
                        cov_mm2: fit.cov_per_var * 1.5625e-8 + Matrix3::zeros(),
                        placement: 0,
                    }
                })
                .collect();
            identify(&g, &set, &obs, &IdentifyOptions::default()).unwrap()
        });
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
