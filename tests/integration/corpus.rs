//! The falls the classifier is held to, gathered in one place: leafmagic's
//! own (the paper's recipes and their seeded families, variants of
//! prototype A, the fixtures at three releases, the flat card under both
//! laws — the falls `classes.rs` tests) and the six MuJoCo falls of
//! `tests/data/mujoco-falls`; and what video of each would give: positions
//! only, resampled, cut short, noisy, with the projected areas two cameras
//! would see. And the real paper squares of `tests/data/real-falls/squares`
//! with people's labels, and the leave-one-out refit of the two thresholds
//! calibrated on them. Shared by `real_falls.rs` and
//! `lab/examples/real_falls_classify.rs`.

use leafmagic::leaf::genome::{Genome, mutate};
use leafmagic::leaf::plates::{self, square_card};
use leafmagic::leaf::recipes::Recipe;
use leafmagic::leaf::{AeroSpec, LeafSpec};
use leafmagic::motion::classify::MotionClass;
use leafmagic::motion::path::{Calibration, Inputs, PathFeatures, verdict};
use leafmagic::motion::trajectory::{AreaSignal, Trajectory};
use leafmagic::sim::drop::{DropParams, drop_leaf};
use nalgebra::Vector3;
use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;
use rand_distr::{Distribution, Normal};
use rayon::prelude::*;
use std::path::Path;

/// One recorded fall and the chord it is classified with.
pub struct Fall {
    /// Where it comes from.
    pub name: String,
    /// Its pose record (10 s at 240 Hz).
    pub trajectory: Trajectory,
    /// The leaf's chord, m.
    pub chord: f64,
}

/// What to drop: a leaf and its release.
enum Source {
    Leaf(String, Box<LeafSpec>, [f64; 2]),
    File(String, &'static str),
}

/// The MuJoCo falls and their chord (tests/data/README.md).
pub const MUJOCO: [&str; 6] = [
    "steady_fall",
    "glide_ballast",
    "wobble_card",
    "flutter_strip",
    "tumble_thick",
    "tumble_cardscoef",
];
const MUJOCO_CHORD: f64 = 0.04;

/// Every fall of the corpus (163), dropped in parallel: ~1 s of CPU.
/// The prototype's bounds with the genes added in issue 19 (aspect ratio,
/// drag ratio, camber, petiole mass) held at their neutral values: the
/// varied leaves of this corpus are the ones the classifier's tests were
/// measured on (a fixed range draws nothing, so the other genes' draws are
/// unchanged).
fn classic_bounds(proto: &LeafSpec) -> leafmagic::leaf::Bounds {
    leafmagic::leaf::Bounds {
        aspect_ratio: [1.0, 1.0],
        drag_ratio: [1.0, 1.0],
        camber: [0.0, 0.0],
        petiole_mass: [0.0, 0.0],
        ..proto.bounds.clone()
    }
}

pub fn falls() -> Vec<Fall> {
    drop_all(sources())
}

/// Falls of the same families the corpus holds none of (the recipes'
/// variants 17–32, prototype A varied with seeds 40–79): the thresholds
/// chosen on leafmagic's own falls were not looked at on these.
pub fn held_out_falls() -> Vec<Fall> {
    let mut sources = Vec::new();
    for (recipe, tag) in [
        (Recipe::Floater, "recipe-floater"),
        (Recipe::Spinner, "recipe-spinner"),
        (Recipe::Lilter, "recipe-lilter"),
    ] {
        for seed in 17..=32u64 {
            let (spec, tilt) = recipe.variant(seed);
            sources.push(Source::Leaf(format!("{tag}-{seed}"), Box::new(spec), tilt));
        }
    }
    let proto = LeafSpec::load("a").unwrap();
    let start = Genome::of_prototype(&proto);
    for seed in 40..80u64 {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
        let genome = mutate(&start, &classic_bounds(&proto), 2.5, &mut rng);
        sources.push(Source::Leaf(
            format!("a-varied-{seed}"),
            Box::new(genome.to_leaf(&proto)),
            DropParams::default().tilt_deg,
        ));
    }
    drop_all(sources)
}

/// What the corpus drops.
fn sources() -> Vec<Source> {
    let mut sources = Vec::new();
    let default_tilt = DropParams::default().tilt_deg;
    for (recipe, tag) in [
        (Recipe::Floater, "recipe-floater"),
        (Recipe::Spinner, "recipe-spinner"),
        (Recipe::Lilter, "recipe-lilter"),
    ] {
        sources.push(Source::Leaf(
            tag.to_string(),
            Box::new(recipe.leaf()),
            default_tilt,
        ));
        for seed in 1..=16u64 {
            let (spec, tilt) = recipe.variant(seed);
            sources.push(Source::Leaf(format!("{tag}-{seed}"), Box::new(spec), tilt));
        }
    }
    let proto = LeafSpec::load("a").unwrap();
    let start = Genome::of_prototype(&proto);
    for seed in 0..40u64 {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
        let genome = mutate(&start, &classic_bounds(&proto), 2.5, &mut rng);
        sources.push(Source::Leaf(
            format!("a-varied-{seed}"),
            Box::new(genome.to_leaf(&proto)),
            default_tilt,
        ));
    }
    let fixtures = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures");
    for file in ["a-floater", "a-spinner", "a-tumbler", "a-lilter"] {
        let spec = LeafSpec::read(&fixtures.join(format!("{file}.toml"))).unwrap();
        for tilt in [[10.0, 2.0], [0.0, 0.0], [-15.0, 0.0]] {
            sources.push(Source::Leaf(
                format!("{file}@{};{}", tilt[0], tilt[1]),
                Box::new(spec.clone()),
                tilt,
            ));
        }
    }
    for sigma in [0.02, 0.1, 0.5] {
        for tilt in [[10.0, 2.0], [0.0, 20.0]] {
            sources.push(Source::Leaf(
                format!("card-linear-{sigma}@{};{}", tilt[0], tilt[1]),
                Box::new(square_card(0.05, sigma, AeroSpec::linear(0.47, 0.047))),
                tilt,
            ));
        }
    }
    for sigma in [0.02, 0.04, 0.1, 0.14, 0.3, 0.5] {
        for tilt in plates::RELEASE_ATTITUDES {
            sources.push(Source::Leaf(
                format!("card-quadratic-{sigma}@{};{}", tilt[0], tilt[1]),
                Box::new(square_card(0.05, sigma, AeroSpec::quadratic())),
                tilt,
            ));
        }
    }
    for name in MUJOCO {
        sources.push(Source::File(format!("mujoco-{name}"), name));
    }
    sources
}

/// Drops (or reads) every source, in parallel, in order.
fn drop_all(sources: Vec<Source>) -> Vec<Fall> {
    sources
        .into_par_iter()
        .map(|s| match s {
            Source::Leaf(name, spec, tilt) => {
                let model = spec.model().unwrap();
                let params = DropParams {
                    tilt_deg: tilt,
                    ..Default::default()
                };
                let trajectory = drop_leaf(&model, &params).unwrap().trajectory;
                Fall {
                    name,
                    trajectory,
                    chord: model.chord(),
                }
            }
            Source::File(name, file) => {
                let path = Path::new(env!("CARGO_MANIFEST_DIR"))
                    .join(format!("tests/data/mujoco-falls/{file}.csv"));
                Fall {
                    name,
                    trajectory: Trajectory::read_csv(&path).unwrap(),
                    chord: MUJOCO_CHORD,
                }
            }
        })
        .collect()
}

/// Two cameras as in the real squares' rig (tests/data/README.md): looking
/// down 40° and 50° below the horizontal, 51° apart in azimuth. Unit
/// vectors from the camera toward the leaf.
pub fn cameras() -> [Vector3<f64>; 2] {
    let view = |elevation_deg: f64, azimuth_deg: f64| {
        let (e, a) = (elevation_deg.to_radians(), azimuth_deg.to_radians());
        Vector3::new(e.cos() * a.cos(), e.cos() * a.sin(), -e.sin())
    };
    [view(40.0, 0.0), view(50.0, 51.0)]
}

/// What video of `fall` over `[t0, t0 + seconds]` would give: positions at
/// `fps`, each coordinate with Gaussian noise of `noise_m`, and (if
/// `areas`) the projected area of a flat plate seen by each of
/// [`cameras`], |n·d| of the plate normal n (with 2 % noise). Seeded: the
/// same arguments give the same record.
pub fn video(
    fall: &Trajectory,
    t0: f64,
    seconds: f64,
    fps: f64,
    noise_m: f64,
    areas: bool,
    seed: u64,
) -> Trajectory {
    let n = (seconds * fps + 1e-9).floor() as usize + 1;
    let times: Vec<f64> = (0..n).map(|k| t0 + k as f64 / fps).collect();
    let posed = fall.sampled_at(&times);
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let noise = Normal::new(0.0, noise_m.max(f64::MIN_POSITIVE)).unwrap();
    let flicker = Normal::new(0.0, 0.02).unwrap();
    let mut out = Trajectory::default();
    for (k, &t) in times.iter().enumerate() {
        let mut p = posed.position[k];
        if noise_m > 0.0 {
            for d in 0..3 {
                p[d] += noise.sample(&mut rng);
            }
        }
        out.push_position(t - t0, p);
    }
    if areas {
        for (c, d) in cameras().iter().enumerate() {
            let values = posed
                .orientation
                .iter()
                .map(|q| {
                    let n = q * Vector3::z();
                    n.dot(d).abs() * (1.0 + flicker.sample(&mut rng))
                })
                .collect();
            out.areas.push(AreaSignal {
                name: format!("area{}", c + 1),
                values,
            });
        }
    }
    out
}

/// The two 1.5 s video cuts of the `i`-th fall of a list that the
/// classifier's figures use (its last 1.5 s, and 5.0–6.5 s), as [`video`]
/// gives them at `fps` with 1 mm of noise, seeded by `i` and the cut.
pub fn video_cuts(fall: &Fall, i: usize, fps: f64, areas: bool) -> Vec<Trajectory> {
    let end = *fall.trajectory.time.last().unwrap();
    [end - 1.5, 5.0]
        .into_iter()
        .enumerate()
        .map(|(k, t0)| {
            video(
                &fall.trajectory,
                t0,
                1.5,
                fps,
                0.001,
                areas,
                (2 * i + k) as u64,
            )
        })
        .collect()
}

/// One labelled segment of a real paper square (tests/data/README.md).
pub struct Square {
    /// `square_NNN`.
    pub name: String,
    /// Released on edge (else flat).
    pub on_edge: bool,
    /// People's label: 1 tumbling, 2 chaotic, 3 steady/periodic (the first
    /// frames of a flat release).
    pub human: u8,
    /// The authors' k-means label.
    pub auto: u8,
    /// The chord to classify with: the square's diagonal (its longest
    /// extent, as leafmagic's chord), m.
    pub chord: f64,
    /// The record: `t,x,y,z,area1,area2`.
    pub trajectory: Trajectory,
}

/// The 127 segments, in file order.
pub fn squares() -> Vec<Square> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/real-falls/squares");
    let labels = std::fs::read_to_string(dir.join("labels.csv")).unwrap();
    let mut lines = labels.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (name, radius, edge, human, auto) = (
        col("name"),
        col("radius_m"),
        col("release_vertical"),
        col("human"),
        col("auto"),
    );
    lines
        .map(|line| {
            let f: Vec<&str> = line.split(',').collect();
            let side = 2.0 * f[radius].parse::<f64>().unwrap();
            Square {
                name: f[name].to_string(),
                on_edge: f[edge] == "1",
                human: f[human].parse().unwrap(),
                auto: f[auto].parse().unwrap(),
                chord: side * std::f64::consts::SQRT_2,
                trajectory: Trajectory::read_csv(&dir.join(format!("{}.csv", f[name]))).unwrap(),
            }
        })
        .collect()
}

/// The class people's label stands for: tumbling → spinner, chaotic →
/// lilter, steady/periodic (a release artefact) → undetermined.
pub fn human_class(label: u8) -> MotionClass {
    match label {
        1 => MotionClass::Spinner,
        2 => MotionClass::Lilter,
        _ => MotionClass::Undetermined,
    }
}

/// Candidate thresholds between the sorted distinct values, at most `max`.
fn candidates(mut values: Vec<f64>, max: usize) -> Vec<f64> {
    values.sort_by(f64::total_cmp);
    values.dedup();
    let mids: Vec<f64> = values.windows(2).map(|w| 0.5 * (w[0] + w[1])).collect();
    let step = mids.len().div_ceil(max).max(1);
    mids.into_iter().step_by(step).collect()
}

/// The calibration that agrees with the most `(features, inputs, class)`
/// of `train` (ties: the median of the tied values of each threshold, if
/// it ties too, else the first tie).
pub fn fit(train: &[&(PathFeatures, Inputs, MotionClass)]) -> Calibration {
    let straight = candidates(train.iter().map(|t| t.0.straightness).collect(), 40);
    let mut rate = candidates(
        train
            .iter()
            .filter(|t| t.1 == Inputs::Areas)
            .filter_map(|t| t.0.area_maxima_per_s)
            .collect(),
        40,
    );
    if rate.is_empty() {
        // Without areas the rate is not looked at.
        rate.push(Calibration::default().tumble_min_area_maxima_per_s);
    }
    let score = |c: &Calibration| {
        train
            .iter()
            .filter(|t| verdict(t.0.clone(), t.1, c).class == t.2)
            .count()
    };
    let mut best = 0;
    let mut ties: Vec<Calibration> = Vec::new();
    for &s in &straight {
        for &r in &rate {
            let c = Calibration {
                tumble_min_straightness: s,
                tumble_min_area_maxima_per_s: r,
            };
            let n = score(&c);
            if n > best {
                best = n;
                ties.clear();
            }
            if n == best {
                ties.push(c);
            }
        }
    }
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let middle = Calibration {
        tumble_min_straightness: median(ties.iter().map(|c| c.tumble_min_straightness).collect()),
        tumble_min_area_maxima_per_s: median(
            ties.iter()
                .map(|c| c.tumble_min_area_maxima_per_s)
                .collect(),
        ),
    };
    if score(&middle) == best {
        middle
    } else {
        ties[0]
    }
}

/// Leave-one-out: each case classified with the calibration fitted to all
/// the others. Returns the classes and the calibrations.
pub fn leave_one_out(
    cases: &[(PathFeatures, Inputs, MotionClass)],
) -> Vec<(MotionClass, Calibration)> {
    (0..cases.len())
        .into_par_iter()
        .map(|i| {
            let train: Vec<&(PathFeatures, Inputs, MotionClass)> = cases
                .iter()
                .enumerate()
                .filter(|(j, _)| *j != i)
                .map(|(_, c)| c)
                .collect();
            let cal = fit(&train);
            (verdict(cases[i].0.clone(), cases[i].1, &cal).class, cal)
        })
        .collect()
}

/// The classes in table order.
pub const CLASSES: [MotionClass; 4] = [
    MotionClass::Floater,
    MotionClass::Spinner,
    MotionClass::Lilter,
    MotionClass::Undetermined,
];

/// Counts of (reference, found) class pairs: `[reference][found]` in
/// [`CLASSES`] order.
pub fn confusion(pairs: &[(MotionClass, MotionClass)]) -> [[usize; 4]; 4] {
    let k = |c: MotionClass| CLASSES.iter().position(|x| *x == c).unwrap();
    let mut t = [[0usize; 4]; 4];
    for &(a, b) in pairs {
        t[k(a)][k(b)] += 1;
    }
    t
}
