//! The modal state machine: executes decoded blocks in RS274/NGC order (see the parent module).

use super::arc::{arc_center, ArcForm, MM_PER_INCH};
use super::checks::{arc_error_msg, plane_axes};
use super::comp_block::{check_block, selected_radius};
use super::cutter_comp::CutterComp;
use super::cycles::{self, CycleInput, CycleState};
use super::decode::{
    decode, CompMode, Decoded, Distance, FeedMode, Motion, NonModal, Stop, ToolLength, Units,
};
use super::expr::Params;
use super::feed;
use super::probe::ProbeRequest;
use super::{CanonKind, CanonMove, InterpConfig, OrientDirection, PauseKind, Plane, SpindleDir};
use crate::syntax::{Block, GcodeError};

mod block_checks;
use block_checks::motion_col;
mod frame;
pub(super) use frame::COORD_SYSTEMS;
mod modal_state;
mod probing;
use probing::PendingProbe;
mod rotary;
mod state_params;
mod tcp;
mod tool_table;

/// Modal interpreter state; feed it blocks with [`Interpreter::execute_block`].
#[derive(Debug, Clone)]
pub struct Interpreter {
    /// Current tool position, machine coordinates, mm.
    pos_mm: [f64; 3],
    plane: Plane,
    units: Units,
    distance: Distance,
    arc_distance: Distance,
    /// Active work offset G54…G59, G59.1…G59.3 as 0…8.
    coord_index: usize,
    /// Work offsets G54…G59.3 (index 0…8), machine coordinates, mm.
    work_offsets_mm: [[f64; 3]; COORD_SYSTEMS],
    /// XY rotation of each work coordinate system about its origin (G10 L2/L20 R), degrees.
    rotations_deg: [f64; COORD_SYSTEMS],
    /// G92 offset, mm.
    axis_offset_mm: [f64; 3],
    /// `None` after G80 and at start.
    motion: Option<Motion>,
    feed_mm_per_min: f64,
    spindle: (SpindleDir, f64),
    spindle_reported: (SpindleDir, f64),
    /// The tool T selected last (the next M6 loads it).
    selected_tool: u32,
    /// The tool in the spindle (M6, M61): G43 without H and G41/G42 without D use it.
    spindle_tool: u32,
    ended: bool,
    /// (mist, flood).
    coolant: (bool, bool),
    /// G92 offset as stored (G92.2 suspends the active one, G92.3 restores it from here), mm.
    axis_offset_saved_mm: [f64; 3],
    /// G28 and G30 positions, machine coordinates, mm.
    homes_mm: [[f64; 3]; 2],
    /// Active tool length offset (G43/G43.1), along Z, mm.
    tool_offset_mm: f64,
    /// Canned cycle state (G98/G99, initial level, remembered words).
    cycle: CycleState,
    /// G93 / G94 / G95; `feed_mm_per_min` then holds F in 1/min, mm/min or mm/rev.
    feed_mode: FeedMode,
    /// States saved by M70/M73, per call level.
    contexts: modal_state::Contexts,
    /// Tool lengths and diameters (G10 L1/L10/L11 change them).
    tools: tool_table::ToolTable,
    /// Cutter radius compensation; `pos_mm` stays the programmed (uncompensated) position.
    comp: CutterComp,
    /// A, B, C: position, offsets and stored positions, degrees.
    rotary: rotary::RotaryState,
    /// The probe move of the last block while its result is still to come.
    probe: Option<PendingProbe>,
    /// Tool centre point control (G43.4): the machine's rotary axes and the active state.
    tcp: tcp::TcpState,
}

/// What the motion step of a block will do.
#[derive(Debug, Clone, Copy, PartialEq)]
enum MotionStep {
    None,
    Move(Motion),
}

impl Interpreter {
    /// A fresh interpreter in LinuxCNC's start-up state (see the parent module).
    pub fn new(cfg: InterpConfig) -> Self {
        Self {
            work_offsets_mm: cfg.work_offsets_mm,
            rotations_deg: [0.0; COORD_SYSTEMS],
            tools: tool_table::ToolTable::new(&cfg),
            pos_mm: cfg.start_mm,
            plane: Plane::Xy,
            units: Units::Mm,
            distance: Distance::Absolute,
            arc_distance: Distance::Incremental,
            coord_index: 0,
            axis_offset_mm: [0.0; 3],
            motion: None,
            feed_mm_per_min: 0.0,
            spindle: (SpindleDir::Off, 0.0),
            spindle_reported: (SpindleDir::Off, 0.0),
            selected_tool: 0,
            spindle_tool: 0,
            ended: false,
            coolant: (false, false),
            axis_offset_saved_mm: [0.0; 3],
            homes_mm: [[0.0; 3]; 2],
            tool_offset_mm: 0.0,
            cycle: CycleState::default(),
            feed_mode: FeedMode::PerMinute,
            contexts: modal_state::Contexts::default(),
            comp: CutterComp::default(),
            rotary: rotary::RotaryState::new(cfg.start_abc_deg),
            tcp: tcp::TcpState::new(cfg.tcp_axes),
            probe: None,
        }
    }

    /// Current tool position in machine coordinates, mm.
    pub fn position_mm(&self) -> [f64; 3] {
        self.pos_mm
    }

    /// Current angles of the rotary axes A, B, C in machine coordinates, degrees.
    pub fn position_abc_deg(&self) -> [f64; 3] {
        self.rotary.pos_deg
    }

    /// Reads the parameters that mirror the modal state (LinuxCNC's numbers, in mm): G28
    /// position #5161–#5163, G30 #5181–#5183, stored G92 offset #5211–#5213, G54…G59.3
    /// #5221–#5223 … #5381–#5383 and their rotations #5230 … #5390.
    pub(super) fn sync_params_in(&mut self, params: &Params) {
        for a in 0..3 {
            self.homes_mm[0][a] = params.get(5161 + a);
            self.homes_mm[1][a] = params.get(5181 + a);
            self.axis_offset_saved_mm[a] = params.get(5211 + a);
            for (i, offset) in self.work_offsets_mm.iter_mut().enumerate() {
                offset[a] = params.get(5221 + 20 * i + a);
            }
        }
        for (i, r) in self.rotations_deg.iter_mut().enumerate() {
            *r = params.get(5230 + 20 * i);
        }
        self.sync_rotary_params_in(params);
    }

    /// Writes the parameters that mirror the modal state (see [`Self::sync_params_in`]).
    pub(super) fn sync_params_out(&self, params: &mut Params) {
        for a in 0..3 {
            params.set(5161 + a, self.homes_mm[0][a]);
            params.set(5181 + a, self.homes_mm[1][a]);
            params.set(5211 + a, self.axis_offset_saved_mm[a]);
            for (i, offset) in self.work_offsets_mm.iter().enumerate() {
                params.set(5221 + 20 * i + a, offset[a]);
            }
        }
        for (i, r) in self.rotations_deg.iter().enumerate() {
            params.set(5230 + 20 * i, *r);
        }
        params.set(5220, (self.coord_index + 1) as f64);
        self.sync_rotary_params_out(params);
        self.sync_state_params_out(params);
    }

    /// The program's length unit now (G20: inch, G21: mm).
    pub fn length_unit(&self) -> super::LengthUnit {
        match self.units {
            Units::Mm => super::LengthUnit::Mm,
            Units::Inch => super::LengthUnit::Inch,
        }
    }

    /// True once M2/M30 has run; later blocks are ignored.
    pub fn is_ended(&self) -> bool {
        self.ended
    }

    /// Executes one block, appending its canonical actions to `out`. On error nothing of the
    /// block has been executed (the state is unchanged and nothing is appended).
    ///
    /// A block with a probe move (G38.2 … G38.5) returns its [`ProbeRequest`]: the move's
    /// result must come back through [`Self::probe_result`] before the next block, which is
    /// refused until then.
    pub fn execute_block(
        &mut self,
        block: &Block,
        out: &mut Vec<CanonMove>,
    ) -> Result<Option<ProbeRequest>, GcodeError> {
        if let Some(p) = self.probe {
            let msg = format!(
                "the probe move of line {} awaits its result (Interpreter::probe_result)",
                p.request.line
            );
            return Err(GcodeError::invalid(block.line, block.first_col, msg));
        }
        if self.ended {
            return Ok(None);
        }
        let mut next = self.clone();
        let mut kinds = Vec::new();
        next.run_block(block, &mut kinds)?;
        feed::apply(
            next.feed_mode,
            &mut kinds,
            (self.pos_mm, self.rotary.pos_deg),
            next.feed_mm_per_min,
            next.spindle.1,
            next.scale(),
        );
        if let Some(p) = next.probe.as_mut() {
            // The request carries the feed as the move does (deg/min for the rotary axes alone).
            for kind in &kinds {
                if let CanonKind::Probe {
                    feed_mm_per_min, ..
                } = kind
                {
                    p.request.feed_mm_per_min = *feed_mm_per_min;
                }
            }
        }
        next.comp.finish_block(block.line, kinds, next.ended, out);
        *self = next;
        Ok(self.pending_probe())
    }

    /// Releases the output held back by cutter radius compensation (end of the program).
    pub fn flush(&mut self, out: &mut Vec<CanonMove>) {
        self.comp.finish_block(0, Vec::new(), true, out);
    }

    /// Executes a block on `self`; may leave `self` half-updated on error (the caller works on
    /// a copy).
    fn run_block(&mut self, block: &Block, out: &mut Vec<CanonKind>) -> Result<(), GcodeError> {
        let d = decode(block)?;
        let step = self.check(block, &d)?;
        let comp_on_after = match d.cutter_comp {
            Some((mode, _)) => mode != CompMode::Off,
            None => self.comp.is_on(),
        };
        check_block(block, &d, self.comp.is_on(), comp_on_after, self.plane)?;
        let mut emit = |kind| out.push(kind);

        if let Some((mode, _)) = d.feed_mode {
            self.feed_mode = mode;
            self.feed_mm_per_min = 0.0;
        }
        if let Some(f) = d.f {
            let k = match self.feed_mode {
                FeedMode::InverseTime => 1.0,
                _ => self.scale(),
            };
            self.feed_mm_per_min = f.value * k;
        }
        if let Some(s) = d.s {
            self.spindle.1 = s.value;
        }
        if let Some(t) = d.t {
            // Range and integrality checked in `check`.
            self.selected_tool = t.value as u32;
        }
        if d.tool_change.is_some() {
            if let Some(p) = self.comp.take_tool_position() {
                self.pos_mm = p;
            }
            self.spindle.0 = SpindleDir::Off;
            self.report_spindle(&mut emit);
            self.spindle_tool = self.selected_tool;
            emit(CanonKind::ToolChange {
                tool: self.selected_tool,
            });
        }
        if let Some((dir, _)) = d.spindle {
            self.spindle.0 = dir;
        }
        self.report_spindle(&mut emit);
        if d.orient.is_some() {
            // The orientation itself stops the spindle: no separate stop is reported.
            self.spindle.0 = SpindleDir::Off;
            self.spindle_reported = self.spindle;
            emit(CanonKind::SpindleOrient {
                angle_deg: d.r.map_or(0.0, |r| r.value),
                direction: match d.p.map(|p| p.value as u8) {
                    Some(1) => OrientDirection::Clockwise,
                    Some(2) => OrientDirection::CounterClockwise,
                    _ => OrientDirection::Shortest,
                },
                timeout_s: d.q.map(|q| q.value),
            });
        }
        if d.coolant.iter().any(Option::is_some) {
            if d.coolant[2].is_some() {
                self.coolant = (false, false);
            }
            self.coolant.0 |= d.coolant[0].is_some();
            self.coolant.1 |= d.coolant[1].is_some();
            emit(CanonKind::Coolant {
                mist: self.coolant.0,
                flood: self.coolant.1,
            });
        }
        if let Some((m, col)) = d.modal_state {
            self.modal_state_code(m, block.line, col, &mut emit)?;
        }
        if d.set_tool.is_some() {
            self.spindle_tool = d.q.map_or(0, |q| q.value as u32);
        }
        if let Some((m, _)) = d.io {
            emit(CanonKind::Io {
                m,
                p: d.p.map(|w| w.value),
                e: d.e.map(|w| w.value),
                l: d.l.map(|w| w.value),
                q: d.q.map(|w| w.value),
            });
        }
        if let (Some((NonModal::Dwell, _)), Some(p)) = (d.non_modal, d.p) {
            emit(CanonKind::Dwell {
                duration_s: p.value,
            });
        }
        self.plane = d.plane.unwrap_or(self.plane);
        self.units = d.units.unwrap_or(self.units);
        if let Some((mode, col)) = d.cutter_comp {
            self.set_cutter_comp(block, &d, mode, col)?;
        }
        match d.tool_length {
            Some((ToolLength::Table, _)) => {
                let tool = d.h.map_or(self.spindle_tool, |h| h.value as u32);
                self.tool_offset_mm = self.tool_length_mm(tool).unwrap_or(0.0);
            }
            Some((ToolLength::Given, _)) => {
                self.tool_offset_mm = d.axes[2].map_or(0.0, |z| z.value * self.scale());
            }
            Some((ToolLength::Off, _)) => self.tool_offset_mm = 0.0,
            Some((ToolLength::Tcp, _)) => self.tool_offset_mm = 0.0,
            None => {}
        }
        self.set_tcp(&d, step);
        self.coord_index = d.coord_system.unwrap_or(self.coord_index);
        self.distance = d.distance.unwrap_or(self.distance);
        self.arc_distance = d.arc_distance.unwrap_or(self.arc_distance);
        match d.non_modal {
            Some((NonModal::SetAxisOffsets, _)) => {
                self.set_axis_offsets(&d);
                self.axis_offset_saved_mm = self.axis_offset_mm;
                self.set_rotary_axis_offsets(&d);
                self.rotary.g92_saved_deg = self.rotary.g92_deg;
            }
            Some((NonModal::LocalOffsets, _)) => {
                // Absolute values whatever the distance mode; they become the stored G92
                // offset too (G92.2/G92.3 suspend and restore them).
                for (axis, word) in d.axes.iter().enumerate() {
                    if let Some(w) = word {
                        self.axis_offset_mm[axis] = w.value * self.scale();
                    }
                }
                self.axis_offset_saved_mm = self.axis_offset_mm;
                self.set_rotary_local_offsets(&d);
                self.rotary.g92_saved_deg = self.rotary.g92_deg;
            }
            Some((NonModal::ResetAxisOffsets, _)) => {
                self.axis_offset_mm = [0.0; 3];
                self.axis_offset_saved_mm = [0.0; 3];
                self.rotary.g92_deg = [0.0; 3];
                self.rotary.g92_saved_deg = [0.0; 3];
            }
            Some((NonModal::SuspendAxisOffsets, _)) => {
                self.axis_offset_mm = [0.0; 3];
                self.rotary.g92_deg = [0.0; 3];
            }
            Some((NonModal::RestoreAxisOffsets, _)) => {
                self.axis_offset_mm = self.axis_offset_saved_mm;
                self.rotary.g92_deg = self.rotary.g92_saved_deg;
            }
            Some((NonModal::SetHome(i), _)) => {
                self.homes_mm[i] = self.pos_mm;
                self.rotary.homes_deg[i] = self.rotary.pos_deg;
            }
            Some((NonModal::SetCoordData, col)) => {
                if d.l.is_some_and(|l| [1.0, 10.0, 11.0].contains(&l.value)) {
                    self.set_tool_data(&d, block.line, col)?;
                } else {
                    self.set_coord_data(&d);
                }
            }
            Some((NonModal::Home(i), _)) => {
                // Through the intermediate point (current position where no axis is given),
                // then to the stored position along the given axes (all if none is given).
                let via = self.target_mm(&d, false);
                let via_abc = self.target_abc_deg(&d, false);
                emit(CanonKind::Traverse {
                    end_mm: via,
                    end_abc_deg: via_abc,
                });
                let all = !d.has_axis_words();
                let homed = |mut end: [f64; 3], home: [f64; 3], words: &[Option<_>; 3]| {
                    for a in 0..3 {
                        if all || words[a].is_some() {
                            end[a] = home[a];
                        }
                    }
                    end
                };
                let end_mm = homed(via, self.homes_mm[i], &d.axes);
                let end_abc_deg = homed(via_abc, self.rotary.homes_deg[i], &d.abc);
                emit(CanonKind::Traverse {
                    end_mm,
                    end_abc_deg,
                });
                self.pos_mm = end_mm;
                self.rotary.pos_deg = end_abc_deg;
            }
            _ => {}
        }
        if let Some(r) = d.retract {
            self.cycle.retract = r;
        }
        let previous_motion = self.motion;
        if let Some((m, _)) = d.motion {
            self.cycle.motion_mode_set(matches!(m, Motion::Cycle(_)));
            self.motion = Some(m).filter(|m| *m != Motion::Cancel);
        }
        if let MotionStep::Move(m) = step {
            let machine = matches!(d.non_modal, Some((NonModal::MachineCoords, _)));
            let end_mm = self.target_mm(&d, machine);
            let end_abc_deg = self.target_abc_deg(&d, machine);
            let kind = match m {
                Motion::Rapid => Some(CanonKind::Traverse {
                    end_mm,
                    end_abc_deg,
                }),
                Motion::Linear => Some(CanonKind::Feed {
                    end_mm,
                    end_abc_deg,
                    feed_mm_per_min: self.feed_mm_per_min,
                }),
                Motion::Arc { clockwise } => {
                    Some(self.arc(block, &d, (end_mm, end_abc_deg), clockwise)?)
                }
                Motion::Probe(kind) => Some(self.probe_move(
                    block,
                    motion_col(block, &d),
                    kind,
                    (end_mm, end_abc_deg),
                )?),
                Motion::Cycle(cycle) => {
                    let first = previous_motion != Some(m);
                    for kind in self.canned_cycle(block, &d, cycle, first)? {
                        emit(kind);
                    }
                    None
                }
                // `check` never schedules G80 as a move.
                Motion::Cancel => None,
            };
            if let Some(kind) = kind {
                let start_mm = self.pos_mm;
                self.pos_mm = end_mm;
                let turns_rotary = end_abc_deg != self.rotary.pos_deg;
                self.rotary.pos_deg = end_abc_deg;
                if self.comp.takes_motion() {
                    if turns_rotary {
                        let col = d.first_axis_word().map_or(block.first_col, |w| w.col);
                        let msg = "rotary axis motion (A, B, C) with cutter radius \
                                   compensation on is not supported";
                        return Err(GcodeError::unsupported(block.line, col, msg));
                    }
                    let col = motion_col(block, &d);
                    self.comp.motion(start_mm, &kind, out).map_err(|e| {
                        if e.unsupported {
                            GcodeError::unsupported(block.line, col, e.msg)
                        } else {
                            GcodeError::invalid(block.line, col, e.msg)
                        }
                    })?;
                } else {
                    out.push(kind);
                }
            }
        }
        let mut emit = |kind| out.push(kind);
        match d.stop {
            Some((Stop::End, _)) => {
                emit(CanonKind::ProgramEnd);
                self.ended = true;
            }
            Some((Stop::Pause, _)) => emit(CanonKind::Pause(PauseKind::Program)),
            Some((Stop::OptionalPause, _)) => emit(CanonKind::Pause(PauseKind::Optional)),
            Some((Stop::PalletShuttle, _)) => emit(CanonKind::Pause(PauseKind::PalletShuttle)),
            None => {}
        }
        Ok(())
    }

    /// Expands a canned cycle block (see `cycles`); moves the tool to where it ends.
    fn canned_cycle(
        &mut self,
        block: &Block,
        d: &Decoded,
        cycle: cycles::Cycle,
        first: bool,
    ) -> Result<Vec<CanonKind>, GcodeError> {
        let input = CycleInput {
            block,
            d,
            cycle,
            col: d
                .motion
                .map(|m| m.1)
                .or_else(|| d.first_axis_word().map(|w| w.col))
                .unwrap_or(block.first_col),
            first,
            pos_mm: self.pos_mm,
            plane: self.plane,
            incremental: self.distance == Distance::Incremental,
            scale: self.scale(),
            offset_mm: [0, 1, 2].map(|a| self.offset_mm(a)),
            abc_deg: self.rotary.pos_deg,
            feed_mm_per_min: self.feed_mm_per_min,
            spindle: self.spindle,
        };
        let mut out = Vec::new();
        if self.rotation_deg() == 0.0 {
            self.pos_mm = cycles::run(&input, &mut self.cycle, &mut out)?;
            return Ok(out);
        }
        // In a rotated coordinate system the cycle runs in the unrotated frame (the work
        // offset's axes): its points are then turned about the work offset's origin.
        let input = CycleInput {
            pos_mm: self.unrotated_from_machine(self.pos_mm),
            ..input
        };
        let end_mm = cycles::run(&input, &mut self.cycle, &mut out)?;
        self.pos_mm = self.machine_from_unrotated(end_mm);
        for kind in &mut out {
            if let CanonKind::Traverse { end_mm, .. } | CanonKind::Feed { end_mm, .. } = kind {
                *end_mm = self.machine_from_unrotated(*end_mm);
            }
        }
        Ok(out)
    }

    /// G40 / G41 / G42 / G41.1 / G42.1 (checked against the state in `check_block`).
    fn set_cutter_comp(
        &mut self,
        block: &Block,
        d: &Decoded,
        mode: CompMode,
        col: usize,
    ) -> Result<(), GcodeError> {
        let tools = &self.tools;
        let diameter_of = |tool: u32| tools.diameter_mm(tool);
        let radius = selected_radius(
            block,
            d,
            col,
            mode,
            self.spindle_tool,
            self.scale(),
            diameter_of,
        )?;
        if radius.is_some() && self.plane != Plane::Xy && self.rotation_deg() != 0.0 {
            let msg = "cutter radius compensation outside the XY plane in a rotated coordinate \
                       system (G10 L2 R) is not supported";
            return Err(GcodeError::unsupported(block.line, col, msg));
        }
        match radius {
            Some((side, radius_mm)) => {
                let (a1, a2, axis) = plane_axes(self.plane);
                self.comp.turn_on(side, radius_mm, [a1, a2, axis]);
            }
            None => self
                .comp
                .turn_off()
                .map_err(|e| GcodeError::invalid(block.line, col, e.msg))?,
        }
        Ok(())
    }

    /// mm per program unit.
    fn scale(&self) -> f64 {
        match self.units {
            Units::Mm => 1.0,
            Units::Inch => MM_PER_INCH,
        }
    }

    /// Length of tool `tool` from the table (see `tool_table`).
    fn tool_length_mm(&self, tool: u32) -> Option<f64> {
        self.tools.length_mm(tool)
    }

    fn report_spindle(&mut self, emit: &mut impl FnMut(CanonKind)) {
        if self.spindle != self.spindle_reported {
            self.spindle_reported = self.spindle;
            emit(CanonKind::Spindle {
                dir: self.spindle.0,
                rpm: self.spindle.1,
            });
        }
    }

    /// The arc of a G2/G3 block. Word-level checks have been done in `check`.
    fn arc(
        &self,
        block: &Block,
        d: &Decoded,
        (end_mm, end_abc_deg): ([f64; 3], [f64; 3]),
        clockwise: bool,
    ) -> Result<CanonKind, GcodeError> {
        let (a1, a2, _) = plane_axes(self.plane);
        let col = d
            .motion
            .map(|m| m.1)
            .or_else(|| d.first_arc_word().map(|w| w.col))
            .unwrap_or(block.first_col);
        if self.plane != Plane::Xy && self.rotation_deg() != 0.0 {
            let msg = "an arc outside the XY plane in a rotated coordinate system (G10 L2 R) \
                       is not supported";
            return Err(GcodeError::unsupported(block.line, col, msg));
        }
        let start = [self.pos_mm[a1], self.pos_mm[a2]];
        let end = [end_mm[a1], end_mm[a2]];
        let k = self.scale();
        let form = match d.r {
            Some(r) => ArcForm::Radius(r.value * k),
            None => ArcForm::Center(self.arc_centre_mm(d, a1, a2)),
        };
        let c = arc_center(start, end, form, clockwise, self.units == Units::Inch)
            .map_err(|e| GcodeError::invalid(block.line, col, arc_error_msg(&e, k)))?;
        let mut center_mm = self.pos_mm;
        center_mm[a1] = c[0];
        center_mm[a2] = c[1];
        let turns = d.p.map_or(1, |p| p.value.round() as u32);
        Ok(CanonKind::Arc {
            end_mm,
            end_abc_deg,
            center_mm,
            plane: self.plane,
            clockwise,
            extra_turns: turns - 1,
            feed_mm_per_min: self.feed_mm_per_min,
        })
    }
}
