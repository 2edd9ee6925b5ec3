//! The tables of docs/guide/classification.md: how the classifier from the path
//! (and projected areas) agrees with people's labels of real paper squares
//! — in sample and by leave-one-out — and with the full classifier (with
//! orientation) on leafmagic's own falls and the MuJoCo falls when it is
//! given what video of them would give.
//!
//! And how each classifier holds at the frame rates video and animation
//! come in (60, 30, 25 and film's 24 frames per second).
//!
//! `cargo run --release --example real_falls_classify` (about 15 s).

#[path = "../../tests/integration/corpus.rs"]
#[allow(dead_code)]
mod corpus;

use corpus::{CLASSES, Fall, Square};
use leafmagic::motion::classify::{ClassifyOptions, MotionClass, classify, classify_with};
use leafmagic::motion::path::{Calibration, Inputs, PathFeatures, verdict};
use leafmagic::motion::trajectory::Trajectory;
use std::time::Instant;

const PATH_ONLY: ClassifyOptions = ClassifyOptions {
    orientation: false,
    areas: false,
};
const PATH_AND_AREAS: ClassifyOptions = ClassifyOptions {
    orientation: false,
    areas: true,
};

fn pct(a: usize, b: usize) -> String {
    if b == 0 {
        "—".to_string()
    } else {
        format!("{a}/{b} ({:.1} %)", 100.0 * a as f64 / b as f64)
    }
}

/// Agreement of `found` with people over the tumbling and chaotic
/// segments: overall, released flat, released on edge.
fn agreement(squares: &[&Square], found: &[MotionClass]) -> [String; 3] {
    let count = |edge: Option<bool>| {
        let (mut ok, mut n) = (0, 0);
        for (s, c) in squares.iter().zip(found) {
            if edge.is_some_and(|e| e != s.on_edge) {
                continue;
            }
            n += 1;
            ok += usize::from(corpus::human_class(s.human) == *c);
        }
        pct(ok, n)
    };
    [count(None), count(Some(false)), count(Some(true))]
}

fn squares_report() {
    let squares = corpus::squares();
    let (named, short): (Vec<&Square>, Vec<&Square>) = squares.iter().partition(|s| s.human != 3);
    println!("## Real paper squares: agreement with people\n");
    println!(
        "{} segments: {} tumbling, {} chaotic, {} steady/periodic (the first frames of a flat release).\n",
        squares.len(),
        named.iter().filter(|s| s.human == 1).count(),
        named.iter().filter(|s| s.human == 2).count(),
        short.len()
    );
    let undetermined = short
        .iter()
        .filter(|s| classify(&s.trajectory, s.chord).class == MotionClass::Undetermined)
        .count();
    let reason = short
        .first()
        .and_then(|s| classify(&s.trajectory, s.chord).reason)
        .unwrap_or_default();
    println!(
        "Steady/periodic segments reported undetermined: {} (e.g. \"{reason}\").\n",
        pct(undetermined, short.len())
    );

    println!("| classifier | inputs | all 92 | released flat | released on edge |");
    println!("|---|---|---|---|---|");
    let kmeans: Vec<MotionClass> = named.iter().map(|s| corpus::human_class(s.auto)).collect();
    let [a, f, e] = agreement(&named, &kmeans);
    println!(
        "| the authors' k-means (their `auto` label) | areas, vertical steps | {a} | {f} | {e} |"
    );
    let mut table = None;
    for (label, options, inputs) in [
        ("path + areas", PATH_AND_AREAS, Inputs::Areas),
        ("path only", PATH_ONLY, Inputs::Path),
    ] {
        let cases: Vec<(PathFeatures, Inputs, MotionClass)> = named
            .iter()
            .map(|s| {
                let c = classify_with(&s.trajectory, s.chord, options);
                (c.path.unwrap(), inputs, corpus::human_class(s.human))
            })
            .collect();
        let shipped: Vec<MotionClass> = cases
            .iter()
            .map(|c| verdict(c.0.clone(), c.1, &Calibration::default()).class)
            .collect();
        let [a, f, e] = agreement(&named, &shipped);
        println!("| leafmagic, shipped thresholds (in sample) | {label} | {a} | {f} | {e} |");
        let t = Instant::now();
        let loo = corpus::leave_one_out(&cases);
        let found: Vec<MotionClass> = loo.iter().map(|l| l.0).collect();
        let [a, f, e] = agreement(&named, &found);
        let range = |get: fn(&Calibration) -> f64| {
            let v: Vec<f64> = loo.iter().map(|l| get(&l.1)).collect();
            (
                v.iter().copied().fold(f64::INFINITY, f64::min),
                v.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            )
        };
        let (s0, s1) = range(|c| c.tumble_min_straightness);
        let (r0, r1) = range(|c| c.tumble_min_area_maxima_per_s);
        println!(
            "| leafmagic, leave-one-out (refitted: straightness {s0:.2}–{s1:.2}{}) | {label} | {a} | {f} | {e} |",
            if inputs == Inputs::Areas {
                format!(", area maxima {r0:.2}–{r1:.2}/s")
            } else {
                String::new()
            }
        );
        eprintln!(
            "leave-one-out ({label}): {:.1} s",
            t.elapsed().as_secs_f64()
        );
        if inputs == Inputs::Areas {
            table = Some(corpus::confusion(
                &named
                    .iter()
                    .zip(&found)
                    .map(|(s, c)| (corpus::human_class(s.human), *c))
                    .collect::<Vec<_>>(),
            ));
        }
    }
    println!();
    if let Some(t) = table {
        println!("People (rows) against leafmagic, path + areas, leave-one-out (columns):\n");
        print_confusion(&t, "people");
    }
}

fn print_confusion(t: &[[usize; 4]; 4], rows: &str) {
    print!("| {rows} \\ found |");
    for c in CLASSES {
        print!(" {c} |");
    }
    println!();
    println!("|---|---|---|---|---|");
    for (i, c) in CLASSES.iter().enumerate() {
        if t[i].iter().sum::<usize>() == 0 {
            continue;
        }
        print!("| {c} |");
        for n in t[i] {
            print!(" {n} |");
        }
        println!();
    }
    println!();
}

/// How often the path agrees with the full classifier's class of the whole
/// fall, for each way of degrading the record; and the confusion tables.
fn consistency(title: &str, falls: &[Fall]) {
    println!("## {title}\n");
    let full: Vec<MotionClass> = falls
        .iter()
        .map(|f| classify(&f.trajectory, f.chord).class)
        .collect();
    let named = full
        .iter()
        .filter(|c| **c != MotionClass::Undetermined)
        .count();
    println!(
        "{} falls ({named} named by the full classifier, the rest undetermined).\n",
        falls.len()
    );
    type Degrade = fn(&Fall, usize) -> Vec<Trajectory>;
    let ways: [(&str, Degrade); 4] = [
        ("quaternions stripped (10 s, 240 Hz)", |f, _| {
            vec![f.trajectory.without_orientation()]
        }),
        (
            "video: 98 Hz, 1 mm noise, the last 1.5 s and 5.0–6.5 s",
            |f, i| corpus::video_cuts(f, i, 98.0, false),
        ),
        ("video + two cameras' areas", |f, i| {
            corpus::video_cuts(f, i, 98.0, true)
        }),
        (
            "full classifier on the same 1.5 s cuts, with orientation",
            |f, _| clean_cuts(f),
        ),
    ];
    println!(
        "| record given | agrees with the full classifier | of the falls it names | undetermined |"
    );
    println!("|---|---|---|---|");
    let mut tables = Vec::new();
    let mut row = |label: &'static str, pairs: Vec<(MotionClass, MotionClass)>| {
        let agree = pairs.iter().filter(|p| p.0 == p.1).count();
        let named: Vec<_> = pairs
            .iter()
            .filter(|p| p.0 != MotionClass::Undetermined)
            .collect();
        let named_agree = named.iter().filter(|p| p.0 == p.1).count();
        let undetermined = pairs
            .iter()
            .filter(|p| p.1 == MotionClass::Undetermined)
            .count();
        println!(
            "| {label} | {} | {} | {undetermined} |",
            pct(agree, pairs.len()),
            pct(named_agree, named.len())
        );
        tables.push((label, corpus::confusion(&pairs)));
    };
    for (label, degrade) in ways {
        let mut pairs = Vec::new();
        for (i, f) in falls.iter().enumerate() {
            for tr in degrade(f, i) {
                pairs.push((full[i], classify(&tr, f.chord).class));
            }
        }
        row(label, pairs);
    }
    // The same cut given to both: the full classifier with orientation
    // (noise-free), the path without (98 Hz, 1 mm noise, areas or not).
    for (label, areas) in [
        (
            "video, path only, against the full classifier on the same cut",
            false,
        ),
        (
            "video + areas, against the full classifier on the same cut",
            true,
        ),
    ] {
        let mut pairs = Vec::new();
        for (i, f) in falls.iter().enumerate() {
            for (clean, video) in clean_cuts(f)
                .iter()
                .zip(corpus::video_cuts(f, i, 98.0, areas))
            {
                let reference = classify(clean, f.chord).class;
                pairs.push((reference, classify(&video, f.chord).class));
            }
        }
        row(label, pairs);
    }
    println!();
    for (label, t) in tables {
        println!("Full classifier (rows) against {label} (columns):\n");
        print_confusion(&t, "full");
    }
}

/// The two 1.5 s cuts of [`cuts`], noise-free, with orientation, at 98 Hz.
fn clean_cuts(f: &Fall) -> Vec<Trajectory> {
    let end = *f.trajectory.time.last().unwrap();
    [end - 1.5, 5.0]
        .iter()
        .map(|&t0| {
            let n = (1.5 * 98.0 + 1e-9f64).floor() as usize + 1;
            let times: Vec<f64> = (0..n).map(|k| t0 + k as f64 / 98.0).collect();
            f.trajectory.sampled_at(&times)
        })
        .collect()
}

/// docs/guide/classification.md, "Frame rates": the full classifier on pose
/// records resampled to video and animation rates, against its own verdict
/// at 240 Hz; the real squares' films decimated, against people; and
/// video cuts of the corpus at those rates, against the full classifier.
fn frame_rates(falls: &[Fall]) {
    println!("## Frame rates\n");
    let full: Vec<MotionClass> = falls
        .iter()
        .map(|f| classify(&f.trajectory, f.chord).class)
        .collect();
    let named: Vec<usize> = (0..falls.len())
        .filter(|&i| full[i] != MotionClass::Undetermined)
        .collect();
    println!("| pose record (with orientation) at | same class as at 240 Hz | undetermined |");
    println!("|---|---|---|");
    for rate in [60.0, 30.0, 25.0, 24.0] {
        let (mut same, mut undetermined) = (0, 0);
        for &i in &named {
            let f = &falls[i];
            let c = classify(&f.trajectory.resampled(rate), f.chord);
            same += usize::from(c.class == full[i] && c.inputs == Inputs::Orientation);
            undetermined += usize::from(c.class == MotionClass::Undetermined);
        }
        println!(
            "| {rate} Hz | {} | {undetermined} |",
            pct(same, named.len())
        );
    }
    println!();

    let squares = corpus::squares();
    let named_squares: Vec<&Square> = squares.iter().filter(|s| s.human != 3).collect();
    println!("| real squares' films, every k-th frame | path + areas | path only |");
    println!("|---|---|---|");
    for k in [1, 2, 3, 4] {
        let agree = |use_: ClassifyOptions| {
            let ok = named_squares
                .iter()
                .filter(|s| {
                    let c = classify_with(&s.trajectory.every(k), s.chord, use_).class;
                    c == corpus::human_class(s.human)
                })
                .count();
            pct(ok, named_squares.len())
        };
        println!(
            "| {:.1} fps (k = {k}) | {} | {} |",
            98.0 / k as f64,
            agree(PATH_AND_AREAS),
            agree(PATH_ONLY)
        );
    }
    println!();

    println!("| video cuts (1.5 s, 1 mm noise) at | path only | path + areas |");
    println!("|---|---|---|");
    for rate in [98.0, 60.0, 30.0, 25.0, 24.0] {
        let agree = |areas: bool| {
            let mut ok = 0;
            for &i in &named {
                let f = &falls[i];
                for v in corpus::video_cuts(f, i, rate, areas) {
                    ok += usize::from(classify(&v, f.chord).class == full[i]);
                }
            }
            pct(ok, 2 * named.len())
        };
        println!("| {rate} fps | {} | {} |", agree(false), agree(true));
    }
    println!();
}

fn main() {
    leafmagic::util::pipe::quiet_broken_pipe();
    squares_report();
    let t = Instant::now();
    let falls = corpus::falls();
    let held_out = corpus::held_out_falls();
    eprintln!(
        "{} + {} falls dropped in {:.1} s",
        falls.len(),
        held_out.len(),
        t.elapsed().as_secs_f64()
    );
    consistency(
        "Consistency: leafmagic's own falls and the MuJoCo falls (the falls the tests hold)",
        &falls,
    );
    consistency(
        "Consistency on held-out falls (recipe variants 17–32, prototype A varied with seeds 40–79)",
        &held_out,
    );
    let mut all = falls;
    all.extend(held_out);
    frame_rates(&all);
}
