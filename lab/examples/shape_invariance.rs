//! Does the path classifier depend on the plate's outline? The unsteady
//! law's plates of four outlines (square, circle, hexagon, cross with arms
//! a third of the span) at the same area, each dropped from the eight
//! release attitudes of `plates::RELEASE_ATTITUDES`, are classified from
//! their orientation (the full classifier) and from their path alone, as
//! video would give them, with the length scale taken two ways: the
//! outline's longest extent (what `classify --all` takes of a mesh: a
//! square's diagonal, a circle's diameter, a cross's span) and the side of
//! the square of the same area. Agreement per outline and length scale is
//! printed (docs/guide/classification.md, "Other outlines").
//!
//! `--short`: the experiment's 1.4 s falls, let go near flat or on edge.
//!
//! `cargo run --release --example shape_invariance [-- --seconds S] [-- --short]`

use leafmagic::leaf::AeroSpec;
use leafmagic::leaf::plates::{PAPER_AREAL_DENSITY, PlateShape, RELEASE_ATTITUDES, plate};
use leafmagic::motion::classify::{ClassifyOptions, MotionClass, classify_with};
use leafmagic::sim::drop::{DropParams, drop_leaf};

/// Sides of the squares of equal area, m: the real squares' bin medians.
const EQUAL_AREA_SIDES: [f64; 5] = [0.032, 0.040, 0.056, 0.069, 0.090];

/// The outlines, with the size and aspect `plate` takes for a plate of
/// area L².
fn outlines(l: f64) -> [(&'static str, PlateShape, f64, f64); 4] {
    let pi = std::f64::consts::PI;
    [
        ("square", PlateShape::Square, l, 1.0),
        ("circle", PlateShape::Circle, 2.0 * l / pi.sqrt(), 1.0),
        // A hexagon of flat-to-flat width w has area (√3/2) w².
        (
            "hexagon",
            PlateShape::Hexagon,
            l * (2.0 / 3f64.sqrt()).sqrt(),
            1.0,
        ),
        // A plus of span S, arms S/3: area 5 S² / 9.
        ("cross S/3", PlateShape::Cross, 3.0 * l / 5f64.sqrt(), 3.0),
    ]
}

/// Near-flat and on-edge releases as the real-falls experiment lets its
/// plates go (1–5° flat, 90 ± 1–5° on edge).
const EXPERIMENT_RELEASES: [[f64; 2]; 8] = [
    [3.0, 1.0],
    [1.0, 4.0],
    [5.0, 0.0],
    [2.0, -2.0],
    [92.0, 3.0],
    [88.0, -2.0],
    [91.0, -4.0],
    [86.0, 1.0],
];

fn releases(short: bool) -> [[f64; 2]; 8] {
    if short {
        EXPERIMENT_RELEASES
    } else {
        RELEASE_ATTITUDES
    }
}

fn main() {
    let mut seconds = 3.0;
    let mut short = false;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--seconds" => {
                seconds = args
                    .next()
                    .and_then(|v| v.parse().ok())
                    .expect("--seconds: a number of seconds");
            }
            // The experiment's falls: 1.1 m, about 1.4 s, let go nearly
            // flat or on edge (real_falls::release's ranges).
            "--short" => {
                short = true;
                seconds = 1.4;
            }
            other => panic!("unknown argument {other:?}; usage: [--seconds S] [--short]"),
        }
    }
    let path_only = ClassifyOptions {
        orientation: false,
        areas: false,
    };
    let letter = |c: MotionClass| match c {
        MotionClass::Floater => 'F',
        MotionClass::Spinner => 'S',
        MotionClass::Lilter => 'L',
        MotionClass::Undetermined => 'U',
    };
    println!(
        "{seconds} s drops of 70 g/m² plates under the unsteady law, {} releases each; classes F/S/L/U\n",
        releases(short).len()
    );
    println!(
        "{:<10} {:>7} {:>7}  {:<10} {:<10} {:<10}",
        "outline", "L cm", "chord", "rotation", "path@chord", "path@L"
    );
    let t0 = std::time::Instant::now();
    let mut totals = std::collections::BTreeMap::<&str, [usize; 3]>::new();
    for l in EQUAL_AREA_SIDES {
        for (name, shape, size, aspect) in outlines(l) {
            let model = plate(
                shape,
                size,
                aspect,
                PAPER_AREAL_DENSITY,
                AeroSpec::unsteady(),
            )
            .expect("a valid plate")
            .model()
            .expect("a valid model");
            let chord = model.chord();
            let (mut full, mut at_chord, mut at_l) = (String::new(), String::new(), String::new());
            let t = totals.entry(name).or_default();
            for tilt in releases(short) {
                let params = DropParams {
                    seconds,
                    tilt_deg: tilt,
                    ..Default::default()
                };
                let fall = drop_leaf(&model, &params).expect("the drop runs");
                let tr = &fall.trajectory;
                let by_rotation = classify_with(tr, chord, ClassifyOptions::default()).class;
                let by_path_chord = classify_with(tr, chord, path_only).class;
                let by_path_l = classify_with(tr, l, path_only).class;
                full.push(letter(by_rotation));
                at_chord.push(letter(by_path_chord));
                at_l.push(letter(by_path_l));
                t[0] += 1;
                t[1] += usize::from(by_path_chord == by_rotation);
                t[2] += usize::from(by_path_l == by_rotation);
            }
            println!(
                "{name:<10} {:>7.1} {:>7.1}  {full:<10} {at_chord:<10} {at_l:<10}",
                l * 100.0,
                chord * 100.0
            );
        }
    }
    println!("\npath's class = rotation's class, per outline:");
    for (name, [n, c, l]) in &totals {
        println!(
            "{name:<10} at the chord {c}/{n} ({:.0} %), at the equal-area side {l}/{n} ({:.0} %)",
            100.0 * *c as f64 / *n as f64,
            100.0 * *l as f64 / *n as f64
        );
    }
    println!("\n{:.1} s wall", t0.elapsed().as_secs_f64());
}
