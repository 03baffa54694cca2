//! The setup's artefacts (gauge blocks, reference spheres) as static bodies of the collision
//! scene: any contact with them is a crash, as with a fixture, except the probe's own touch on
//! a probe move.

use parry3d_f64::math::{Pose, Vector};
use parry3d_f64::shape::{Ball, Cuboid};

use super::{BodyRole, Scene, Static};
use crate::probe_setup::{ArtefactSpec, Solid};

impl Scene {
    /// The same scene with `artefacts` on the table (validated entries), checked as fixtures.
    #[must_use]
    pub fn with_artefacts(mut self, artefacts: &[ArtefactSpec]) -> Self {
        for a in artefacts {
            let body = match a.solid() {
                Solid::Box { min_mm, max_mm } => {
                    let half = [0, 1, 2].map(|i| 0.5 * (max_mm[i] - min_mm[i]));
                    let c = [0, 1, 2].map(|i| 0.5 * (max_mm[i] + min_mm[i]));
                    Static {
                        name: a.name.clone(),
                        role: BodyRole::Fixture,
                        shape: Box::new(Cuboid::new(Vector::new(half[0], half[1], half[2]))),
                        pose: Pose::from_translation(Vector::new(c[0], c[1], c[2])),
                        lo_mm: min_mm,
                        hi_mm: max_mm,
                        cut: false,
                    }
                }
                Solid::Sphere {
                    centre_mm: c,
                    radius_mm: r,
                } => Static {
                    name: a.name.clone(),
                    role: BodyRole::Fixture,
                    shape: Box::new(Ball::new(r)),
                    pose: Pose::from_translation(Vector::new(c[0], c[1], c[2])),
                    lo_mm: c.map(|v| v - r),
                    hi_mm: c.map(|v| v + r),
                    cut: false,
                },
                // Artefacts are boxes and spheres only.
                Solid::Cylinder { .. } => continue,
            };
            self.statics.push(body);
        }
        self
    }
}
