//! The 3-D scene of a recording: simple boxes for the machine's bodies, placed from the machine
//! description's travels and tool, and where each thermal node sits on them.
//!
//! # Frames and units
//! The scene frame is the **bed** frame, Z up, in **metres** (what the viewer's grid and camera
//! assume); this module works in mm and [`mm_to_scene`] converts. The spindle axis stands over
//! the middle of the travel, `S = (x_mid, y_mid)`. For axis position `q` (the tool tip relative
//! to the workpiece, machine coordinates, mm) the bodies of a `w X Y b Z t` machine move as:
//! - table (carries the workpiece, rides X on the saddle): translation `(Sx − qx, Sy − qy, 0)`;
//!   its local frame *is* the workpiece frame, so paths drawn in workpiece coordinates under the
//!   same translation ride on the table;
//! - saddle (rides Y on the bed): translation `(0, Sy − qy, 0)`;
//! - head (rides Z on the column): translation `(Sx, Sy, qz)`; its local origin is the tool tip;
//! - bed and column: fixed.
//!
//! The sizes are illustrative (derived from the travels), not the machine's real castings. The
//! thermal nodes of the network have no coordinates in the machine description; they are placed
//! by name (`spindle_*`, `headstock_<side>`, `column_<level>_<face>`, `<axis>_motor`,
//! `<axis>_support`, `<axis>_screw_<k>`, `saddle`, `table`, `bed_top`, `bed_bottom`,
//! `work_zone`). Nodes with other names are not drawn.

use vmc_machine::machine::MachineSpec;

/// Converts a position in mm to scene units (m, f32).
pub fn mm_to_scene(p_mm: [f64; 3]) -> [f32; 3] {
    [0, 1, 2].map(|a| (p_mm[a] * 1e-3) as f32)
}

/// A moving or fixed body of the machine.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Body {
    /// Bed (fixed).
    Bed,
    /// Column (fixed).
    Column,
    /// Saddle (Y).
    Saddle,
    /// Table and workpiece (X on the saddle).
    Table,
    /// Headstock, spindle and tool (Z).
    Head,
}

impl Body {
    /// Entity path of the body under `machine/`.
    pub fn entity(self) -> &'static str {
        match self {
            Body::Bed => "machine/bed",
            Body::Column => "machine/column",
            Body::Saddle => "machine/saddle",
            Body::Table => "machine/table",
            Body::Head => "machine/head",
        }
    }

    /// The moving bodies (with a transform per axis position).
    pub const MOVING: [Body; 3] = [Body::Saddle, Body::Table, Body::Head];
}

/// One box of a body: centre and half sizes in the body's local frame (mm), colour, label.
#[derive(Debug, Clone, PartialEq)]
pub struct BodyBox {
    /// Centre, mm (local frame).
    pub center_mm: [f64; 3],
    /// Half sizes, mm.
    pub half_mm: [f64; 3],
    /// RGBA.
    pub rgba: [u8; 4],
    /// Label shown on hover.
    pub label: &'static str,
}

/// Machine scene derived from a machine description.
#[derive(Debug, Clone)]
pub struct Scene {
    /// Spindle axis position in the bed frame (x, y), mm.
    pub spindle_xy_mm: [f64; 2],
    travel_min_mm: [f64; 3],
    travel_max_mm: [f64; 3],
    tool_len_mm: f64,
    tool_radius_mm: f64,
    /// Table top height in workpiece (table) coordinates, mm.
    table_top_mm: f64,
    /// Bed top height, mm (bed frame).
    bed_top_mm: f64,
    /// Column front face, y in the bed frame, mm.
    column_front_y_mm: f64,
    /// Column depth, mm.
    column_depth_mm: f64,
    /// Column top, z in the bed frame, mm.
    column_top_mm: f64,
}

impl Scene {
    /// The scene of a machine.
    pub fn new(spec: &MachineSpec) -> Self {
        let min = spec.axes.travel_min_mm;
        let max = spec.axes.travel_max_mm;
        let span = [0, 1, 2].map(|a| (max[a] - min[a]).max(1.0));
        let mid = [0, 1, 2].map(|a| 0.5 * (min[a] + max[a]));
        let off = spec.tool.offset_mm;
        let tool_len_mm = (off[0] * off[0] + off[1] * off[1] + off[2] * off[2])
            .sqrt()
            .max(10.0);
        let table_top_mm = min[2] - 50.0;
        let bed_top_mm = table_top_mm - 60.0 - 100.0;
        // The table reaches furthest back (+y) at qy = min: Sy − min + mid + half table.
        let table_back = mid[1] - min[1] + mid[1] + 0.55 * span[1];
        let column_front_y_mm = table_back + 0.1 * span[1];
        Scene {
            spindle_xy_mm: [mid[0], mid[1]],
            travel_min_mm: min,
            travel_max_mm: max,
            tool_len_mm,
            tool_radius_mm: 0.5 * spec.tool.diameter_mm.max(1.0),
            table_top_mm,
            bed_top_mm,
            column_front_y_mm,
            column_depth_mm: 0.6 * span[1],
            column_top_mm: max[2] + tool_len_mm + 600.0,
        }
    }

    fn span(&self, a: usize) -> f64 {
        (self.travel_max_mm[a] - self.travel_min_mm[a]).max(1.0)
    }

    fn mid(&self, a: usize) -> f64 {
        0.5 * (self.travel_min_mm[a] + self.travel_max_mm[a])
    }

    /// Translation of a body's local frame in the bed frame for axis position `q_mm`, mm.
    pub fn body_translation_mm(&self, body: Body, q_mm: [f64; 3]) -> [f64; 3] {
        let [sx, sy] = self.spindle_xy_mm;
        match body {
            Body::Bed | Body::Column => [0.0; 3],
            Body::Saddle => [0.0, sy - q_mm[1], 0.0],
            Body::Table => [sx - q_mm[0], sy - q_mm[1], 0.0],
            Body::Head => [sx, sy, q_mm[2]],
        }
    }

    /// Tool length (tool tip to spindle gauge point), mm.
    pub fn tool_len_mm(&self) -> f64 {
        self.tool_len_mm
    }

    /// Tool radius, mm.
    pub fn tool_radius_mm(&self) -> f64 {
        self.tool_radius_mm
    }

    /// The boxes of a body, in its local frame.
    pub fn boxes(&self, body: Body) -> Vec<BodyBox> {
        let (sx, sy) = (self.spindle_xy_mm[0], self.spindle_xy_mm[1]);
        let (lx, ly) = (self.span(0), self.span(1));
        let (cx, cy) = (self.mid(0), self.mid(1));
        let lt = self.tool_len_mm;
        match body {
            Body::Bed => {
                let y0 = sy - (self.mid(1) - self.travel_min_mm[1]) - 0.7 * ly;
                let y1 = self.column_front_y_mm + self.column_depth_mm;
                vec![BodyBox {
                    center_mm: [sx, 0.5 * (y0 + y1), self.bed_top_mm - 150.0],
                    half_mm: [0.6 * lx, 0.5 * (y1 - y0), 150.0],
                    rgba: [70, 74, 82, 255],
                    label: "bed",
                }]
            }
            Body::Column => {
                let z0 = self.bed_top_mm;
                let z1 = self.column_top_mm;
                vec![BodyBox {
                    center_mm: [
                        sx,
                        self.column_front_y_mm + 0.5 * self.column_depth_mm,
                        0.5 * (z0 + z1),
                    ],
                    half_mm: [0.32 * lx, 0.5 * self.column_depth_mm, 0.5 * (z1 - z0)],
                    rgba: [96, 110, 130, 255],
                    label: "column",
                }]
            }
            Body::Saddle => vec![BodyBox {
                center_mm: [sx, cy, self.table_top_mm - 60.0 - 50.0],
                half_mm: [0.42 * lx, 0.6 * ly, 50.0],
                rgba: [120, 124, 132, 255],
                label: "saddle (Y)",
            }],
            Body::Table => vec![
                BodyBox {
                    center_mm: [cx, cy, self.table_top_mm - 30.0],
                    half_mm: [0.62 * lx, 0.55 * ly, 30.0],
                    rgba: [165, 170, 178, 255],
                    label: "table (X)",
                },
                BodyBox {
                    center_mm: [cx, cy, self.table_top_mm + 10.0],
                    half_mm: [0.5 * lx, 0.45 * ly, 10.0],
                    rgba: [200, 190, 160, 255],
                    label: "workpiece fixture plate",
                },
            ],
            Body::Head => {
                let back = self.column_front_y_mm - sy;
                vec![
                    BodyBox {
                        center_mm: [0.0, 0.0, lt + 110.0],
                        half_mm: [55.0, 55.0, 110.0],
                        rgba: [210, 130, 50, 255],
                        label: "spindle",
                    },
                    BodyBox {
                        center_mm: [0.0, 0.5 * (back - 140.0), lt + 380.0],
                        half_mm: [140.0, 0.5 * (back + 140.0), 160.0],
                        rgba: [225, 150, 70, 255],
                        label: "headstock (Z)",
                    },
                ]
            }
        }
    }

    /// Where a thermal node sits: its body and local position (mm), or None if its name does
    /// not say. `screws[a]` is the number of `<axis>_screw_<k>` nodes of axis `a`.
    pub fn node_place(&self, name: &str, screws: [usize; 3]) -> Option<(Body, [f64; 3])> {
        let (sx, sy) = (self.spindle_xy_mm[0], self.spindle_xy_mm[1]);
        let (lx, ly) = (self.span(0), self.span(1));
        let cy = self.mid(1);
        let lt = self.tool_len_mm;
        let back = self.column_front_y_mm - sy;
        let head = |p: [f64; 3]| Some((Body::Head, p));
        let col_y = |face: &str| match face {
            "front" => Some(self.column_front_y_mm + 20.0),
            "back" => Some(self.column_front_y_mm + self.column_depth_mm - 20.0),
            _ => None,
        };
        let col_z = |level: &str| {
            let (z0, z1) = (self.bed_top_mm, self.column_top_mm);
            match level {
                "top" => Some(z1 - 0.15 * (z1 - z0)),
                "mid" => Some(0.5 * (z0 + z1)),
                "bottom" => Some(z0 + 0.15 * (z1 - z0)),
                _ => None,
            }
        };
        let saddle_top = self.table_top_mm - 60.0;
        // Ends of each axis drive: (motor end, support end) in the carrying body's frame.
        let drive = |axis: usize| -> (Body, [f64; 3], [f64; 3]) {
            match axis {
                0 => (
                    Body::Saddle,
                    [sx + 0.45 * lx, cy, saddle_top],
                    [sx - 0.45 * lx, cy, saddle_top],
                ),
                1 => {
                    let y0 = sy - (self.mid(1) - self.travel_min_mm[1]) - 0.5 * ly;
                    let y1 = self.column_front_y_mm - 20.0;
                    (
                        Body::Bed,
                        [sx, y1, self.bed_top_mm],
                        [sx, y0, self.bed_top_mm],
                    )
                }
                _ => {
                    let y = self.column_front_y_mm - 10.0;
                    (
                        Body::Column,
                        [sx, y, self.column_top_mm - 30.0],
                        [sx, y, self.bed_top_mm + 60.0],
                    )
                }
            }
        };
        let axis_of = |c: &str| match c {
            "x" => Some(0usize),
            "y" => Some(1),
            "z" => Some(2),
            _ => None,
        };
        match name {
            "spindle_nose" => return head([0.0, 0.0, lt + 10.0]),
            "spindle_front_bearing" => return head([0.0, 0.0, lt + 40.0]),
            "spindle_housing" => return head([45.0, 0.0, lt + 120.0]),
            "spindle_rear_bearing" => return head([0.0, 0.0, lt + 200.0]),
            "spindle_motor" => return head([0.0, 0.0, lt + 480.0]),
            "headstock_left" => return head([-140.0, 0.4 * back, lt + 380.0]),
            "headstock_right" => return head([140.0, 0.4 * back, lt + 380.0]),
            "headstock_front" => return head([0.0, -140.0, lt + 380.0]),
            "headstock_back" => return head([0.0, back, lt + 380.0]),
            "saddle" => return Some((Body::Saddle, [sx, cy, saddle_top - 50.0])),
            "table" => return Some((Body::Table, [self.mid(0), cy, self.table_top_mm - 30.0])),
            "work_zone" => return Some((Body::Table, [self.mid(0), cy, self.table_top_mm + 80.0])),
            "bed_top" => return Some((Body::Bed, [sx, cy, self.bed_top_mm - 40.0])),
            "bed_bottom" => return Some((Body::Bed, [sx, cy, self.bed_top_mm - 260.0])),
            _ => {}
        }
        let parts: Vec<&str> = name.split('_').collect();
        match parts.as_slice() {
            ["column", level, face] => Some((Body::Column, [sx, col_y(face)?, col_z(level)?])),
            [a, "motor"] => {
                let (b, motor, _) = drive(axis_of(a)?);
                Some((b, motor))
            }
            [a, "support"] => {
                let (b, _, support) = drive(axis_of(a)?);
                Some((b, support))
            }
            [a, "screw", k] => {
                let axis = axis_of(a)?;
                let k: usize = k.parse().ok()?;
                let n = screws[axis].max(1);
                let (b, motor, support) = drive(axis);
                // Segment k of n between the motor end (k = 0) and the support end.
                let f = (k as f64 + 0.5) / n as f64;
                Some((b, [0, 1, 2].map(|i| motor[i] + f * (support[i] - motor[i]))))
            }
            _ => None,
        }
    }
}

/// Counts `<axis>_screw_<k>` nodes per axis.
pub fn screw_counts(node_names: &[String]) -> [usize; 3] {
    let mut n = [0; 3];
    for name in node_names {
        for (a, p) in ["x_screw_", "y_screw_", "z_screw_"].iter().enumerate() {
            if name.starts_with(p) {
                n[a] += 1;
            }
        }
    }
    n
}

/// Colour of a temperature on a blue → green → yellow → red ramp over `[lo, hi]` °C.
pub fn temp_rgba(temp_degc: f64, lo_degc: f64, hi_degc: f64) -> [u8; 4] {
    let f = ((temp_degc - lo_degc) / (hi_degc - lo_degc)).clamp(0.0, 1.0);
    let stops: [[f64; 3]; 5] = [
        [40.0, 70.0, 200.0],
        [40.0, 170.0, 220.0],
        [80.0, 200.0, 80.0],
        [240.0, 210.0, 40.0],
        [220.0, 40.0, 30.0],
    ];
    let x = f * (stops.len() - 1) as f64;
    let i = (x.floor() as usize).min(stops.len() - 2);
    let t = x - i as f64;
    let c = [0, 1, 2].map(|k| (stops[i][k] + t * (stops[i + 1][k] - stops[i][k])).round() as u8);
    [c[0], c[1], c[2], 255]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tool_tip_stays_on_the_spindle_axis_and_paths_ride_the_table() {
        let spec = MachineSpec::reference();
        let s = Scene::new(&spec);
        let q = [123.0, 45.0, -300.0];
        // A workpiece point at the commanded position lands under the tool tip.
        let t = s.body_translation_mm(Body::Table, q);
        let head = s.body_translation_mm(Body::Head, q);
        let tip_on_table = [q[0] + t[0], q[1] + t[1], q[2] + t[2]];
        assert_eq!(tip_on_table, head);
    }

    #[test]
    fn every_reference_node_has_a_place_and_nodes_are_distinct() {
        let spec = MachineSpec::reference();
        let s = Scene::new(&spec);
        let names: Vec<String> = spec.thermal.nodes.iter().map(|n| n.name.clone()).collect();
        let screws = screw_counts(&names);
        // The counts by name agree with the segments each ballscrew nut heats.
        let mut heated = [0; 3];
        for s in &spec.thermal.sources {
            if let vmc_machine::thermal::HeatSourceSpec::BallscrewNut { axis, segments, .. } = s {
                heated[axis.index()] += segments.len();
            }
        }
        assert_eq!(screws, heated);
        let mut places = Vec::new();
        for n in &names {
            let p = s.node_place(n, screws);
            assert!(p.is_some(), "node {n} has no place");
            places.push(p.unwrap());
        }
        for i in 0..places.len() {
            for j in 0..i {
                assert!(
                    places[i] != places[j],
                    "{} and {} at the same place",
                    names[i],
                    names[j]
                );
            }
        }
        assert!(s.node_place("mystery_node", screws).is_none());
        assert!(s.node_place("column_top_side", screws).is_none());
    }

    #[test]
    fn the_temperature_ramp_runs_from_blue_to_red() {
        assert_eq!(temp_rgba(10.0, 20.0, 30.0), [40, 70, 200, 255]);
        assert_eq!(temp_rgba(40.0, 20.0, 30.0), [220, 40, 30, 255]);
        let mid = temp_rgba(25.0, 20.0, 30.0);
        assert_eq!(mid, [80, 200, 80, 255]);
    }
}
