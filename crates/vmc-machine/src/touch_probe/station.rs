//! The probe of a placed program: the touch probe, the solids it can touch and where its ball
//! sits on the machine, answering each probe move on the twin (the machine) or on the nominal
//! machine (what the controller expects: `check`, and the first pass of `run`).

use vmc_gcode::interp::ProbeRequest;

use super::{nominal_move, ProbeError, ProbeMotion, ProbeMove, ProbeOnTwin, TouchProbe};
use crate::probe_setup::{NamedSolid, Solid};
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
