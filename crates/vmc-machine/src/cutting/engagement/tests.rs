//! Engagement against hand-computed cases: a slot, side cuts of known stepover up and down, a
//! second pass, an arc round a groove, a plunge.

use super::*;

/// Tool Ø10 mm on a 0.3125 mm grid (D/32).
const D_MM: f64 = 10.0;
const GRID_MM: f64 = D_MM / 32.0;

/// One cell over D: the resolution of a_e/D.
const IMMERSION_TOL: f64 = GRID_MM / D_MM;

fn block() -> StockBox {
    StockBox {
        min_mm: [0.0, 0.0, -10.0],
        max_mm: [60.0, 40.0, 0.0],
    }
}

fn sweep(stock: &StockBox) -> Sweep {
    Sweep::new(stock, GRID_MM, D_MM).unwrap()
}

fn line(a: [f64; 3], b: [f64; 3]) -> Line {
    Line {
        start_mm: a,
        end_mm: b,
    }
}

fn arc_of(c: &Contact) -> EngagedArc {
    match c.kind {
        ContactKind::Side(a) => a,
        ContactKind::Plunge => panic!("a plunge at {:?}", c.position_mm),
    }
}

/// Contacts whose tool is wholly inside the block in X, away from the entry and exit.
fn interior(contacts: &[Contact]) -> Vec<Contact> {
    contacts
        .iter()
        .filter(|c| c.position_mm[0] > 10.0 && c.position_mm[0] < 50.0)
        .copied()
        .collect()
}

#[test]
fn a_straight_slot_through_full_stock_is_full_immersion_at_the_cut_depth() {
    let mut s = sweep(&block());
    let contacts = s.cut(&line([-10.0, 20.0, -2.0], [70.0, 20.0, -2.0]));
    let inner = interior(&contacts);
    assert!(inner.len() > 100);
    for c in &inner {
        let a = arc_of(c);
        assert_eq!(a.side, Side::Both, "{c:?}");
        assert_eq!((a.entry_rad, a.exit_rad), (0.0, PI));
        assert!((c.axial_depth_mm - 2.0).abs() < 1e-12, "{c:?}");
        assert!(a.feed_angle_rad.abs() < 1e-12);
    }
    // No contact before the tool reaches the block (x + R < 0), every sample after.
    assert!(contacts.iter().all(|c| c.position_mm[0] > -5.0));
    assert!(contacts.iter().all(|c| c.position_mm[0] < 65.0));
    // The slot volume: 60 mm × 10 mm × 2 mm, plus the two half-discs at the ends do not
    // exist (the tool passes right through): 1200 mm³, to a cell on each wall.
    let removed = 24_000.0 - s.finish().volume_mm3();
    assert!(
        (removed - 1200.0).abs() < 60.0 * 2.0 * GRID_MM * 2.0,
        "{removed}"
    );
}

#[test]
fn a_side_cut_of_stepover_s_has_immersion_s_over_d_on_the_side_of_the_material() {
    for (stepover_mm, sign) in [(1.0, 1.0), (2.5, 1.0), (4.0, -1.0), (7.0, -1.0)] {
        let mut s = sweep(&block());
        s.cut(&line([-10.0, 20.0, -3.0], [70.0, 20.0, -3.0]));
        // The next pass, `stepover_mm` to the left (+Y, sign +1) or to the right (−Y).
        let y = 20.0 + sign * stepover_mm;
        let contacts = s.cut(&line([-10.0, y, -3.0], [70.0, y, -3.0]));
        let inner = interior(&contacts);
        assert!(inner.len() > 100, "{stepover_mm}");
        for c in &inner {
            let a = arc_of(c);
            let (side, immersion) = if sign > 0.0 {
                (Side::Left, a.immersion_from_left())
            } else {
                (Side::Right, a.immersion_from_right())
            };
            assert_eq!(a.side, side, "{stepover_mm}: {c:?}");
            let want = stepover_mm / D_MM;
            assert!(
                (immersion - want).abs() <= IMMERSION_TOL,
                "stepover {stepover_mm}: a_e/D {immersion} vs {want}"
            );
            assert!((c.axial_depth_mm - 3.0).abs() < 1e-12);
        }
    }
}

#[test]
fn a_second_pass_over_cut_material_does_not_engage() {
    let mut s = sweep(&block());
    let path = line([-10.0, 20.0, -2.0], [70.0, 20.0, -2.0]);
    s.cut(&path);
    assert!(s.cut(&path).is_empty());
    // Back the other way, and higher up: still nothing.
    assert!(s
        .cut(&line([70.0, 20.0, -1.0], [-10.0, 20.0, -1.0]))
        .is_empty());
    // Deeper, it cuts the floor only: a slot again, 0.5 mm deep.
    let deeper = s.cut(&line([-10.0, 20.0, -2.5], [70.0, 20.0, -2.5]));
    let inner = interior(&deeper);
    assert!(!inner.is_empty());
    for c in inner {
        assert_eq!(arc_of(&c).side, Side::Both);
        assert!((c.axial_depth_mm - 0.5).abs() < 1e-12);
    }
}

/// A circle of radius `r_mm` about (cx, cy) at height z, counter-clockwise from angle 0.
struct Circle {
    centre: [f64; 2],
    r_mm: f64,
    z_mm: f64,
}

impl ToolPath for Circle {
    fn length_mm(&self) -> f64 {
        2.0 * PI * self.r_mm
    }
    fn point_at(&self, s_mm: f64) -> [f64; 3] {
        let a = s_mm / self.r_mm;
        [
            self.centre[0] + self.r_mm * a.cos(),
            self.centre[1] + self.r_mm * a.sin(),
            self.z_mm,
        ]
    }
    fn tangent_at(&self, s_mm: f64) -> [f64; 3] {
        let a = s_mm / self.r_mm;
        [-a.sin(), a.cos(), 0.0]
    }
}

#[test]
fn an_arc_widening_a_ring_groove_outwards_engages_as_computed_by_hand() {
    let stock = StockBox {
        min_mm: [-40.0, -40.0, -10.0],
        max_mm: [40.0, 40.0, 0.0],
    };
    let mut s = sweep(&stock);
    let (rho1, rho2, r) = (20.0, 23.0, 0.5 * D_MM);
    let groove = Circle {
        centre: [0.0, 0.0],
        r_mm: rho1,
        z_mm: -2.0,
    };
    s.cut(&groove);
    let wider = s.cut(&Circle {
        r_mm: rho2,
        ..groove
    });
    // Counter-clockwise, the centre is on the left; the new material is outside the groove
    // (|x| > ρ1 + R), on the right. A periphery point at φ is at distance
    // √(ρ2² − 2ρ2R cos φ + R²) from the centre, so the arc starts at
    // cos φ_entry = (ρ2² + R² − (ρ1 + R)²)/(2ρ2R) and a_e/D = (1 + cos φ_entry)/2 = 0.3457
    // (a straight cut of the same 3 mm stepover would give 0.3).
    let cos_entry = (rho2 * rho2 + r * r - (rho1 + r).powi(2)) / (2.0 * rho2 * r);
    let want = 0.5 * (1.0 + cos_entry);
    assert!((want - 0.3457).abs() < 1e-4);
    // Away from the start of the circle, where the groove's own start was cut last.
    let middle: Vec<&Contact> = wider
        .iter()
        .filter(|c| c.s_mm > 0.2 * 2.0 * PI * rho2 && c.s_mm < 0.9 * 2.0 * PI * rho2)
        .collect();
    assert!(middle.len() > 200, "{}", middle.len());
    for c in middle {
        let a = arc_of(c);
        assert_eq!(a.side, Side::Right, "{c:?}");
        let got = a.immersion_from_right();
        assert!(
            (got - want).abs() <= IMMERSION_TOL,
            "a_e/D {got} vs {want} at {:?}",
            c.position_mm
        );
        assert!((c.axial_depth_mm - 2.0).abs() < 1e-12);
    }
}

#[test]
fn material_ahead_only_is_neither_side_and_a_plunge_is_a_plunge() {
    let mut s = sweep(&block());
    // Entering the block's face at x = 0 head on: the first contacts see material ahead only.
    let contacts = s.cut(&line([-10.0, 20.0, -2.0], [2.0, 20.0, -2.0]));
    let first = arc_of(&contacts[0]);
    assert_eq!(first.side, Side::Neither);
    assert!(
        first.entry_rad > 0.5 && first.exit_rad < PI - 0.5,
        "{first:?}"
    );
    // A plunge into fresh stock beside it.
    let plunge = s.cut(&line([30.0, 20.0, 5.0], [30.0, 20.0, -4.0]));
    let last = plunge.last().unwrap();
    assert_eq!(last.kind, ContactKind::Plunge);
    assert!((last.axial_depth_mm - 4.0).abs() < 1e-9);
    // Air above the stock: nothing.
    assert!(s.cut(&line([0.0, 0.0, 1.0], [60.0, 40.0, 1.0])).is_empty());
}

#[test]
fn a_grid_too_coarse_for_the_tool_is_refused() {
    assert!(matches!(
        Sweep::new(&block(), 3.0, 10.0),
        Err(CuttingError::CoarseGrid { .. })
    ));
    assert!(matches!(
        Sweep::new(&block(), 1.0, 0.0),
        Err(CuttingError::ToolDiameter { .. })
    ));
}
