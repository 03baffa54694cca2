//! Compensation in the loop.
//!
//! What a controller is told, and when, is the [`Controller`] trait: sensor readings and the
//! commanded spindle speed at every sensor sample, the commanded motion segment by segment, and
//! the commanded tool position whenever an axis command is due. [`Compensator`] implements it
//! with a predictor: readings reach the predictor by one door
//! ([`ErrorPredictor::observe_readings`], from [`Controller::on_readings`]), and an axis command
//! is computed under the readings last observed.
//!
//! At each interpolation cycle the controller knows the commanded tool position `p` (workpiece
//! coordinates, mm) and the latest held sensor readings `T` (°C). The machine puts the tool at
//! `q + E(q, T)` when its axes are commanded to `q`, so the axis command that lands the tool on
//! `p` solves `q + E_pred(q, T) = p`, i.e. the fixed point `q = p − E_pred(q, T)`:
//!
//! ```text
//! q₀ = p,   q_{i+1} = p − E_pred(q_i, T),   stop when |q_{i+1} − q_i| < tol (1e-6 mm)
//!                                           or after max_iterations (5) evaluations of E.
//! ```
//!
//! The map is a contraction with factor `L = max ‖∂E/∂q‖` (µm of error change per mm of travel,
//! ~1e-5), so the error after `i` iterations is `~Lⁱ·|E|`: two to three iterations reach the
//! nanometre. At the stopping point the residual `|q + E(q) − p| = |E(q_i) − E(q_{i+1})| ≤ L·tol`.
//! The tool then really lands at `p + E_true(q) − E_pred(q)`.
//!
//! **Approach direction (reversal).** The positioning error of an axis depends on the direction
//! in which it reached its position (backlash-like reversal). Like a CNC's backlash
//! compensation, the compensator keys it on the *commanded* motion, which the controller knows:
//! it keeps the last commanded position per axis, and a change of the commanded position gives
//! that axis's direction of motion (a change below [`DIRECTION_DEADBAND_MM`] or none keeps the
//! last direction; before any motion every axis counts as positive). Every commanded position
//! passed to [`Controller::axis_command_mm`] counts, and so does the commanded trajectory between
//! them when the loop reports it ([`Controller::on_commanded_motion`],
//! [`Compensator::note_commanded_mm`]). An axis whose last motion was negative gets the
//! predictor's [`ErrorPredictor::negative_approach_shift_mm`] added to its component of `E_pred`
//! (a constant, so the fixed-point iteration is unchanged).
//!
//! The compensator is generic over the predictor (static dispatch) and allocation-free; its
//! cost is `iterations × (one predictor query)`.

use crate::predictor::{check_sensor_names, ErrorPredictor, PredictError};

/// Convergence tolerance of the fixed-point step, mm (default: 1e-6 mm = 1 nm).
///
/// Why 1 nm: with a contraction factor ~1e-5 the residual after the stopping step is
/// ≤ 1e-5 · 1 nm, far below any instrument's resolution, and a typical solve then stops after two
/// predictor evaluations (the second step is ~1e-5 × |E| ≈ 0.4 nm) instead of three.
pub const DEFAULT_TOL_MM: f64 = 1e-6;
/// Maximum predictor evaluations per solve (default: 5).
pub const DEFAULT_MAX_ITERATIONS: usize = 5;
/// Smallest change of a commanded axis position that counts as motion, mm (1e-9 mm = 1 pm).
///
/// Why: commanded positions computed along a path carry rounding at the 1e-13 mm level; a
/// reversal must come from real motion, not from the last bit of a float.
pub const DIRECTION_DEADBAND_MM: f64 = 1e-9;

/// A controller in the loop: it turns commanded tool positions into axis commands, knowing
/// only what a machine's controller knows (sensor readings, the commanded spindle speed, the
/// commanded motion), never the machine's state.
pub trait Controller {
    /// New sensor readings `values_degc` (°C, in the machine's sensor order) taken at time
    /// `time_s` (s): at every sensor sample, also between compensated points and while nothing is
    /// compensated (a warm-up, the thermal history before a test), as a controller logging its
    /// sensors sees them. They hold until the next call: every [`Self::axis_command_mm`] after
    /// this call is computed under these readings. Required of every controller (no default),
    /// like the two calls after it: a wrapper around a controller cannot lose a signal by
    /// forgetting to pass it on.
    fn on_readings(&mut self, time_s: f64, values_degc: &[f64]);

    /// The spindle ran at the commanded speed `rpm` since the previous call, up to time `time_s`
    /// (s, the clock of [`Self::on_readings`]): what the controller commanded (S, M3/M5), never
    /// the spindle's state. Called at every sensor sample, after [`Self::on_readings`].
    fn on_spindle_speed(&mut self, time_s: f64, rpm: f64);

    /// The axes ran at the commanded mean speeds `feeds_mm_per_min` (|v| of X, Y, Z, mm/min)
    /// since the previous call, up to `time_s`: what the controller commanded, the heat its
    /// screws and motors take in. Called at every sensor sample, after
    /// [`Self::on_spindle_speed`].
    fn on_axis_feeds(&mut self, time_s: f64, feeds_mm_per_min: [f64; 3]);

    /// The commanded tool path ran one motion segment from `start_mm` to `end_mm` (mm), in
    /// program order, after any points taken on it. Lets a controller follow the commanded
    /// trajectory between the points it compensates (e.g. each axis's direction of motion, for
    /// backlash compensation). Default: ignored.
    fn on_commanded_motion(&mut self, _start_mm: [f64; 3], _end_mm: [f64; 3]) {}

    /// The controller loaded a tool (M6) whose tip sits at `tool_offset_mm` (mm) from the
    /// spindle gauge point, from its own tool table. Default: nothing to do.
    ///
    /// # Errors
    /// A message when the controller cannot compensate with that tool (e.g. a model fitted on
    /// another tool's tip error).
    fn on_tool_change(&mut self, _tool_offset_mm: [f64; 3]) -> Result<(), String> {
        Ok(())
    }

    /// Axis command `q` (mm) for the commanded tool position `p_mm` (mm, workpiece
    /// coordinates), under the readings last given to [`Self::on_readings`].
    fn axis_command_mm(&mut self, p_mm: [f64; 3]) -> [f64; 3];
}

/// How the last solve went.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SolveInfo {
    /// Predictor evaluations used.
    pub iterations: usize,
    /// Size of the last fixed-point step |q_{i+1} − q_i|, mm.
    pub last_step_mm: f64,
    /// Whether the last step was below the tolerance.
    pub converged: bool,
}

/// The reversal `R` (mm) of the axes flagged `negative`, from the predictor's shift.
#[inline(always)]
pub(crate) fn reversal_mm(negative: [bool; 3], shift_mm: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|k| if negative[k] { shift_mm[k] } else { 0.0 })
}

/// The compensation's fixed point (module doc), shared by this compensator and the compiled
/// one: `q₀ = p`, `q_{i+1} = p − E(q_i) − R`, until the step `|q_{i+1} − q_i|` is below `tol_mm`
/// or after `max_iterations` evaluations; `error_mm(i, q)` is the `i`-th evaluation `E(q)` (mm)
/// (the compiled model starts afresh at `i = 0` and moves from the previous iterate after).
/// Generic and inlined: no call, no allocation, the target features of the caller.
#[inline(always)]
pub(crate) fn fixed_point_mm(
    p_mm: [f64; 3],
    reversal_mm: [f64; 3],
    tol_mm: f64,
    max_iterations: usize,
    mut error_mm: impl FnMut(usize, [f64; 3]) -> [f64; 3],
) -> ([f64; 3], SolveInfo) {
    let mut q = p_mm;
    let mut info = SolveInfo::default();
    while info.iterations < max_iterations {
        let mut e = error_mm(info.iterations, q);
        for k in 0..3 {
            e[k] += reversal_mm[k];
        }
        let next = [p_mm[0] - e[0], p_mm[1] - e[1], p_mm[2] - e[2]];
        let d = [next[0] - q[0], next[1] - q[1], next[2] - q[2]];
        info.last_step_mm = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        info.iterations += 1;
        q = next;
        if info.last_step_mm < tol_mm {
            info.converged = true;
            break;
        }
    }
    (q, info)
}

/// Each axis's direction of commanded motion (module doc, "Approach direction"): what every
/// compensator keys the reversal on (this one, the compiled one, and a controller's static
/// tables choosing their forward or reverse column).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ApproachDirections {
    /// Last commanded tool position, mm (None before the first).
    last_commanded_mm: Option<[f64; 3]>,
    /// Whether each axis's last commanded motion was negative.
    negative: [bool; 3],
}

impl ApproachDirections {
    /// Starts from the commanded position `p_mm` (mm), every axis positive.
    pub fn starting_at(p_mm: [f64; 3]) -> Self {
        Self {
            last_commanded_mm: Some(p_mm),
            negative: [false; 3],
        }
    }

    /// Notes a commanded tool position `p_mm` (mm): a change of an axis beyond
    /// [`DIRECTION_DEADBAND_MM`] sets its direction and moves its reference.
    #[inline]
    pub fn note_commanded_mm(&mut self, p_mm: [f64; 3]) {
        if let Some(last) = self.last_commanded_mm {
            for k in 0..3 {
                let d = p_mm[k] - last[k];
                if d > DIRECTION_DEADBAND_MM {
                    self.negative[k] = false;
                } else if d < -DIRECTION_DEADBAND_MM {
                    self.negative[k] = true;
                } else {
                    continue;
                }
                // Only a counted motion moves the reference, so slow creep adds up.
                if let Some(l) = self.last_commanded_mm.as_mut() {
                    l[k] = p_mm[k];
                }
            }
        } else {
            self.last_commanded_mm = Some(p_mm);
        }
    }

    /// Notes one commanded motion segment: the start counts only if no position was known yet.
    #[inline]
    pub fn note_motion_segment_mm(&mut self, start_mm: [f64; 3], end_mm: [f64; 3]) {
        if self.last_commanded_mm.is_none() {
            self.last_commanded_mm = Some(start_mm);
        }
        self.note_commanded_mm(end_mm);
    }

    /// Whether each axis's last commanded motion was negative.
    #[inline]
    pub fn negative(&self) -> [bool; 3] {
        self.negative
    }

    /// `1.0` positive (or no motion yet), `-1.0` negative, per axis.
    pub fn signs(&self) -> [f64; 3] {
        self.negative.map(|n| if n { -1.0 } else { 1.0 })
    }
}

/// Turns commanded tool positions into compensated axis commands with a predictor; the loop's
/// [`Controller`]. It holds nothing of the readings itself: they go to the predictor
/// ([`ErrorPredictor::observe_readings`]), which holds them.
#[derive(Debug, Clone)]
pub struct Compensator<P: ErrorPredictor> {
    predictor: P,
    tol_mm: f64,
    max_iterations: usize,
    last: SolveInfo,
    directions: ApproachDirections,
}

impl<P: ErrorPredictor> Compensator<P> {
    /// A compensator with the default tolerance (1e-6 mm) and iteration cap (5).
    pub fn new(predictor: P) -> Self {
        Self {
            predictor,
            tol_mm: DEFAULT_TOL_MM,
            max_iterations: DEFAULT_MAX_ITERATIONS,
            last: SolveInfo::default(),
            directions: ApproachDirections::default(),
        }
    }

    /// A compensator for a machine with sensors `machine_sensor_names` (checked against the model).
    ///
    /// # Errors
    /// [`PredictError::SensorMismatch`] when names or order differ.
    pub fn for_machine(
        predictor: P,
        machine_sensor_names: &[String],
    ) -> Result<Self, PredictError> {
        check_sensor_names(predictor.sensor_names(), machine_sensor_names)?;
        Ok(Self::new(predictor))
    }

    /// Sets the step tolerance (mm, clamped to ≥ 0) and the evaluation cap (≥ 1).
    #[must_use]
    pub fn with_tolerance(mut self, tol_mm: f64, max_iterations: usize) -> Self {
        self.tol_mm = tol_mm.max(0.0);
        self.max_iterations = max_iterations.max(1);
        self
    }

    /// Sets where the tool is commanded when the compensator takes over (e.g. the program's
    /// start position), so the first motion already gives directions.
    #[must_use]
    pub fn with_start_mm(mut self, p_mm: [f64; 3]) -> Self {
        self.directions = ApproachDirections::starting_at(p_mm);
        self
    }

    /// Notes a commanded tool position `p_mm` (mm) on the trajectory without computing a
    /// command: updates each axis's direction of motion (see the module doc).
    #[inline]
    pub fn note_commanded_mm(&mut self, p_mm: [f64; 3]) {
        self.directions.note_commanded_mm(p_mm);
    }

    /// Notes one commanded motion segment from `start_mm` to `end_mm` (mm): the start counts
    /// only if no position was known yet (the segments of a path join end to start).
    #[inline]
    pub fn note_motion_segment_mm(&mut self, start_mm: [f64; 3], end_mm: [f64; 3]) {
        self.directions.note_motion_segment_mm(start_mm, end_mm);
    }

    /// Direction of each axis's last commanded motion: `1.0` positive (or none yet), `-1.0`
    /// negative.
    pub fn approach_directions(&self) -> [f64; 3] {
        self.directions.signs()
    }

    /// How the last [`Controller::axis_command_mm`] went.
    pub fn last_solve(&self) -> SolveInfo {
        self.last
    }

    /// The predictor.
    pub fn predictor(&self) -> &P {
        &self.predictor
    }

    /// The predictor, mutably (e.g. to query it directly for a report).
    pub fn predictor_mut(&mut self) -> &mut P {
        &mut self.predictor
    }

    /// Gives the predictor back.
    pub fn into_inner(self) -> P {
        self.predictor
    }
}

/// The loop's door to the predictor: readings and the spindle speed go to the predictor, the
/// commanded motion to the approach directions.
impl<P: ErrorPredictor> Controller for Compensator<P> {
    fn on_readings(&mut self, time_s: f64, values_degc: &[f64]) {
        self.predictor.observe_readings(time_s, values_degc);
    }

    fn on_spindle_speed(&mut self, time_s: f64, rpm: f64) {
        self.predictor.observe_spindle_speed(time_s, rpm);
    }

    fn on_axis_feeds(&mut self, time_s: f64, feeds_mm_per_min: [f64; 3]) {
        self.predictor.observe_axis_feeds(time_s, feeds_mm_per_min);
    }

    fn on_commanded_motion(&mut self, start_mm: [f64; 3], end_mm: [f64; 3]) {
        self.note_motion_segment_mm(start_mm, end_mm);
    }

    fn on_tool_change(&mut self, tool_offset_mm: [f64; 3]) -> Result<(), String> {
        self.predictor
            .change_tool(tool_offset_mm)
            .map_err(|e| e.to_string())
    }

    /// Axis command `q` (mm) that should put the tool at `p_mm` under the readings last
    /// observed; `p_mm` also counts as commanded motion for the approach directions.
    /// Allocation-free; see the module doc for the iteration.
    #[inline]
    fn axis_command_mm(&mut self, p_mm: [f64; 3]) -> [f64; 3] {
        self.note_commanded_mm(p_mm);
        let reversal_mm = reversal_mm(
            self.directions.negative(),
            self.predictor.negative_approach_shift_mm(),
        );
        let predictor = &mut self.predictor;
        let (q, info) = fixed_point_mm(
            p_mm,
            reversal_mm,
            self.tol_mm,
            self.max_iterations,
            |_, q| predictor.predict_error_mm(q),
        );
        self.last = info;
        q
    }
}

/// The integration tests' counting allocator (the one copy), for the no-allocation test.
#[cfg(test)]
#[path = "../tests/common/counting_alloc.rs"]
mod counting_alloc;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::predictor::{train_hybrid, train_linear, AnyPredictor, Settings};

    /// A smooth analytic error field of tens of µm with a thermal scale factor.
    #[derive(Debug)]
    struct Analytic {
        sensors: Vec<String>,
        /// The reading last observed, °C.
        t_degc: f64,
    }

    fn analytic_e(q: [f64; 3], t: f64) -> [f64; 3] {
        let s = 1.0 + 0.1 * (t - 20.0);
        [
            s * (0.02 * (q[1] / 80.0).sin() + 3e-5 * q[0] + 1e-5 * q[2]),
            s * (0.015 * (q[0] / 120.0).cos() - 2e-5 * q[2]),
            s * (0.03 * (q[0] * q[1] / 40000.0).sin() + 1e-5 * q[2]),
        ]
    }

    impl ErrorPredictor for Analytic {
        fn observe_spindle_speed(&mut self, _time_s: f64, _rpm: f64) {}
        fn observe_axis_feeds(&mut self, _time_s: f64, _feeds_mm_per_min: [f64; 3]) {}
        fn sensor_names(&self) -> &[String] {
            &self.sensors
        }
        fn predict_error_mm(&mut self, q_mm: [f64; 3]) -> [f64; 3] {
            analytic_e(q_mm, self.t_degc)
        }
        fn observe_readings(&mut self, _: f64, temps_degc: &[f64]) {
            self.t_degc = temps_degc[0];
        }
    }

    fn analytic() -> Analytic {
        Analytic {
            sensors: vec!["T".into()],
            t_degc: f64::NAN,
        }
    }

    #[test]
    fn fixed_point_solve_leaves_a_residual_below_a_picometre() {
        let mut c = Compensator::new(analytic());
        for p in [
            [0.0, 0.0, 0.0],
            [300.0, 150.0, -200.0],
            [560.0, 400.0, -450.0],
        ] {
            for t in [20.0, 26.0] {
                c.on_readings(0.0, &[t]);
                let q = c.axis_command_mm(p);
                let e = analytic_e(q, t);
                let residual = ((q[0] + e[0] - p[0]).powi(2)
                    + (q[1] + e[1] - p[1]).powi(2)
                    + (q[2] + e[2] - p[2]).powi(2))
                .sqrt();
                // 1e-9 mm = 1 pm; the uncompensated error |E(p)| is tens of µm.
                assert!(residual < 1e-9, "residual {residual} mm at {p:?}");
                let info = c.last_solve();
                assert!(info.converged && info.iterations <= 4, "{info:?}");
                assert!(q != p, "a non-zero error must move the axes");
            }
        }
    }

    #[test]
    fn the_iteration_cap_is_respected_and_reported() {
        /// A field too steep to converge: E = 0.9·q (a contraction with factor 0.9).
        struct Steep(Vec<String>);
        impl ErrorPredictor for Steep {
            fn observe_spindle_speed(&mut self, _time_s: f64, _rpm: f64) {}
            fn observe_axis_feeds(&mut self, _time_s: f64, _feeds_mm_per_min: [f64; 3]) {}
            fn sensor_names(&self) -> &[String] {
                &self.0
            }
            fn predict_error_mm(&mut self, q: [f64; 3]) -> [f64; 3] {
                q.map(|v| 0.9 * v)
            }
            fn observe_readings(&mut self, _: f64, _: &[f64]) {}
        }
        let mut c = Compensator::new(Steep(vec!["T".into()]));
        c.axis_command_mm([100.0, 0.0, 0.0]);
        let info = c.last_solve();
        assert_eq!(info.iterations, 5);
        assert!(!info.converged && info.last_step_mm > 1.0, "{info:?}");
        let mut c = c.with_tolerance(1e-7, 2);
        c.axis_command_mm([100.0, 0.0, 0.0]);
        assert_eq!(c.last_solve().iterations, 2);
    }

    /// Zero error except a reversal: E_k shifts by `shift[k]` after a negative approach of k.
    struct ReversalOnly(Vec<String>, [f64; 3]);
    impl ErrorPredictor for ReversalOnly {
        fn observe_spindle_speed(&mut self, _time_s: f64, _rpm: f64) {}
        fn observe_axis_feeds(&mut self, _time_s: f64, _feeds_mm_per_min: [f64; 3]) {}
        fn sensor_names(&self) -> &[String] {
            &self.0
        }
        fn predict_error_mm(&mut self, _: [f64; 3]) -> [f64; 3] {
            [0.0; 3]
        }
        fn observe_readings(&mut self, _: f64, _: &[f64]) {}
        fn negative_approach_shift_mm(&self) -> [f64; 3] {
            self.1
        }
    }

    #[test]
    fn the_approach_direction_follows_the_commanded_positions() {
        let shift = [-0.25e-3, -0.3e-3, 0.25e-3];
        let mut c = Compensator::new(ReversalOnly(vec!["T".into()], shift));
        // Before any motion every axis counts as positive: no reversal applied.
        assert_eq!(
            c.axis_command_mm([100.0, 50.0, -10.0]),
            [100.0, 50.0, -10.0]
        );
        assert_eq!(c.approach_directions(), [1.0, 1.0, 1.0]);
        // X back, Y forward, Z back: X and Z get their shift subtracted (q = p − E).
        let q = c.axis_command_mm([90.0, 60.0, -20.0]);
        assert_eq!(c.approach_directions(), [-1.0, 1.0, -1.0]);
        assert_eq!(q, [90.0 + 0.25e-3, 60.0, -20.0 - 0.25e-3]);
        // No change keeps the last direction (a dwell re-commands the same point).
        assert_eq!(c.axis_command_mm([90.0, 60.0, -20.0]), q);
        // A change below the dead band (1 pm) is not motion.
        c.note_commanded_mm([90.0 + 1e-12, 60.0, -20.0]);
        assert_eq!(c.approach_directions(), [-1.0, 1.0, -1.0]);
        // Motion between the points (reported by the loop) counts: X overshoots and comes back
        // up to the same point, so it now approaches positively.
        c.note_commanded_mm([80.0, 60.0, -20.0]);
        let q = c.axis_command_mm([90.0, 60.0, -20.0]);
        assert_eq!(c.approach_directions(), [1.0, 1.0, -1.0]);
        assert_eq!(q, [90.0, 60.0, -20.0 - 0.25e-3]);
    }

    #[test]
    fn a_start_position_gives_the_first_points_direction() {
        let shift = [1e-3; 3];
        let c = Compensator::new(ReversalOnly(vec!["T".into()], shift));
        let mut c = c.with_start_mm([0.0, 0.0, 0.0]);
        c.axis_command_mm([540.0, 20.0, -430.0]);
        assert_eq!(c.approach_directions(), [1.0, 1.0, -1.0]);
    }

    #[test]
    fn zero_error_commands_the_nominal_position_in_one_evaluation() {
        struct Zero(Vec<String>);
        impl ErrorPredictor for Zero {
            fn observe_spindle_speed(&mut self, _time_s: f64, _rpm: f64) {}
            fn observe_axis_feeds(&mut self, _time_s: f64, _feeds_mm_per_min: [f64; 3]) {}
            fn sensor_names(&self) -> &[String] {
                &self.0
            }
            fn predict_error_mm(&mut self, _: [f64; 3]) -> [f64; 3] {
                [0.0; 3]
            }
            fn observe_readings(&mut self, _: f64, _: &[f64]) {}
        }
        let mut c = Compensator::new(Zero(vec!["T".into()]));
        assert_eq!(c.axis_command_mm([1.0, 2.0, 3.0]), [1.0, 2.0, 3.0]);
        assert_eq!(c.last_solve().iterations, 1);
    }

    #[test]
    fn a_compensator_for_a_machine_with_other_sensors_is_refused() {
        let err = Compensator::for_machine(analytic(), &["T".into(), "U".into()]).unwrap_err();
        assert!(matches!(err, PredictError::SensorMismatch { .. }), "{err}");
        assert!(Compensator::for_machine(analytic(), &["T".into()]).is_ok());
    }

    #[test]
    fn compensating_with_a_trained_model_removes_most_of_the_true_error() {
        use crate::predictor::testdata as td;
        let ds = td::dataset(&[4.0, 7.0, 5.5, 3.0], 11);
        let (p, _) = train_linear(&ds, &td::geometry(), &Settings::default()).unwrap();
        let mut c = Compensator::new(AnyPredictor::Linear(p));
        let (mut before, mut after) = (0.0, 0.0);
        for (p_mm, t, _) in td::held_out(6.0, 5) {
            c.on_readings(0.0, &t);
            let q = c.axis_command_mm(p_mm);
            // The tool really lands at q + E_true(q).
            let e_at_q = td::true_error_mm(q, &t);
            let landed: [f64; 3] = std::array::from_fn(|k| q[k] + e_at_q[k] - p_mm[k]);
            let e_nominal = td::true_error_mm(p_mm, &t);
            before += e_nominal.iter().map(|v| v * v).sum::<f64>();
            after += landed.iter().map(|v| v * v).sum::<f64>();
        }
        let reduction = 1.0 - (after / before).sqrt();
        assert!(reduction > 0.5, "reduction {reduction}");
    }

    // Allocation counting for the no-allocation test (per thread, so parallel tests don't mix).
    use super::counting_alloc::allocations;

    #[test]
    fn compensation_queries_do_not_allocate() {
        use crate::predictor::testdata as td;
        let ds = td::dataset(&[4.0, 7.0], 2);
        let quick = Settings {
            hidden_candidates: vec![6],
            max_epochs: 5,
            ..Settings::default()
        };
        let (h, _) = train_hybrid(&ds, &td::geometry(), &quick).unwrap();
        let (l, _) = train_linear(&ds, &td::geometry(), &quick).unwrap();
        let (v, _) = crate::predictor::train_volumetric(&ds, &td::geometry(), &quick).unwrap();
        for model in [
            AnyPredictor::Hybrid(h),
            AnyPredictor::Linear(l),
            AnyPredictor::Volumetric(v),
        ] {
            let mut c = Compensator::new(model);
            let temps = [td::temps_degc(5.0, 1000.0), td::temps_degc(5.0, 2000.0)];
            let before = allocations();
            for i in 0..1000 {
                if i % 500 == 0 {
                    c.on_readings(i as f64, &temps[i / 500]);
                }
                let p = [i as f64 * 0.5, 200.0 - i as f64 * 0.1, -100.0];
                std::hint::black_box(c.axis_command_mm(p));
            }
            let after = allocations();
            assert_eq!(after - before, 0, "{:?} allocated", c.predictor().kind());
        }
    }
}
