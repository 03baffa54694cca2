//! Straight probe moves G38.2 / G38.3 / G38.4 / G38.5 and how their result comes back.
//!
//! Model (LinuxCNC's): a probe move feeds in a straight line toward its target and stops
//! where the probe input changes state — it trips on contact (G38.2, G38.3) or on losing
//! contact (G38.4, G38.5). Where that happened is known only to the machine: the interpreter
//! emits [`CanonKind::Probe`](super::CanonKind::Probe) and then waits for a
//! [`ProbeOutcome`] before it runs the next block. The outcome sets the parameters
//! #5061…#5069 (the probed point — X Y Z A B C U V W — in the program's work coordinates and
//! current units: work offset, G92 offset, XY rotation and tool length removed; U V W are 0)
//! and #5070 (1 if the probe tripped, else 0), and the tool continues from where the machine
//! says it came to rest. G38.2 and G38.4 that end without the state change are errors
//! ("G38.2 move finished without making contact.", "G38.4 move finished without breaking
//! contact.", LinuxCNC's motion controller's words); G38.3 and G38.5 then set #5070 = 0 and
//! #5061… to the target. A probe already in the state the move seeks when it starts is
//! refused by G38.2 and G38.4 and trips at once for G38.3 and G38.5
//! ([`ProbeOutcome::AlreadyInState`]); zero feed, feed per revolution and cutter radius
//! compensation are refused before the move (`exec::probing`).
//!
//! Units: machine coordinates in mm (spindle positions, the tool length included, as every
//! [`CanonKind`](super::CanonKind) move), angles in degrees, feeds in mm/min.

use super::XYZ_STILL_MM;

/// Which of G38.2 … G38.5 a probe move is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ProbeKind {
    /// True for G38.2 / G38.3: stop on contact; false for G38.4 / G38.5: stop on loss of
    /// contact.
    pub toward: bool,
    /// True for G38.2 / G38.4: a move that ends without the probe changing state is an error;
    /// false for G38.3 / G38.5: it sets #5070 = 0.
    pub error_on_no_contact: bool,
}

impl ProbeKind {
    /// The G code: `"G38.2"`, `"G38.3"`, `"G38.4"` or `"G38.5"`.
    pub fn code(self) -> &'static str {
        match (self.toward, self.error_on_no_contact) {
            (true, true) => "G38.2",
            (true, false) => "G38.3",
            (false, true) => "G38.4",
            (false, false) => "G38.5",
        }
    }
}

/// How far LinuxCNC's stand-alone interpreter `rs274` puts the tool back from the target after
/// a probe move, toward the move's start (its canonical layer's stand-in for a machine's stop
/// position), mm: 0.01 inch, whatever the program's units.
pub const STANDALONE_BACKOFF_MM: f64 = 0.254;

/// A probe move waiting for its result (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProbeRequest {
    /// 1-based line of the probe block in its file.
    pub line: usize,
    /// G38.2 … G38.5.
    pub kind: ProbeKind,
    /// Where the tool starts, machine coordinates, mm (after a G40, the compensated point the
    /// exit move leaves from).
    pub start_mm: [f64; 3],
    /// A, B, C at the start, degrees.
    pub start_abc_deg: [f64; 3],
    /// The programmed target, machine coordinates, mm: the move stops there at the latest.
    pub end_mm: [f64; 3],
    /// A, B, C at the target, degrees.
    pub end_abc_deg: [f64; 3],
    /// The feed of the move, mm/min (deg/min for a move of the rotary axes alone).
    pub feed_mm_per_min: f64,
}

impl ProbeRequest {
    /// Where `rs274` leaves the tool after the move: [`STANDALONE_BACKOFF_MM`] back from the
    /// target along the straight XYZ path toward the start (the target itself if X, Y and Z
    /// do not move, that is by at most [`XYZ_STILL_MM`]: the rounding of the coordinate
    /// transforms must not give the back-off a direction); A, B, C at the target.
    pub fn standalone_rest_mm(&self) -> [f64; 3] {
        let d = [0, 1, 2].map(|a| self.start_mm[a] - self.end_mm[a]);
        let length_mm = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        if length_mm <= XYZ_STILL_MM {
            return self.end_mm;
        }
        [0, 1, 2].map(|a| self.end_mm[a] + STANDALONE_BACKOFF_MM * d[a] / length_mm)
    }
}

/// What the machine reports at the end of a probe move.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ProbeOutcome {
    /// The probe changed state at `trip_mm` / `trip_abc_deg` (machine coordinates), and the
    /// tool came to rest at `rest_mm` / `rest_abc_deg` (past the trip point by the stopping
    /// distance on a real machine): #5061… the trip point, #5070 = 1.
    Tripped {
        /// Trip point, machine coordinates, mm.
        trip_mm: [f64; 3],
        /// A, B, C at the trip, degrees.
        trip_abc_deg: [f64; 3],
        /// Where the tool stopped, machine coordinates, mm.
        rest_mm: [f64; 3],
        /// A, B, C where the tool stopped, degrees.
        rest_abc_deg: [f64; 3],
    },
    /// The move reached its target without the probe changing state: an error for G38.2 and
    /// G38.4; for G38.3 and G38.5 #5061… the target and #5070 = 0.
    NoContact,
    /// The probe already read the state the move seeks when the move was to start (a G38.2 or
    /// G38.3 with the stylus deflected, a G38.4 or G38.5 with it clear). LinuxCNC's motion
    /// controller refuses G38.2 and G38.4 then ("Probe is already tripped when starting G38.2
    /// or G38.3 move", "Probe is already clear when starting G38.4 or G38.5 move"); G38.3 and
    /// G38.5 trip at once: #5061… the start point, #5070 = 1, the tool stays where it is.
    AlreadyInState,
    /// No machine, as LinuxCNC's stand-alone `rs274` runs a program: #5061… the target,
    /// #5070 = 0 (its probe input never reads tripped), no error whatever the kind (that error
    /// is the motion controller's, which it has not), and the tool rests at
    /// [`ProbeRequest::standalone_rest_mm`]. [`run_program`](super::run_program) uses it.
    Standalone,
}

/// The values of #5061…#5070 after a probe move (index 0 is #5061): X, Y, Z in program units,
/// A, B, C in degrees, U, V, W (always 0), all in the work coordinates of the program when the
/// move ran; then 1 if the probe tripped, else 0.
pub type ProbeParams = [f64; 10];

/// The first of the probe parameters (#5061).
pub const PROBE_PARAM_FIRST: usize = 5061;

/// A probe move in the call syntax of LinuxCNC's `rs274 -g`: `STRAIGHT_PROBE(x, y, z, a, b,
/// c)` with 4 decimals. `rs274` prints it between `TURN_PROBE_ON()` and `TURN_PROBE_OFF()`,
/// after a `SET_FEED_RATE(…)` when the feed changed, in program coordinates (give it machine
/// coordinates to print those).
///
/// ```
/// use vmc_gcode::interp::straight_probe_call;
/// assert_eq!(
///     straight_probe_call([1.0, 2.0, -3.25], [0.0, 90.0, 0.0]),
///     "STRAIGHT_PROBE(1.0000, 2.0000, -3.2500, 0.0000, 90.0000, 0.0000)"
/// );
/// ```
pub fn straight_probe_call(end_mm: [f64; 3], end_abc_deg: [f64; 3]) -> String {
    format!(
        "STRAIGHT_PROBE({:.4}, {:.4}, {:.4}, {:.4}, {:.4}, {:.4})",
        end_mm[0], end_mm[1], end_mm[2], end_abc_deg[0], end_abc_deg[1], end_abc_deg[2]
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn request(start_mm: [f64; 3], end_mm: [f64; 3]) -> ProbeRequest {
        ProbeRequest {
            line: 1,
            kind: ProbeKind {
                toward: true,
                error_on_no_contact: true,
            },
            start_mm,
            start_abc_deg: [0.0; 3],
            end_mm,
            end_abc_deg: [0.0; 3],
            feed_mm_per_min: 10.0,
        }
    }

    #[test]
    fn the_standalone_rest_is_a_hundredth_of_an_inch_back_toward_the_start() {
        // rs274: G38.2 X5 Z-2 F10 from the origin, then G1 Y1 → STRAIGHT_FEED(4.7642, 1,
        // -1.9057): the tool rested at (4.7642, 0, -1.9057).
        let rest = request([0.0; 3], [5.0, 0.0, -2.0]).standalone_rest_mm();
        assert!((rest[0] - 4.7642).abs() < 5e-5 && (rest[2] + 1.9057).abs() < 5e-5);
        assert_eq!(rest[1], 0.0);
        // A move of the rotary axes alone keeps X, Y, Z, even with the rounding of a rotated
        // frame in its target.
        assert_eq!(request([1.0; 3], [1.0; 3]).standalone_rest_mm(), [1.0; 3]);
        let end = [1.0, 1.0 + 1e-14, 1.0];
        assert_eq!(request([1.0; 3], end).standalone_rest_mm(), end);
    }

    #[test]
    fn kinds_name_their_g_code() {
        let k = |toward, error_on_no_contact| ProbeKind {
            toward,
            error_on_no_contact,
        };
        assert_eq!(
            [
                k(true, true),
                k(true, false),
                k(false, true),
                k(false, false)
            ]
            .map(ProbeKind::code),
            ["G38.2", "G38.3", "G38.4", "G38.5"]
        );
    }
}
