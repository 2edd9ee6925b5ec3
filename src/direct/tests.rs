//! Bad input named by file, line and field; goals judged exactly on
//! hand-built tracks.

use super::geometry::{Aabb, Cylinder, Polygon};
use super::goals::{Aim, Goal, Region, TOUCH, Target, Tracks, judge};
use super::problem::{Problem, objective};
use super::search::{Settings, search};
use crate::util::bad_input::BadInput;
use nalgebra::Vector3;
use std::path::Path;

type V3 = Vector3<f64>;

const BASE: &str = r#"name = "t"
duration = 2.0

[ground]
static_friction = 0.6
kinetic_friction = 0.5

[[rigid]]
name = "bin"
shape = "cylinder"
radius = 0.3
height = 0.6
mass = 2.0

[[leaf]]
name = "east"
leaf = "a"
count = 2
position = [1.0, 0.0, 1.0]
spread = [0.1, 0.1, 0.1]

[[wind]]
kind = "point_sink"
point = [0.0, 0.0, 0.6]
flux = 1.0
core_radius = 0.3
"#;

const GOAL: &str =
    "\n[[goal]]\nname = \"in\"\nleaves = \"east\"\nkind = \"enter\"\nobject = \"bin\"\nby = 1.5\n";
const FREE: &str = "\n[[free]]\nparameter = \"wind[0].flux\"\nmin = 0.0\nmax = 4.0\n";

fn load(text: &str) -> Result<Problem, BadInput> {
    Problem::from_toml(text, "d.toml", Path::new("."))
}

fn refused(text: &str) -> BadInput {
    load(text).expect_err("bad input is refused")
}

fn line_of(text: &str, needle: &str) -> usize {
    text.lines()
        .position(|l| l.contains(needle))
        .expect("the needle is in the text")
        + 1
}

#[test]
fn a_good_file_loads_and_runs_only_as_far_as_its_goals_look() {
    let p = load(&format!("{BASE}{GOAL}{FREE}")).unwrap();
    assert_eq!(p.goals.len(), 1);
    assert_eq!(p.goals[0].leaves, vec![0, 1]);
    assert_eq!(p.free[0].written, 1.0);
    assert!((p.seconds - 1.5).abs() < 1e-12, "{}", p.seconds);
}

#[test]
fn a_goal_that_names_no_leaf_is_refused_at_its_line() {
    let no_leaves = format!("{BASE}{}{FREE}", GOAL.replace("leaves = \"east\"\n", ""));
    let e = refused(&no_leaves);
    assert_eq!(e.field, "goal[0].leaves");
    assert_eq!(e.line, Some(line_of(&no_leaves, "[[goal]]")), "{e}");
    assert!(e.reason.contains("names no leaf"), "{e}");
    let empty = format!("{BASE}{}{FREE}", GOAL.replace("\"east\"", "[]"));
    let e = refused(&empty);
    assert_eq!(
        (e.field.as_str(), e.line),
        ("goal[0].leaves", Some(line_of(&empty, "leaves = []")))
    );
    let unknown = format!("{BASE}{}{FREE}", GOAL.replace("\"east\"", "\"west\""));
    let e = refused(&unknown);
    assert!(
        e.reason.contains("'west'") && e.reason.contains("east"),
        "{e}"
    );
}

#[test]
fn empty_and_self_crossing_polygons_are_refused() {
    let land = |polygon: &str| {
        format!(
            "{BASE}\n[[goal]]\nname = \"down\"\nleaves = \"east\"\nkind = \"land\"\npolygon = {polygon}\n{FREE}"
        )
    };
    let text = land("[]");
    let e = refused(&text);
    assert_eq!(e.field, "goal[0].polygon");
    assert_eq!(e.line, Some(line_of(&text, "polygon =")));
    assert!(e.reason.contains("at least 3"), "{e}");
    let e = refused(&land("[[0.0, 0.0], [1.0, 1.0], [1.0, 0.0], [0.0, 1.0]]"));
    assert!(e.reason.contains("crosses itself"), "{e}");
    let e = refused(&land("[[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]]"));
    assert_eq!(e.field, "goal[0].polygon", "{e}");
    // The same square drawn properly loads.
    load(&land("[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]")).unwrap();
}

#[test]
fn a_field_that_does_not_apply_to_the_kind_is_named() {
    let text = format!("{BASE}{}tolerance = 0.1\n{FREE}", GOAL);
    let e = refused(&text);
    assert_eq!(e.field, "goal[0].tolerance");
    assert_eq!(e.line, Some(line_of(&text, "tolerance")));
    let text = format!("{BASE}{}", GOAL.replace("\"bin\"", "\"east-000\""));
    let e = refused(&format!("{text}{FREE}"));
    assert!(e.reason.contains("no [[rigid]]"), "{e}");
    let late = format!("{BASE}{}{FREE}", GOAL.replace("by = 1.5", "by = 3.0"));
    assert_eq!(refused(&late).field, "goal[0].by");
}

#[test]
fn a_free_parameter_needs_bounds_the_scene_accepts() {
    let no_max = format!("{BASE}{GOAL}\n[[free]]\nparameter = \"wind[0].flux\"\nmin = 0.0\n");
    let e = refused(&no_max);
    assert_eq!(e.field, "free[0].max");
    assert!(e.reason.contains("needs bounds"), "{e}");
    assert_eq!(e.line, Some(line_of(&no_max, "[[free]]")));
    // A core radius must be > 0: a lower bound of 0 is refused at `min`.
    let core = format!(
        "{BASE}{GOAL}\n[[free]]\nparameter = \"wind[0].core_radius\"\nmin = 0.0\nmax = 0.5\n"
    );
    let e = refused(&core);
    assert_eq!(e.field, "free[0].min");
    assert_eq!(e.line, Some(line_of(&core, "min = 0.0")));
    assert!(e.reason.contains("core_radius"), "{e}");
    let flipped = format!("{BASE}{GOAL}{}", FREE.replace("max = 4.0", "max = -1.0"));
    assert_eq!(refused(&flipped).field, "free[0].max");
    let mass = format!(
        "{BASE}{GOAL}{}",
        FREE.replace("wind[0].flux", "rigid[0].mass")
    );
    let e = refused(&mass);
    assert!(e.reason.contains("cannot be free"), "{e}");
    let unwritten = format!(
        "{BASE}{GOAL}{}",
        FREE.replace("wind[0].flux", "leaf[east].velocity[0]")
    );
    assert!(refused(&unwritten).reason.contains("not written"));
    let none = format!("{BASE}{GOAL}");
    assert_eq!(refused(&none).field, "free");
    let twice = format!("{BASE}{GOAL}{FREE}{FREE}");
    assert_eq!(refused(&twice).field, "free[1].parameter");
}

#[test]
fn a_budget_of_zero_is_refused() {
    let p = load(&format!("{BASE}{GOAL}{FREE}")).unwrap();
    let settings = Settings {
        budget: 0,
        seed: 0,
        threads: 1,
    };
    let e = search(&p, &settings, None, |_, _| Ok::<(), BadInput>(())).unwrap_err();
    assert_eq!((e.file.as_str(), e.field.as_str()), ("d.toml", "budget"));
}

/// Tracks of one object at 10 frames a second.
fn tracks(centres: Vec<Vec<[f64; 3]>>, lowest: Vec<Vec<f64>>) -> Tracks {
    let n = centres.len();
    Tracks {
        frame_rate: 10.0,
        centre: centres
            .into_iter()
            .map(|c| c.into_iter().map(V3::from).collect())
            .collect(),
        lowest,
        cylinder: vec![Vec::new(); n],
    }
}

#[test]
fn landing_inside_and_outside_a_polygon() {
    let square = Polygon {
        vertices: vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]],
    };
    let goal = Goal {
        name: "down".into(),
        leaves: vec![0, 1, 2, 3],
        aim: Aim::Land {
            region: Region::Polygon(square),
            after: 0.15,
            before: 0.3,
            ground: 0.0,
        },
    };
    let t = tracks(
        vec![
            // Touches down at frame 2 inside; then slides out, which does not count.
            vec![
                [0.5, 0.5, 0.3],
                [0.5, 0.5, 0.2],
                [0.5, 0.5, 0.0],
                [3.0, 0.5, 0.0],
            ],
            // Touches down at frame 2, 0.5 m beyond the edge x = 1.
            vec![
                [1.5, 0.5, 0.3],
                [1.5, 0.5, 0.2],
                [1.5, 0.5, 0.0],
                [1.5, 0.5, 0.0],
            ],
            // Still 0.4 m up at the window's end, over the square.
            vec![
                [0.5, 0.5, 0.8],
                [0.5, 0.5, 0.7],
                [0.5, 0.5, 0.6],
                [0.5, 0.5, 0.5],
            ],
            // Inside, but down at frame 1 (t = 0.1), before the window.
            vec![
                [0.5, 0.5, 0.1],
                [0.5, 0.5, 0.0],
                [0.5, 0.5, 0.0],
                [0.5, 0.5, 0.0],
            ],
        ],
        vec![
            vec![0.3, 0.2, 0.0, 0.0],
            vec![0.3, 0.2, 0.001, 0.0],
            vec![0.8, 0.7, 0.6, 0.4],
            vec![0.1, 0.0, 0.0, 0.0],
        ],
    );
    let r = judge(&goal, &t);
    assert!(r.leaves[0].met && r.leaves[0].distance == 0.0);
    assert!(!r.leaves[1].met);
    assert!((r.leaves[1].distance - 0.5).abs() < 1e-12);
    assert!(!r.leaves[2].met);
    assert!((r.leaves[2].distance - (0.4 - TOUCH)).abs() < 1e-12);
    assert!(!r.leaves[3].met);
    assert!(
        (r.leaves[3].distance - 0.05).abs() < 1e-12,
        "{:?}",
        r.leaves[3]
    );
    assert_eq!(r.met_fraction, 0.25);
    let mean = (0.5 + 0.4 - TOUCH + 0.05) / 4.0;
    assert!((r.mean_distance - mean).abs() < 1e-12);
    assert!((objective(&[r]) - (mean + 0.75)).abs() < 1e-12);
}

#[test]
fn passing_a_point_or_a_box_at_a_time_between_frames() {
    // x = 10 t: at t = 0.15 the centre is at x = 1.5, between frames.
    let t = tracks(
        vec![vec![[0.0, 0.0, 1.0], [1.0, 0.0, 1.0], [2.0, 0.0, 1.0]]],
        vec![vec![1.0; 3]],
    );
    let target = Aabb {
        min: V3::new(1.4, -0.1, 0.9),
        max: V3::new(1.6, 0.1, 1.1),
    };
    let at = |time: f64, target: Target| Goal {
        name: "through".into(),
        leaves: vec![0],
        aim: Aim::Pass { target, at: time },
    };
    assert_eq!(judge(&at(0.15, Target::Box(target)), &t).met_fraction, 1.0);
    let early = judge(&at(0.05, Target::Box(target)), &t);
    assert!((early.leaves[0].distance - 0.9).abs() < 1e-12);
    let point = |tolerance| Target::Point {
        point: V3::new(1.5, 0.3, 1.0),
        tolerance,
    };
    assert!(judge(&at(0.15, point(0.3)), &t).leaves[0].met);
    let near = judge(&at(0.15, point(0.1)), &t);
    assert!((near.leaves[0].distance - 0.2).abs() < 1e-12);
}

#[test]
fn staying_inside_counts_the_worst_frame_of_the_window() {
    let volume = Aabb {
        min: V3::new(-1.0, -1.0, 0.0),
        max: V3::new(1.0, 1.0, 2.0),
    };
    let t = tracks(
        vec![vec![
            [0.0, 0.0, 1.0],
            [1.3, 0.0, 1.0],
            [0.0, 0.0, 1.0],
            [0.0, 0.0, 3.0],
        ]],
        vec![vec![1.0; 4]],
    );
    let stay = |after, until| Goal {
        name: "hover".into(),
        leaves: vec![0],
        aim: Aim::Stay {
            region: volume,
            after,
            until,
        },
    };
    let r = judge(&stay(0.0, 0.2), &t);
    assert!((r.leaves[0].distance - 0.3).abs() < 1e-12);
    assert!(judge(&stay(0.2, 0.2 + 1e-9), &t).leaves[0].met);
    assert!((judge(&stay(0.2, 0.3), &t).leaves[0].distance - 1.0).abs() < 1e-12);
}

#[test]
fn entering_the_bin_is_judged_in_its_own_frame_at_the_time() {
    let mut t = tracks(
        vec![
            vec![[0.0, 0.0, 1.0], [0.05, 0.0, 0.3]],
            vec![[0.0, 0.0, 1.0], [0.0, 0.0, 1.0]],
            vec![],
        ],
        vec![vec![1.0; 2], vec![1.0; 2], vec![]],
    );
    // Object 2: a bin tipped onto its side at frame 1, axis along +x.
    let upright = Cylinder {
        base: V3::zeros(),
        axis: V3::z(),
        radius: 0.3,
        height: 0.6,
    };
    let tipped = Cylinder {
        base: V3::new(0.0, 0.0, 0.3),
        axis: V3::x(),
        ..upright
    };
    t.cylinder[2] = vec![upright, tipped];
    let goal = Goal {
        name: "in".into(),
        leaves: vec![0, 1],
        aim: Aim::Enter {
            object: 2,
            radius: 0.3,
            height: 0.6,
            segments: 16,
            rings: 2,
            by: 0.1,
        },
    };
    let r = judge(&goal, &t);
    assert!(r.leaves[0].met);
    // (0, 0, 1) against the tipped bin: 0.7 from its axis, 0.4 outside its wall.
    assert!(
        (r.leaves[1].distance - 0.4).abs() < 1e-12,
        "{:?}",
        r.leaves[1]
    );
    assert_eq!(r.met_fraction, 0.5);
}
