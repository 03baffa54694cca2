//! Progress bars for long runs (indicatif), on stderr and only when stderr is a terminal: piped
//! or redirected output stays clean.
//!
//! [`Progress`] serves both the campaign (work units through
//! [`crate::studies::campaign::CampaignProgress`], from parallel runs) and a single run (as a
//! [`vmc_machine::sim::Observer`], its position the simulated time in seconds).

use std::io::IsTerminal;

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use crate::studies::campaign::CampaignProgress;
use vmc_machine::sensors::SensorReadings;
use vmc_machine::sim::{Observer, RunStart};

/// A progress bar on stderr (hidden unless stderr is a terminal).
pub struct Progress {
    bar: ProgressBar,
}

impl Progress {
    /// A bar of `total` units; `unit` names them in the display (e.g. `s` or `units`).
    pub fn new(total: u64, unit: &str) -> Self {
        let target = if std::io::stderr().is_terminal() {
            ProgressDrawTarget::stderr()
        } else {
            ProgressDrawTarget::hidden()
        };
        let bar = ProgressBar::with_draw_target(Some(total), target);
        let template = format!(
            "{{elapsed_precise}} [{{bar:40}}] {{pos}}/{{len}} {unit} (eta {{eta}}) {{msg}}"
        );
        if let Ok(style) = ProgressStyle::with_template(&template) {
            bar.set_style(style.progress_chars("=> "));
        }
        Progress { bar }
    }

    /// Whether the bar is drawn.
    pub fn is_visible(&self) -> bool {
        !self.bar.is_hidden()
    }

    /// Removes the bar from the terminal.
    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }
}

impl CampaignProgress for Progress {
    fn add_total(&self, units: u64) {
        self.bar.inc_length(units);
    }

    fn advance(&self, units: u64, what: &str) {
        self.bar.inc(units);
        self.bar.set_message(what.to_string());
    }
}

impl Observer for Progress {
    fn on_run_start(&mut self, start: &RunStart) {
        self.bar.set_message(start.label.clone());
    }

    fn on_thermal_step(&mut self, time_s: f64, _readings: &SensorReadings) {
        self.bar.set_position(time_s.max(0.0) as u64);
    }
}
