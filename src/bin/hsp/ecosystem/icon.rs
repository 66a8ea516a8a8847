//! The FMU's icon: a small top view of the rig drawn with `plotters`, the same picture in both
//! FMUs (`model.png` in FMI 2.0, `terminalsAndIcons/icon.png` in FMI 3.0). From left to right:
//! the servo valve with its torque-motor coil and the two lines to the actuator (supply side
//! red, return side blue), the vane motor with its vane, the torsion bar, the hub with the
//! slewing arrow, and the plate with its 4 x 3 grid of accelerometers.

use plotters::prelude::*;

/// The icon's size in pixels.
pub const SIZE: (u32, u32) = (200, 200);

const STEEL: RGBColor = RGBColor(70, 74, 86);
const LIGHT_STEEL: RGBColor = RGBColor(150, 156, 170);
const VALVE: RGBColor = RGBColor(96, 116, 146);
const COIL: RGBColor = RGBColor(214, 140, 40);
const PLATE: RGBColor = RGBColor(176, 204, 232);
const PLATE_EDGE: RGBColor = RGBColor(36, 60, 96);
const SUPPLY: RGBColor = RGBColor(200, 40, 40);
const RETURN: RGBColor = RGBColor(40, 80, 200);
const SENSOR: RGBColor = RGBColor(200, 30, 30);
const ARROW: RGBColor = RGBColor(30, 130, 60);

/// The hub's centre and radius, px.
const HUB: (i32, i32) = (98, 100);
const HUB_R: i32 = 13;

/// The plate's corners: root top, tip top, tip bottom, root bottom (a little perspective: the
/// tip nearer the viewer).
const PLATE_CORNERS: [(i32, i32); 4] = [(110, 80), (194, 68), (194, 132), (110, 120)];

/// A point on the plate at fractions `u` along it (0 root, 1 tip) and `v` across it (0 top).
fn on_plate(u: f64, v: f64) -> (i32, i32) {
    let [rt, tt, tb, rb] = PLATE_CORNERS.map(|(x, y)| (f64::from(x), f64::from(y)));
    let top = (rt.0 + u * (tt.0 - rt.0), rt.1 + u * (tt.1 - rt.1));
    let bottom = (rb.0 + u * (tb.0 - rb.0), rb.1 + u * (tb.1 - rb.1));
    (
        (top.0 + v * (bottom.0 - top.0)).round() as i32,
        (top.1 + v * (bottom.1 - top.1)).round() as i32,
    )
}

fn draw<DB: DrawingBackend>(area: &DrawingArea<DB, plotters::coord::Shift>) -> Result<(), String> {
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    area.fill(&WHITE).map_err(e)?;

    // The servo valve: body, spool, torque-motor coil, and the lines to the motor's two chambers.
    area.draw(&Rectangle::new([(16, 152), (70, 182)], VALVE.filled()))
        .map_err(e)?;
    area.draw(&Rectangle::new(
        [(22, 164), (64, 170)],
        LIGHT_STEEL.filled(),
    ))
    .map_err(e)?;
    area.draw(&Rectangle::new([(4, 156), (16, 178)], COIL.filled()))
        .map_err(e)?;
    for (x, color) in [(32, SUPPLY), (54, RETURN)] {
        area.draw(&PathElement::new(
            vec![(x, 152), (x, 118)],
            color.stroke_width(4),
        ))
        .map_err(e)?;
    }

    // The vane motor: housing, rotor and vane.
    area.draw(&Circle::new((42, 100), 22, STEEL.filled()))
        .map_err(e)?;
    area.draw(&Circle::new((42, 100), 9, LIGHT_STEEL.filled()))
        .map_err(e)?;
    area.draw(&PathElement::new(
        vec![(42, 100), (58, 86)],
        LIGHT_STEEL.stroke_width(5),
    ))
    .map_err(e)?;

    // The torsion bar to the hub, and the hub.
    area.draw(&PathElement::new(
        vec![(64, 100), (HUB.0 - HUB_R, 100)],
        LIGHT_STEEL.stroke_width(5),
    ))
    .map_err(e)?;

    // The plate and its accelerometers (x = a/4 .. a, y = b/6, 3b/6, 5b/6).
    area.draw(&Polygon::new(PLATE_CORNERS.to_vec(), PLATE.filled()))
        .map_err(e)?;
    let mut edge = PLATE_CORNERS.to_vec();
    edge.push(PLATE_CORNERS[0]);
    area.draw(&PathElement::new(edge, PLATE_EDGE.stroke_width(2)))
        .map_err(e)?;
    for i in 1..=4 {
        for j in [1.0, 3.0, 5.0] {
            let u = f64::from(i) / 4.0 - if i == 4 { 0.05 } else { 0.0 };
            area.draw(&Circle::new(on_plate(u, j / 6.0), 3, SENSOR.filled()))
                .map_err(e)?;
        }
    }
    area.draw(&Circle::new(HUB, HUB_R, STEEL.filled()))
        .map_err(e)?;
    area.draw(&Circle::new(HUB, 5, LIGHT_STEEL.filled()))
        .map_err(e)?;

    // The slewing arrow around the hub.
    let r = f64::from(HUB_R + 12);
    let arc: Vec<(i32, i32)> = (0..=16)
        .map(|k| {
            let a = (-150.0 + 100.0 * f64::from(k) / 16.0_f64).to_radians();
            (
                HUB.0 + (r * a.cos()).round() as i32,
                HUB.1 + (r * a.sin()).round() as i32,
            )
        })
        .collect();
    let tip = *arc.last().unwrap_or(&HUB);
    area.draw(&PathElement::new(arc, ARROW.stroke_width(3)))
        .map_err(e)?;
    area.draw(&Polygon::new(
        vec![tip, (tip.0 - 10, tip.1 - 4), (tip.0 - 3, tip.1 - 11)],
        ARROW.filled(),
    ))
    .map_err(e)?;
    area.present().map_err(e)
}

/// The icon as PNG bytes.
pub fn png() -> Result<Vec<u8>, String> {
    let path = std::env::temp_dir().join(format!("hsp-icon-{}.png", std::process::id()));
    {
        let area = BitMapBackend::new(&path, SIZE).into_drawing_area();
        draw(&area).map_err(|e| format!("icon: {e}"))?;
    }
    let bytes = std::fs::read(&path).map_err(|e| format!("{}: {e}", path.display()));
    let _ = std::fs::remove_file(&path);
    bytes
}
