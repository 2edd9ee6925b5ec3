//! Falls as video gives them: the real paper squares of
//! `tests/data/real-falls/squares` against people's labels (held out by
//! leave-one-out), leafmagic's and MuJoCo's falls with the orientation
//! taken away against the full classifier, the CLI on such records, bad
//! input, and breeding toward a real square. The figures are those of
//! docs/guide/classification.md (`cargo run --release --example
//! real_falls_classify` prints them all).

use crate::breeding::{breed, leafmagic, scratch};
use crate::corpus::{self, Square};
use leafmagic::motion::class::Regime;
use leafmagic::motion::classify::{ClassifyOptions, MotionClass, classify, classify_with};
use leafmagic::motion::path::{Calibration, Inputs, PathFeatures, verdict};
use leafmagic::motion::trajectory::Trajectory;
use proptest::prelude::*;
use std::path::{Path, PathBuf};

fn square_file(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("tests/data/real-falls/squares/{name}.csv"))
}

/// (features, inputs, people's class) of the 92 tumbling and chaotic
/// segments, classified without orientation (`areas`: with the area signals).
fn cases(named: &[&Square], areas: bool) -> Vec<(PathFeatures, Inputs, MotionClass)> {
    let options = ClassifyOptions {
        orientation: false,
        areas,
    };
    named
        .iter()
        .map(|s| {
            let c = classify_with(&s.trajectory, s.chord, options);
            (c.path.unwrap(), c.inputs, corpus::human_class(s.human))
        })
        .collect()
}

/// The goal: ≥ 90 % of the 92 segments people called tumbling or
/// chaotic, held out (leave-one-out: each segment classified with the two
/// calibrated thresholds refitted on the other 91); in sample too, and the
/// first frames of a release (people's label 3) are too short to classify.
/// Measured: 84/92 held out, 86/92 in sample (the authors' k-means: 78/92).
#[test]
fn people_agree_with_the_path_and_areas_on_held_out_squares() {
    let squares = corpus::squares();
    let (named, short): (Vec<&Square>, Vec<&Square>) = squares.iter().partition(|s| s.human != 3);
    assert_eq!((named.len(), short.len()), (92, 35));
    for s in &short {
        let c = classify(&s.trajectory, s.chord);
        assert_eq!(c.class, MotionClass::Undetermined, "{}", s.name);
        assert!(
            c.reason.as_deref().unwrap().contains("too short"),
            "{}",
            s.name
        );
    }
    let with_areas = cases(&named, true);
    assert!(with_areas.iter().all(|c| c.1 == Inputs::Areas));
    let agree = |found: &[MotionClass]| {
        found
            .iter()
            .zip(&with_areas)
            .filter(|(f, c)| **f == c.2)
            .count()
    };
    let shipped: Vec<MotionClass> = with_areas
        .iter()
        .map(|c| verdict(c.0.clone(), c.1, &Calibration::default()).class)
        .collect();
    let in_sample = agree(&shipped);
    let loo: Vec<MotionClass> = corpus::leave_one_out(&with_areas)
        .iter()
        .map(|l| l.0)
        .collect();
    let held_out = agree(&loo);
    assert!(in_sample >= 85, "in sample: {in_sample}/92");
    assert!(held_out >= 83, "held out: {held_out}/92, below 90 %");
    // Per release, held out (measured 46/50 flat, 38/42 on edge): neither
    // carries the other.
    for edge in [false, true] {
        let (mut ok, mut n) = (0, 0);
        for ((s, f), c) in named.iter().zip(&loo).zip(&with_areas) {
            if s.on_edge == edge {
                n += 1;
                ok += usize::from(*f == c.2);
            }
        }
        assert!(ok as f64 >= 0.85 * n as f64, "on edge {edge}: {ok}/{n}");
    }
    // Path alone (no areas) is weaker: 77/92 held out.
    let path_only = cases(&named, false);
    let loo: Vec<MotionClass> = corpus::leave_one_out(&path_only)
        .iter()
        .map(|l| l.0)
        .collect();
    let path_agree = loo
        .iter()
        .zip(&path_only)
        .filter(|(f, c)| **f == c.2)
        .count();
    assert!(path_agree >= 74, "path only, held out: {path_agree}/92");
}

/// Consistency with the full classifier on the falls the tests hold
/// (leafmagic's and MuJoCo's, 163): quaternions stripped, and as video
/// (98 Hz, 1 mm noise, two cuts of 1.5 s). Of the falls the full classifier
/// names, measured: 151/158 (95.6 %) stripped, 272/316 (86.1 %) as video,
/// 276/316 (87.3 %) as video with two cameras' areas; at 24 Hz with the
/// orientation, all as at 240 Hz. Stripped meets the
/// issue's 95 %; video does not (docs/guide/classification.md: what a 1.5 s cut
/// can hold), and is held here so that it does not slip further.
#[test]
fn the_path_alone_mostly_agrees_with_the_full_classifier() {
    let falls = corpus::falls();
    let (mut stripped, mut video, mut named) = (0usize, 0usize, 0usize);
    let mut with_areas = 0usize;
    for (i, f) in falls.iter().enumerate() {
        let full = classify(&f.trajectory, f.chord).class;
        if full == MotionClass::Undetermined {
            continue;
        }
        named += 1;
        let tr = f.trajectory.without_orientation();
        stripped += usize::from(classify(&tr, f.chord).class == full);
        for v in corpus::video_cuts(f, i, 98.0, false) {
            video += usize::from(classify(&v, f.chord).class == full);
        }
        for a in corpus::video_cuts(f, i, 98.0, true) {
            with_areas += usize::from(classify(&a, f.chord).class == full);
        }
    }
    assert!(named >= 150, "{named}");
    // At film's 24 frames per second, with the orientation: the same class
    // from the orientation (measured: 158/158; with the held-out falls
    // 245/245, `cargo run --release --example real_falls_classify`).
    let at_24 = falls
        .iter()
        .filter(|f| {
            let full = classify(&f.trajectory, f.chord);
            let film = classify(&f.trajectory.resampled(24.0), f.chord);
            full.class != MotionClass::Undetermined
                && film.inputs == Inputs::Orientation
                && film.class == full.class
        })
        .count();
    assert!(
        at_24 as f64 >= 0.98 * named as f64,
        "at 24 Hz: {at_24}/{named}"
    );
    let s = stripped as f64 / named as f64;
    let v = video as f64 / (2 * named) as f64;
    assert!(s >= 0.95, "stripped: {stripped}/{named}");
    assert!(v >= 0.85, "video: {video}/{}", 2 * named);
    let a = with_areas as f64 / (2 * named) as f64;
    assert!(a >= 0.86, "video + areas: {with_areas}/{}", 2 * named);
}

/// The path features of a real tumbling square (square_000, 4.2 cm
/// diagonal), without orientation, with or without its area signals: the
/// base the rule tests below vary.
fn square_000_features(areas: bool) -> PathFeatures {
    let tr = Trajectory::read_csv(&square_file("square_000")).unwrap();
    let options = ClassifyOptions {
        orientation: false,
        areas,
    };
    classify_with(&tr, 0.042, options).path.unwrap()
}

/// `leafmagic classify FILE --size SIZE --json EXTRA…`, which must succeed:
/// its JSON and its stderr.
fn classify_json(file: &Path, size: &str, extra: &[&str]) -> (serde_json::Value, String) {
    let out = leafmagic()
        .args(["classify", "--size", size, "--json"])
        .args(extra)
        .arg(file)
        .output()
        .unwrap();
    crate::common::assert_succeeded(&out);
    let json = serde_json::from_slice(&out.stdout).unwrap();
    (json, String::from_utf8_lossy(&out.stderr).into_owned())
}

/// Rule 7b: a leaf falling straight down fast, nearly steadily, whose path
/// turns the same way on the whole is autorotating even when its centre
/// circles too irregularly for a helix; modulated like a rocking leaf, or
/// not turning, it is not named so.
#[test]
fn an_irregular_helix_straight_down_is_autorotation() {
    let base = square_000_features(false);
    // The features of the corpus's autorotating leaf this rule was added
    // for (a-varied-25: 12 rad/s about the vertical, tilted 70°).
    let named = |cv: f64, turns: f64, froude: f64| {
        let mut f = base.clone();
        f.drift_ratio = 0.002;
        f.straightness = 0.02;
        f.froude_number = froude;
        f.descent_speed_cv = cv;
        f.path_turns = turns;
        f.path_turn_consistency = 0.67;
        f.helix_radius_chords = 0.73;
        f.reversals = 1;
        let v = verdict(f, Inputs::Path, &Calibration::default());
        (v.class, v.regime, v.reason)
    };
    let (class, regime, reason) = named(0.054, 5.0, 3.56);
    assert_eq!(
        (class, regime),
        (MotionClass::Spinner, Regime::Autorotation)
    );
    assert!(reason.contains("circles irregularly"), "{reason}");
    // The same sign of turning either way round.
    assert_eq!(named(0.054, -5.0, 3.56).0, MotionClass::Spinner);
    assert_eq!(named(0.15, 5.0, 3.56).0, MotionClass::Lilter, "rocking");
    assert_eq!(
        named(0.054, 0.5, 3.56).0,
        MotionClass::Lilter,
        "not turning"
    );
    assert_eq!(named(0.054, 5.0, 1.5).0, MotionClass::Lilter, "slow");
}

/// With areas a tumble is named either fast (≥ 3.5 area maxima/s) or
/// regular (area periodicity ≥ 0.8, ≥ 2 maxima/s): a real tumbling square's
/// features slowed to 2.7 maxima/s stay a tumble only while its areas stay
/// periodic, and a regular but too slow or a wandering record is not one.
#[test]
fn a_slow_tumble_is_named_by_its_regular_turning() {
    let fast = square_000_features(true);
    let decided = |maxima: f64, periodicity: f64, straightness: f64| {
        let mut f = fast.clone();
        f.area_maxima_per_s = Some(maxima);
        f.area_periodicity = Some(periodicity);
        f.straightness = straightness;
        verdict(f, Inputs::Areas, &Calibration::default())
    };
    let named = |maxima, periodicity, straightness| {
        let v = decided(maxima, periodicity, straightness);
        (v.class, v.regime)
    };
    let tumble = (MotionClass::Spinner, Regime::Tumble);
    assert_eq!(named(5.0, 0.1, 0.9), tumble, "fast: the rate suffices");
    assert_eq!(named(2.7, 0.95, 0.9), tumble, "slow but regular");
    assert_eq!(
        named(2.7, 0.5, 0.9).0,
        MotionClass::Lilter,
        "slow, irregular"
    );
    assert_eq!(named(1.5, 0.95, 0.9).0, MotionClass::Lilter, "too slow");
    assert_eq!(
        named(2.7, 0.95, 0.3).0,
        MotionClass::Lilter,
        "regular turning on a wandering path"
    );
    let reason = decided(2.7, 0.95, fast.straightness).reason;
    assert!(reason.contains("regularly"), "{reason}");
}

/// Rule 5 at video rates: where the record's jitter hides a modulation of
/// 0.04, a glide needs areas that show no plate turning at a tumble's rate;
/// where it does not, or without areas, the rule is as it was.
#[test]
fn a_glide_turns_no_plate_where_the_record_cannot_resolve_steadiness() {
    let base = square_000_features(true);
    let named = |modulation_noise: f64, maxima: f64, inputs: Inputs| {
        let mut f = base.clone();
        f.descent_speed_cv = 0.0;
        f.modulation_noise = modulation_noise;
        f.area_maxima_per_s = Some(maxima);
        let v = verdict(f, inputs, &Calibration::default());
        (v.class, v.regime, v.reason)
    };
    let (class, regime, _) = named(0.08, 7.0, Inputs::Areas);
    assert_eq!((class, regime), (MotionClass::Spinner, Regime::Tumble));
    let (class, regime, reason) = named(0.08, 1.0, Inputs::Areas);
    assert_eq!((class, regime), (MotionClass::Floater, Regime::Glide));
    assert!(
        reason.contains("steady only as far as the record resolves"),
        "{reason}"
    );
    let (class, _, reason) = named(0.01, 7.0, Inputs::Areas);
    assert_eq!(class, MotionClass::Floater, "resolved steady: {reason}");
    assert!(
        !reason.contains("as far as the record resolves"),
        "{reason}"
    );
    let (class, _, _) = named(0.08, 7.0, Inputs::Path);
    assert_eq!(class, MotionClass::Floater, "the path alone cannot tell");
}

/// An area maximum is a swing of a fifth of the signal's range and a tenth
/// of its level: a steady plate's flicker (2 %) is none, a plate turning at
/// ω shows two per turn.
#[test]
fn area_maxima_count_turns_not_flicker() {
    let rate = 98.0;
    let record = |area: &dyn Fn(f64, usize) -> f64| {
        let mut tr = Trajectory::default();
        let mut values = Vec::new();
        for k in 0..147 {
            let t = k as f64 / rate;
            tr.push_position(t, nalgebra::Vector3::new(0.3 * t, 0.0, -0.6 * t));
            values.push(area(t, k));
        }
        tr.areas.push(leafmagic::motion::trajectory::AreaSignal {
            name: "area".into(),
            values,
        });
        let options = ClassifyOptions {
            orientation: false,
            areas: true,
        };
        classify_with(&tr, 0.042, options)
            .path
            .unwrap()
            .area_maxima_per_s
            .unwrap()
    };
    // A deterministic ±2 % flicker (a hash of the frame).
    let flicker = |k: usize| ((k * 2_654_435_761) % 1000) as f64 / 500.0 - 1.0;
    let steady = record(&|_, k| 1.0 + 0.02 * flicker(k));
    assert!(steady < 0.5, "flicker counted: {steady} maxima/s");
    let w = 10.0;
    let turning = record(&|t, k| (w * t).cos().abs() * (1.0 + 0.02 * flicker(k)));
    let expected = w / std::f64::consts::PI;
    assert!(
        (turning - expected).abs() < 0.7,
        "{turning} maxima/s, {expected} expected"
    );
}

/// The real squares' films with every 3rd or 4th frame kept (32.7 and 24.5
/// fps) agree with people as at 98 fps (measured: 86/92 at each, as at 98;
/// 82 and 79 before rule 5 looked at the areas where the jitter hides the
/// modulation).
#[test]
fn the_squares_at_video_frame_rates_agree_with_people() {
    let squares = corpus::squares();
    let named: Vec<&Square> = squares.iter().filter(|s| s.human != 3).collect();
    for k in [3, 4] {
        let agree = named
            .iter()
            .filter(|s| {
                classify(&s.trajectory.every(k), s.chord).class == corpus::human_class(s.human)
            })
            .count();
        assert!(agree >= 85, "every {k}th frame: {agree}/92");
    }
}

/// `classify` on a real square: the inputs used, the features behind the
/// decision in --json, columns in any order with an extra one noted, and
/// --up y.
#[test]
fn classify_reads_real_records_by_header_and_says_what_it_used() {
    let (json, _) = classify_json(&square_file("square_000"), "0.042", &[]);
    assert_eq!(json["class"], "spinner");
    assert_eq!(json["regime"], "tumble");
    assert_eq!(json["inputs"], "areas");
    assert!(json["features"]["straightness"].as_f64().unwrap() > 0.9);
    assert!(json["features"]["area_maxima_per_s"].as_f64().unwrap() > 5.0);

    let file = square_y_up("real-yup", "square_000");
    let (back, stderr) = classify_json(&file, "0.042", &["--up", "y"]);
    assert_eq!(back["class"], "spinner");
    assert_eq!(back["ignored_columns"], serde_json::json!(["frame"]));
    assert!(stderr.contains("ignored column frame"), "{stderr}");
    let d = |j: &serde_json::Value, k: &str| j["features"][k].as_f64().unwrap();
    for k in ["straightness", "drift_ratio", "mean_descent_speed_m_s"] {
        assert!((d(&json, k) - d(&back, k)).abs() < 1e-9, "{k}");
    }
}

/// A fall baked at film's 24 frames per second with its orientation, as an
/// animation package would write it, is named from the orientation; at 12
/// it is below both classifiers' floor and says so for each.
#[test]
fn a_pose_record_at_film_frame_rate_is_classified_from_its_orientation() {
    let source =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/mujoco-falls/tumble_thick.csv");
    let text = std::fs::read_to_string(&source).unwrap();
    let every = |k: usize| -> String {
        let mut lines = text.lines();
        let mut out = format!("{}\n", lines.next().unwrap());
        for line in lines.step_by(k) {
            out.push_str(line);
            out.push('\n');
        }
        out
    };
    let dir = scratch("real-film");
    let json_of = |name: &str, k: usize| {
        let file = dir.join(name);
        std::fs::write(&file, every(k)).unwrap();
        classify_json(&file, "0.04", &[]).0
    };
    let film = json_of("film.csv", 10);
    assert_eq!(
        (&film["class"], &film["regime"], &film["inputs"]),
        (&"spinner".into(), &"tumble".into(), &"orientation".into()),
        "{film}"
    );
    assert!((film["features"]["sample_rate_hz"].as_f64().unwrap() - 24.0).abs() < 0.01);
    // A 3 s clip of it (the last 3 s: 1.8 s of window, 43 samples) is
    // named from its orientation too: the window needs 60 samples or 1 s.
    let clip: String = {
        let all = every(10);
        let lines: Vec<&str> = all.lines().collect();
        let keep = 3 * 24 + 1;
        let mut out = format!("{}\n", lines[0]);
        for line in &lines[lines.len() - keep..] {
            out.push_str(line);
            out.push('\n');
        }
        out
    };
    let file = dir.join("clip.csv");
    std::fs::write(&file, clip).unwrap();
    let (clip, _) = classify_json(&file, "0.04", &[]);
    assert_eq!(
        (&clip["class"], &clip["inputs"]),
        (&"spinner".into(), &"orientation".into()),
        "{clip}"
    );
    let slow = json_of("slow.csv", 20);
    assert_eq!(slow["class"], "undetermined", "{slow}");
    let reason = slow["reason"].as_str().unwrap();
    assert!(
        reason.contains(
            "sampled at 12.0 Hz, below the 24 Hz minimum; from the path alone: sampled at 12.0 Hz"
        ),
        "{reason}"
    );
}

/// One camera's view of the real squares: the path in the vertical plane
/// it sees, with its area signal or without, the depth read as 0 (measured
/// with the camera of `area1`, looking along y: 83/92 with its area, 72/92
/// without; the other camera, along x: 75/92 and 65/92; both cameras:
/// 86/92 and 75/92). And through the CLI, a tracker's `t,x,y` export with y
/// up, noted as a fall in a vertical plane.
#[test]
fn one_cameras_view_of_the_squares_mostly_agrees_with_people() {
    let squares = corpus::squares();
    let named: Vec<&Square> = squares.iter().filter(|s| s.human != 3).collect();
    let agree = |areas: bool| {
        named
            .iter()
            .filter(|s| {
                let mut view = s.trajectory.clone();
                for p in &mut view.position {
                    p.y = 0.0;
                }
                view.areas.truncate(usize::from(areas));
                let options = ClassifyOptions {
                    orientation: false,
                    areas,
                };
                classify_with(&view, s.chord, options).class == corpus::human_class(s.human)
            })
            .count()
    };
    let (with_area, path_only) = (agree(true), agree(false));
    assert!(with_area >= 80, "one camera with its area: {with_area}/92");
    assert!(path_only >= 69, "one camera, path only: {path_only}/92");

    let tr = Trajectory::read_csv(&square_file("square_000")).unwrap();
    let mut text = String::from("t,x,y\n");
    for k in 0..tr.len() {
        let p = tr.position[k];
        text.push_str(&format!("{},{},{}\n", tr.time[k], p.x, p.z));
    }
    let file = scratch("real-tracker").join("tracker.csv");
    std::fs::write(&file, text).unwrap();
    let (json, stderr) = classify_json(&file, "0.042", &["--up", "y"]);
    assert_eq!(
        (&json["class"], &json["regime"]),
        (&"spinner".into(), &"tumble".into())
    );
    assert_eq!(json["depth_missing"], "z");
    assert!(
        stderr.contains("read as a fall in a vertical plane"),
        "{stderr}"
    );
}

/// A tracker's raw output: pixels, y counting image rows down, `t` a frame
/// number. The first real square seen by one camera as such a tracker
/// writes it (0.4 mm a pixel, 98 fps, the origin at the image's top left)
/// reads with `--up=-y --scale 0.0004 --frame-rate 98` as its metric `t,x,y`
/// record does with `--up y`: the same class, and every feature within
/// 1e-6 (the pixel file is written to 1e-4 px). Without the units it is
/// undetermined, the notes naming them.
#[test]
fn a_pixel_track_reads_as_its_metric_record() {
    let tr = Trajectory::read_csv(&square_file("square_000")).unwrap();
    let (metres_per_px, fps) = (0.0004, 98.0);
    let (mut metric, mut pixels) = (String::from("t,x,y\n"), String::from("t,x,y\n"));
    for k in 0..tr.len() {
        // Whole frames for both (the file's times are 0.010204 s steps).
        let (p, frame) = (tr.position[k], (tr.time[k] * fps).round());
        metric.push_str(&format!("{},{},{}\n", frame / fps, p.x, p.z));
        pixels.push_str(&format!(
            "{},{:.4},{:.4}\n",
            frame,
            (p.x + 0.3) / metres_per_px,
            (1.2 - p.z) / metres_per_px
        ));
    }
    let dir = scratch("pixel-tracker");
    let (m, px) = (dir.join("metres.csv"), dir.join("pixels.csv"));
    std::fs::write(&m, metric).unwrap();
    std::fs::write(&px, pixels).unwrap();
    let (want, _) = classify_json(&m, "0.042", &["--up", "y"]);
    let (got, _) = classify_json(
        &px,
        "0.042",
        &["--up=-y", "--scale", "0.0004", "--frame-rate", "98"],
    );
    assert_eq!(
        (&got["class"], &got["regime"]),
        (&want["class"], &want["regime"])
    );
    let (fw, fg) = (
        want["features"].as_object().unwrap(),
        got["features"].as_object().unwrap(),
    );
    assert_eq!(fw.keys().collect::<Vec<_>>(), fg.keys().collect::<Vec<_>>());
    for (name, w) in fw {
        if let (Some(w), Some(g)) = (w.as_f64(), fg[name].as_f64()) {
            // Positions differ by the pixels' rounding, 1e-4 px = 4e-8 m.
            assert!(
                (g - w).abs() <= 1e-6 * w.abs().max(1e-3),
                "{name}: {g} from pixels against {w} from metres"
            );
        }
    }
    let (raw, stderr) = classify_json(&px, "0.042", &["--up=-y"]);
    assert_eq!(raw["class"], "undetermined");
    assert!(
        stderr.contains("in seconds; is it in frames"),
        "the note names the time unit: {stderr}"
    );
}

/// A tracker that loses the leaf writes rows without a position (empty or
/// NaN): they are left out and noted with their lines (the squares' files
/// end their lines with CRLF, where the csv crate's line count lags), and
/// what remains is a record with a gap, bridged when short and refused
/// when long.
#[test]
fn frames_where_the_tracker_lost_the_leaf_are_gaps() {
    let text = std::fs::read_to_string(square_file("square_000")).unwrap();
    assert!(
        text.contains("\r\n"),
        "the squares' files end lines with CRLF"
    );
    let blanked = |lines: std::ops::RangeInclusive<usize>, blank: &str| -> String {
        text.split_inclusive('\n')
            .enumerate()
            .map(|(k, line)| {
                if lines.contains(&(k + 1)) {
                    let f: Vec<&str> = line.trim_end().split(',').collect();
                    format!("{},{blank},{blank},{blank},{},{}\r\n", f[0], f[4], f[5])
                } else {
                    line.to_string()
                }
            })
            .collect()
    };
    let dir = scratch("real-lost");
    let short = dir.join("short.csv");
    std::fs::write(&short, blanked(40..=42, "")).unwrap();
    let (json, stderr) = classify_json(&short, "0.042", &[]);
    assert_eq!(
        (&json["class"], &json["lost_rows"]),
        (&"spinner".into(), &3.into())
    );
    assert_eq!(json["features"]["gaps"], 1);
    assert!(
        stderr.contains("short.csv: left out 3 rows without a position")
            && stderr.contains("lines 40–42"),
        "{stderr}"
    );
    let long = dir.join("long.csv");
    std::fs::write(&long, blanked(40..=60, "NaN")).unwrap();
    let (json, _) = classify_json(&long, "0.042", &[]);
    assert_eq!(json["class"], "undetermined");
    assert!(
        json["reason"].as_str().unwrap().contains("too gappy"),
        "{json}"
    );
}

/// A record read with the wrong vertical (a z-up square read as y up:
/// its y is its depth, its z rises), or a tracker's y pointing down as
/// image rows do, rises instead of falling: the reason asks about the axis.
#[test]
fn a_record_read_with_the_wrong_vertical_says_it_rises() {
    let (json, _) = classify_json(&square_file("square_000"), "0.042", &["--up", "y"]);
    assert_eq!(json["class"], "undetermined");
    let reason = json["reason"].as_str().unwrap();
    assert!(
        reason.contains("not falling") && reason.contains("it rises instead"),
        "{reason}"
    );
    let (json, _) = classify_json(&square_file("square_000"), "0.042", &[]);
    assert_eq!(json["class"], "spinner");
}

/// Filmed falls end on the floor and baked ones on the ground: a real
/// tumbling square that then lies still for a second (as video of it
/// would go on), and MuJoCo's tumbling card whose 24 Hz bake ends with 5 s
/// at rest, are named as their falls, the rest left out and said (before,
/// the square read as chaotic, and the rest filled more than half of the
/// card's analysis window).
#[test]
fn a_fall_that_ends_at_rest_is_classified_by_its_time_in_the_air() {
    let square = Trajectory::read_csv(&square_file("square_000")).unwrap();
    let end = |tr: &Trajectory| (*tr.time.last().unwrap(), *tr.position.last().unwrap());
    let mut landed = square.clone();
    let (t1, p1) = end(&square);
    for k in 1..=98 {
        landed.push_position(t1 + k as f64 / 98.0, p1);
        for a in &mut landed.areas {
            let last = *a.values.last().unwrap();
            a.values.push(last);
        }
    }
    let c = classify(&landed, 0.042);
    assert_eq!(
        (c.class, c.regime),
        (MotionClass::Spinner, Regime::Tumble),
        "{c:#?}"
    );
    let rest = c.at_rest.unwrap();
    assert!(
        (rest.after_s - 1.0).abs() < 0.05 && rest.before_s == 0.0,
        "{rest:?}"
    );
    assert!(c.reason.unwrap().contains("after landing: left out"));
    assert!(classify(&square, 0.042).at_rest.is_none());
    // classify and describe --json say what was cut.
    let file = scratch("real-landed").join("landed.csv");
    landed.write_csv(&file).unwrap();
    let (json, _) = classify_json(&file, "0.042", &[]);
    assert!(
        (json["at_rest"]["after_s"].as_f64().unwrap() - 1.0).abs() < 0.05,
        "{json}"
    );
    let out = leafmagic()
        .args(["describe", "--size", "0.042", "--json"])
        .arg(&file)
        .output()
        .unwrap();
    crate::common::assert_succeeded(&out);
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(json["class"], "spinner");
    assert!(
        (json["at_rest"]["after_s"].as_f64().unwrap() - 1.0).abs() < 0.05,
        "{json}"
    );

    let card =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/mujoco-falls/tumble_thick.csv");
    let card = Trajectory::read_csv(&card).unwrap().resampled(24.0);
    let mut baked = card.clone();
    let (t1, p1) = end(&card);
    let q1 = *card.orientation.last().unwrap();
    for k in 1..=120 {
        baked.push(t1 + k as f64 / 24.0, p1, q1);
    }
    let c = classify(&baked, 0.04);
    assert_eq!(
        (c.class, c.regime, c.inputs),
        (MotionClass::Spinner, Regime::Tumble, Inputs::Orientation),
        "{c:#?}"
    );
    assert!((c.at_rest.unwrap().after_s - 5.0).abs() < 0.1);
}

/// A record in millimetres is still read (the classes are scale-free), but
/// its speeds are a thousand times too high: `classify` says so on stderr,
/// naming the file; the same fall in metres gets no such note; nor a time
/// in frames, which reads as a record at 1 Hz.
#[test]
fn a_record_in_millimetres_or_frames_is_pointed_out() {
    let tr = Trajectory::read_csv(&square_file("square_000")).unwrap();
    let mut text = String::from("t,x,y,z\n");
    for k in 0..tr.len() {
        let p = tr.position[k] * 1000.0;
        text.push_str(&format!("{},{},{},{}\n", tr.time[k], p.x, p.y, p.z));
    }
    let file = scratch("real-mm").join("mm.csv");
    std::fs::write(&file, text).unwrap();
    let run = |file: &Path| {
        let out = leafmagic()
            .args(["classify", "--size", "0.042"])
            .arg(file)
            .output()
            .unwrap();
        crate::common::assert_succeeded(&out);
        String::from_utf8_lossy(&out.stderr).into_owned()
    };
    let stderr = run(&file);
    assert!(
        stderr.contains("mm.csv: it falls 997.")
            && stderr.contains("m in 1.388 s (719 m/s on average)")
            && stderr.contains("must be in metres"),
        "{stderr}"
    );
    let stderr = run(&square_file("square_000"));
    assert!(
        !stderr.contains("metres") && !stderr.contains("seconds"),
        "{stderr}"
    );
    // The time in frames: refused for its rate (1 Hz), and the note says why
    // it may be so slow.
    let mut text = String::from("t,x,y,z\n");
    for k in 0..tr.len() {
        let p = tr.position[k];
        text.push_str(&format!("{k},{},{},{}\n", p.x, p.y, p.z));
    }
    let file = scratch("real-frames").join("frames.csv");
    std::fs::write(&file, text).unwrap();
    let stderr = run(&file);
    assert!(
        stderr.contains("frames.csv: its samples are 1.000 s apart (median)")
            && stderr.contains("t must be in seconds; is it in frames or milliseconds?"),
        "{stderr}"
    );
}

/// `compare` takes `--up` and `--size` per file (`A,B`): a real square
/// written with y up is at distance 0 from itself with z up; one value for
/// both reads the z-up file wrong, and a third value is refused.
#[test]
fn compare_reads_each_file_with_its_own_vertical_and_size() {
    let yup = square_y_up("real-compare", "square_000");
    let zup = square_file("square_000");
    let compare = |extra: &[&str]| {
        leafmagic()
            .arg("compare")
            .args([&yup, &zup])
            .args(extra)
            .arg("--json")
            .output()
            .unwrap()
    };
    let out = compare(&["--up", "y,z", "--size", "0.042,0.042"]);
    crate::common::assert_succeeded(&out);
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(json["distance"], 0.0, "{json}");
    let out = compare(&["--up", "y", "--size", "0.042"]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("square_000.csv") && err.contains("it rises instead"),
        "{err}"
    );
    let out = compare(&["--up", "y,z,y"]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("one value for both files, or two"), "{err}");
}

/// A real square's record written as another tool might: columns
/// shuffled, y up, with a frame column. Returns the file.
fn square_y_up(dir: &str, name: &str) -> std::path::PathBuf {
    let tr = Trajectory::read_csv(&square_file(name)).unwrap();
    let mut text = String::from("frame,area2,y,t,z,x,area1\n");
    for k in 0..tr.len() {
        let p = tr.position[k];
        // z up → y up: (x, y, z) → (x, z, −y).
        text.push_str(&format!(
            "{k},{},{},{},{},{},{}\n",
            tr.areas[1].values[k], p.z, tr.time[k], -p.y, p.x, tr.areas[0].values[k]
        ));
    }
    let file = scratch(dir).join("yup.csv");
    std::fs::write(&file, text).unwrap();
    file
}

/// Bad records: an error naming the file, the line and the reason, or
/// `undetermined` with its reason; never a panic.
#[test]
fn bad_records_are_refused_with_file_line_and_reason() {
    let dir = scratch("real-bad");
    let ok = "0,0,0,1\n0.01,0,0,0.99\n";
    for (name, text, want) in [
        (
            "noz.csv",
            "t,x,y\n0,0,1\n",
            vec!["noz.csv", "line 1", "no column `z`, the vertical"],
        ),
        (
            "onlyz.csv",
            "t,z\n0,1\n",
            vec!["onlyz.csv", "line 1", "no column `x`, `y`"],
        ),
        (
            "back.csv",
            "t,x,y,z\n0,0,0,1\n0.02,0,0,0.9\n0.01,0,0,0.8\n",
            vec!["back.csv", "line 4", "not after"],
        ),
        (
            "nan.csv",
            &format!("t,x,y,z\n{ok}0.02,NaN,0,0.98\n") as &str,
            vec!["nan.csv", "line 4", "`x`", "not finite"],
        ),
    ] {
        let file = dir.join(name);
        std::fs::write(&file, text).unwrap();
        let out = leafmagic().arg("classify").arg(&file).output().unwrap();
        assert!(!out.status.success(), "{name}");
        let err = String::from_utf8_lossy(&out.stderr);
        for w in want {
            assert!(err.contains(w), "{name}: `{err}` lacks `{w}`");
        }
    }
    // Too short, too sparse, not falling: undetermined with the reason.
    let file = dir.join("short.csv");
    std::fs::write(&file, format!("t,x,y,z\n{ok}")).unwrap();
    let out = leafmagic().arg("classify").arg(&file).output().unwrap();
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("undetermined") && text.contains("too short"),
        "{text}"
    );
    let mut still = String::from("t,x,y,z\n");
    for k in 0..100 {
        still.push_str(&format!("{},0,0,1\n", k as f64 / 100.0));
    }
    let tr = Trajectory::from_csv_reader(still.as_bytes(), "still.csv").unwrap();
    let c = classify(&tr, 0.04);
    assert_eq!(c.class, MotionClass::Undetermined);
    assert!(c.reason.unwrap().contains("not falling"));
    let sparse = tr.resampled(10.0);
    let c = classify(&sparse, 0.04);
    assert!(c.reason.unwrap().contains("Hz"));
}

/// Video as it comes: uneven steps, dropped frames and short gaps are
/// bridged (and reported), a long gap is not; 25 fps and half a second
/// are enough.
#[test]
fn gaps_uneven_steps_and_low_rates_are_handled_and_reported() {
    let tr = Trajectory::read_csv(&square_file("square_000")).unwrap();
    let whole = classify(&tr, 0.042);
    assert_eq!(whole.class, MotionClass::Spinner);
    let keep = |drop: &dyn Fn(usize) -> bool| {
        let mut out = tr.clone();
        let k: Vec<usize> = (0..tr.len()).filter(|&k| !drop(k)).collect();
        out.time = k.iter().map(|&i| tr.time[i]).collect();
        out.position = k.iter().map(|&i| tr.position[i]).collect();
        for (a, b) in out.areas.iter_mut().zip(&tr.areas) {
            a.values = k.iter().map(|&i| b.values[i]).collect();
        }
        out
    };
    // Three frames dropped here and there: three gaps of 0.04 s, bridged.
    let gappy = keep(&|k| k == 30 || k == 31 || k == 32 || k == 70 || k == 100);
    let c = classify(&gappy, 0.042);
    assert_eq!(c.class, MotionClass::Spinner, "{:?}", c.reason);
    let p = c.path.unwrap();
    assert_eq!(p.gaps, 3);
    // Time stamps are printed to the microsecond.
    assert!(
        (p.longest_gap_s - 4.0 / 98.0).abs() < 1e-5,
        "{}",
        p.longest_gap_s
    );
    // Twenty frames missing: a gap of 0.21 s is not bridged.
    let holed = keep(&|k| (40..60).contains(&k));
    let c = classify(&holed, 0.042);
    assert_eq!(c.class, MotionClass::Undetermined);
    assert!(c.reason.unwrap().contains("too gappy"));
    // Uneven steps (every other frame 2 ms late): same class.
    let mut jitter = tr.clone();
    for k in (1..tr.len() - 1).step_by(2) {
        jitter.time[k] += 0.002;
    }
    assert_eq!(classify(&jitter, 0.042).class, MotionClass::Spinner);
    // 25 and 24 fps, and the first 0.6 s only: still named, never a panic.
    for short in [
        tr.resampled(25.0),
        tr.resampled(24.0),
        tr.sampled_at(&(0..60).map(|k| k as f64 / 98.0).collect::<Vec<_>>()),
    ] {
        let c = classify(&short, 0.042);
        assert_ne!(c.class, MotionClass::Undetermined, "{:?}", c.reason);
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    /// A real record mangled at random (bytes replaced, lines cut or
    /// swapped) reads or is refused with a message naming the source; what
    /// reads classifies without a panic.
    #[test]
    fn mangled_records_never_panic(
        edits in proptest::collection::vec((0usize..10_000, 0u8..=255), 1..6),
        cut in 0usize..20_000,
    ) {
        let mut bytes = std::fs::read(square_file("square_011")).unwrap();
        for (at, b) in edits {
            let k = at % bytes.len();
            bytes[k] = b;
        }
        bytes.truncate(cut.max(1).min(bytes.len()));
        match Trajectory::from_csv_reader(&bytes[..], "mangled.csv") {
            Ok(tr) => {
                let c = classify(&tr, 0.04);
                prop_assert!(c.reason.is_some());
            }
            Err(e) => prop_assert!(e.to_string().starts_with("mangled.csv"), "{}", e),
        }
    }
}

/// Motion design from a real fall: breeding from A toward a tumbling paper
/// square (positions and areas only) reaches its class; the distance counts
/// only what the example has (descent, drift, the tumbling rate its areas
/// give).
#[test]
fn breeding_like_a_real_tumbling_square_reaches_its_class() {
    let dir = scratch("like-square");
    let run = dir.join("run");
    let example = square_file("square_000");
    let args = [
        "--like",
        example.to_str().unwrap(),
        "--size",
        "0.04",
        "--population",
        "16",
        "--generations",
        "3",
        "--seconds",
        "3",
    ];
    let out = breed(&args, &run);
    crate::common::assert_succeeded(&out);
    let toml = std::fs::read_to_string(run.join("run.toml")).unwrap();
    assert!(toml.contains("tumble") && toml.contains("drift"), "{toml}");
    assert!(
        !toml.contains("tilt_std"),
        "not measured, not targeted: {toml}"
    );
    let index = std::fs::read_to_string(run.join("best/index.csv")).unwrap();
    let mut lines = index.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let row: Vec<&str> = lines.next().unwrap().split(',').collect();
    let class = row[header.iter().position(|h| *h == "class").unwrap()];
    assert_eq!(class, "spinner", "{index}");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("not measured"), "{stdout}");
}

/// `breed --like FILE --up y` reads a y-up example as `classify --up y`
/// does: the run it creates targets the same class and descriptors as the
/// z-up original and keeps the same example; `--up` without `--like` is
/// refused.
#[test]
fn breed_reads_a_y_up_example_with_up_y() {
    let dir = scratch("like-yup");
    let target = |example: &std::path::Path, up: &str, run: &str| {
        let run = dir.join(run);
        let args = [
            "--like",
            example.to_str().unwrap(),
            "--up",
            up,
            "--size",
            "0.04",
            "--create-only",
        ];
        let out = breed(&args, &run);
        crate::common::assert_succeeded(&out);
        let toml: toml::Table =
            toml::from_str(&std::fs::read_to_string(run.join("run.toml")).unwrap()).unwrap();
        let mut like = toml["settings"]
            .get("like")
            .cloned()
            .expect("run.toml has the target");
        // Where it came from differs; what it asks for must not.
        like.as_table_mut().unwrap().remove("source");
        like
    };
    let z = target(&square_file("square_000"), "z", "z");
    let y = target(&square_y_up("like-yup-file", "square_000"), "y", "y");
    assert!(z.get("descriptors").is_some(), "{z}");
    assert_eq!(z, y, "{z}");
    // The run keeps the example as read, z up: until 2026-12-05 it copied
    // the file read again as z up, so a y-up example was stored (and
    // plotted) lying on its side.
    let example = |run: &str| Trajectory::read_csv(&dir.join(run).join("example.csv")).unwrap();
    let (ez, ey) = (example("z"), example("y"));
    assert_eq!(ez.time, ey.time);
    assert_eq!(ez.position, ey.position, "example.csv's positions differ");
    // The y-up file read as z up is another fall.
    let wrong = target(&square_y_up("like-yup-file2", "square_000"), "z", "wrong");
    assert_ne!(z, wrong);

    let out = leafmagic()
        .args(["breed", "--up", "y", "--create-only", "--out"])
        .arg(dir.join("no-like"))
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("--like"), "{err}");
}
