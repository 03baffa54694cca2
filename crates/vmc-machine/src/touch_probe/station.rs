//! The probe of a placed program: the touch probe, the solids it can touch and where its ball
//! sits on the machine, answering each probe move on the twin (the machine) or on the nominal
//! machine (what the controller expects: `check`, and the first pass of `run`).

use vmc_gcode::interp::ProbeRequest;

use super::{nominal_move, ProbeError, ProbeMotion, ProbeMove, ProbeOnTwin, TouchProbe};
use crate::collision_spec::BodySpec;
use crate::machine::MachineSpec;
use crate::probe_setup::{NamedSolid, Solid};
use crate::setup::Placement;
use crate::twin::Twin;

/// A probe with what it can touch (see the module documentation).
pub struct ProbeStation {
    on_twin: ProbeOnTwin,
    names: Vec<String>,
    solids: Vec<Solid>,
    motion: ProbeMotion,
}

impl ProbeStation {
    /// `probe` among `solids`, its ball placed by `motion`, its trip scatter drawn from `seed`.
    ///
    /// # Errors
    /// A probe setting that is not a usable number.
    pub fn new(
        probe: TouchProbe,
        solids: Vec<NamedSolid>,
        motion: ProbeMotion,
        seed: u64,
    ) -> Result<Self, ProbeError> {
        let (names, solids) = solids.into_iter().map(|s| (s.name, s.solid)).unzip();
        Ok(Self {
            on_twin: ProbeOnTwin::new(probe, seed)?,
            names,
            solids,
            motion,
        })
    }

    /// The probe.
    pub fn probe(&self) -> &TouchProbe {
        self.on_twin.probe()
    }

    /// The name of solid `index` (of a [`ProbeMove::touched`]).
    pub fn solid_name(&self, index: usize) -> &str {
        self.names.get(index).map_or("", String::as_str)
    }

    /// `request` on the nominal machine (no error, no scatter).
    pub fn nominal(&self, request: &ProbeRequest) -> ProbeMove {
        nominal_move(self.probe(), &self.solids, &self.motion, request)
    }

    /// `request` on `twin` at its present state (see [`ProbeOnTwin::straight_move`]).
    ///
    /// # Errors
    /// A probe feed that is not a positive number.
    pub fn on_twin(
        &mut self,
        twin: &mut Twin,
        request: &ProbeRequest,
    ) -> Result<ProbeMove, ProbeError> {
        self.on_twin
            .straight_move(twin, &self.solids, &self.motion, request)
    }
}

impl TouchProbe {
    /// The touch probe of the program's G38 moves on `machine`: the setup's `[probe]`, fields
    /// left out (or the whole section) from [`TouchProbe::typical`] with the machine's own tool
    /// length as the stylus length.
    pub fn of_placement(placement: &Placement, machine: &MachineSpec) -> TouchProbe {
        let spec = placement.probe.unwrap_or_default();
        let d = TouchProbe::typical(
            spec.stylus_length_mm
                .unwrap_or(crate::tools::master_length_mm(machine)),
        );
        TouchProbe {
            stylus_length_mm: d.stylus_length_mm,
            ball_radius_mm: spec.ball_radius_mm.unwrap_or(d.ball_radius_mm),
            trigger_force_n: spec.trigger_force_n.unwrap_or(d.trigger_force_n),
            stylus_stiffness_n_per_um: spec
                .stylus_stiffness_n_per_um
                .unwrap_or(d.stylus_stiffness_n_per_um),
            repeatability_2sigma_um: spec
                .repeatability_2sigma_um
                .unwrap_or(d.repeatability_2sigma_um),
            servo_period_s: spec.servo_period_s.unwrap_or(d.servo_period_s),
            feed_mm_per_min: d.feed_mm_per_min,
        }
    }
}

impl ProbeStation {
    /// The probe station of the program's G38 moves on `machine`: the
    /// [`TouchProbe::of_placement`], what it can touch ([`Placement::probe_solids`] with `extra`), its
    /// trip scatter drawn from `seed`.
    ///
    /// # Errors
    /// A probe setting that is not a usable number.
    pub fn of_placement(
        placement: &Placement,
        machine: &MachineSpec,
        extra: &[BodySpec],
        seed: u64,
    ) -> Result<ProbeStation, ProbeError> {
        let probe = TouchProbe::of_placement(placement, machine);
        let motion = ProbeMotion::of_machine(machine, probe.stylus_length_mm);
        ProbeStation::new(probe, placement.probe_solids(machine, extra), motion, seed)
    }
}
