//! The recording of `vmc-twin check`: the program's motion on a cold twin, the fixture and stock
//! bodies on the table (red from the time they are hit), every problem an event.

use std::path::Path;

use vmc_machine::collision::{BodySpec, FixtureSpec, Problem};
use vmc_machine::machine::MachineSpec;
use vmc_machine::motion::Plan;
use vmc_machine::sim::{self, EventLevel, Observer, RunStart, SampleMode, SimConfig, SimEvent};
use vmc_machine::twin::Twin;

use super::scene::mm_to_scene;
use super::{RecordError, RecordSettings, Recorder, RrdFile};

/// The recording of a `check`: the program's motion on a cold twin, every problem an event at
/// its time and place (the contact point, or the tool position for a travel violation); gives
/// the file's size in bytes.
///
/// # Errors
/// The recording cannot be written.
pub fn record_check(
    path: &Path,
    force: bool,
    machine: &MachineSpec,
    fixture: Option<&FixtureSpec>,
    plan: &Plan,
    file: &str,
    problems: &[Problem],
) -> Result<u64, RecordError> {
    let settings = RecordSettings::default();
    let rrd = RrdFile::create(
        path,
        force,
        &format!("vmc-twin check {file} on {}", machine.machine.name),
        super::layout::run_blueprint(settings.magnify),
    )?;
    let mut rec = Recorder::new(&rrd, machine, settings, None)?;
    let mut twin = Twin::new(machine, 1)?;
    rec.on_run_start(&RunStart {
        label: format!("check {file}"),
        time_s: twin.time_s(),
        duration_s: plan.duration_s(),
        measured: false,
    });
    // Fixture and stock bodies ride on the table with the paths (`paths/fixture/<name>`), grey;
    // a body that is hit turns red from the time of the contact.
    let bodies: Vec<&BodySpec> = fixture
        .map(|f| f.bodies.iter().collect())
        .unwrap_or_default();
    let draw = |name: &str, color: [u8; 3], t_s: f64| -> Result<(), RecordError> {
        let Some(b) = bodies.iter().find(|b| b.name == name) else {
            return Ok(());
        };
        let (lo, hi) = match (
            b.min_mm,
            b.max_mm,
            b.base_center_mm,
            b.radius_mm,
            b.height_mm,
        ) {
            (Some(lo), Some(hi), _, _, _) => (lo, hi),
            // A vertical cylinder, drawn as its bounding box.
            (_, _, Some(c), Some(r), Some(h)) => {
                ([c[0] - r, c[1] - r, c[2]], [c[0] + r, c[1] + r, c[2] + h])
            }
            _ => return Ok(()),
        };
        let centre = mm_to_scene([0, 1, 2].map(|a| 0.5 * (lo[a] + hi[a])));
        let half = mm_to_scene([0, 1, 2].map(|a| 0.5 * (hi[a] - lo[a])));
        let stream = rrd.stream();
        stream.set_duration_secs("sim_time", t_s);
        stream
            .log(
                format!("paths/fixture/{name}"),
                &rerun::Boxes3D::from_centers_and_half_sizes([centre], [half])
                    .with_colors([rerun::Color::from_rgb(color[0], color[1], color[2])])
                    .with_labels([name.to_string()]),
            )
            .map_err(|e| RecordError::Rerun {
                path: path.to_path_buf(),
                msg: e.to_string(),
            })?;
        Ok(())
    };
    for b in &bodies {
        draw(&b.name, [150, 150, 150], twin.time_s())?;
    }
    let mut lines = Vec::new();
    for p in problems {
        let (kind, time_s, place) = match p {
            Problem::Collision(c) => ("collision", c.time_s, c.contact_point_mm),
            Problem::Travel(t) => ("travel", t.time_s, plan.position_at(t.time_s)),
        };
        if let Problem::Collision(c) = p {
            draw(
                &c.other_body,
                [230, 40, 40],
                twin.time_s() + c.first_contact_time_s,
            )?;
        }
        lines.push(format!("- {p}"));
        rec.on_event(&SimEvent {
            time_s: twin.time_s() + time_s,
            level: EventLevel::Error,
            kind: kind.into(),
            text: p.to_string(),
            position_mm: Some(place),
        });
    }
    // The motion itself, sampled along the path (at most ~20,000 samples) so the commanded
    // and actual paths are drawn; a program that leaves the travel still shows its problems
    // even if the twin cannot follow it.
    // The cycle is at least 10 ms (and finite: a plan's duration is).
    let cfg = SimConfig::new(1.0, (plan.duration_s() / 20_000.0).max(0.01))
        .unwrap_or_default()
        .sampling(SampleMode::EveryCycle);
    let motion = sim::execute(&mut twin, plan, &cfg, None, &mut rec);
    let mut md = format!("# vmc-twin check: {file}\n\n");
    if problems.is_empty() {
        md.push_str("No problem found.\n");
    } else {
        md.push_str(&format!(
            "{} problem(s), drawn as magenta points at their time (`paths/events`, `events` log):\n\n{}\n",
            problems.len(),
            lines.join("\n")
        ));
    }
    if let Err(e) = &motion {
        md.push_str(&format!("\nThe motion could not be simulated past: {e}\n"));
    }
    rec.finish(Some(&md))?;
    rrd.finish()
}
