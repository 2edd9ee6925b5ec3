//! The experiment redone in the simulator: one plate's filmed fall, what
//! it did by its rotation, and a bin of releases.

use super::departure;
use super::films::{CAMERAS, Camera, DROP_POINT, FLOOR_TRIM, FPS, Film, Label, smooth5};
use super::protocol::{
    AIR_DENSITY, AIR_VISCOSITY, EDGE_HEIGHT, EDGE_SEEN, FLAT_HEIGHT, PAPER, Protocol, Release,
    draught_field, release,
};
use super::segments::label_of;
use super::table::{BinStats, ByRelease, Measured, MovingDrop, release_stats, stats};
use leafmagic::leaf::AeroSpec;
use leafmagic::leaf::plates::{PlateShape, plate_meshed};
use leafmagic::motion::trajectory::Trajectory;
use leafmagic::physics::model::Model;
use leafmagic::physics::params::{Integrator, TimeStep};
use leafmagic::physics::pose::PoseTracker;
use leafmagic::physics::run::{StepError, resolve_step, run_sampled};
use leafmagic::physics::state::State;
use nalgebra::{UnitQuaternion, Vector3};
use rayon::prelude::*;

type V3 = Vector3<f64>;

/// Why a simulated release failed.
#[derive(Debug, thiserror::Error)]
pub enum ExperimentError {
    /// The plate could not be built.
    #[error(transparent)]
    Plate(#[from] leafmagic::leaf::plates::PlateError),
    /// The plate's model is invalid.
    #[error(transparent)]
    Model(#[from] leafmagic::physics::model::ModelError),
    /// No step could be chosen.
    #[error(transparent)]
    Step(#[from] StepError),
    /// The fall diverged.
    #[error(transparent)]
    Sim(#[from] leafmagic::physics::integrate::SimError),
    /// The release protocol is out of range ([`Protocol::check`]).
    #[error("release protocol: {0}")]
    Protocol(String),
    /// The films to compare with are not of one shape.
    #[error("films: {0}")]
    Films(String),
}

/// The camera's projected area of every triangle of `model` at `x`, px.
fn projected_area(model: &Model, x: &[V3], camera: &Camera) -> f64 {
    let c = V3::from(camera.centre);
    let axis = V3::from(camera.axis);
    let f2 = camera.focal[0] * camera.focal[1];
    model
        .triangles
        .iter()
        .map(|t| {
            let [a, b, cc] = t.corners;
            let big_n = (x[b] - x[a]).cross(&(x[cc] - x[a]));
            let r = (x[a] + x[b] + x[cc]) / 3.0 - c;
            let depth = r.dot(&axis);
            0.5 * f2 * big_n.dot(&r).abs() / depth.powi(3)
        })
        .sum()
}

fn centroid(model: &Model, x: &[V3]) -> V3 {
    let (mut sum, mut total) = (V3::zeros(), 0.0);
    for t in &model.triangles {
        let [a, b, c] = t.corners;
        let area = 0.5 * (x[b] - x[a]).cross(&(x[c] - x[a])).norm();
        sum += (x[a] + x[b] + x[c]) * (area / 3.0);
        total += area;
    }
    sum / total
}

/// A simulated drop as the cameras saw it.
#[derive(Clone, Debug, PartialEq)]
pub struct SimulatedDrop {
    /// The release.
    pub on_edge: bool,
    /// The labelled segments (a flat release's steady start included).
    pub segments: Vec<Measured>,
    /// The tumbling rate of the whole filmed drop.
    pub omega: Option<f64>,
    /// The plate's normal turned past the horizontal this many times.
    pub flips: usize,
    /// Simulated seconds to the floor.
    pub seconds: f64,
    /// A flat release's departure from its flat fall, measured on its film
    /// as on the real ones ([`departure::departure`]), s; `None` on edge or
    /// if it never departs.
    pub departs: Option<f64>,
    /// Its moving segment's fastest descent ([`Film::fastest_descent`]),
    /// m/s; `None` without one.
    pub fastest: Option<f64>,
    /// How far its moving segment's path turns ([`Film::path_turn`]),
    /// degrees; `None` without one or without a heading.
    pub turn: Option<f64>,
    /// What the plate's rotation did over the filmed fall ([`rotation_of`]).
    pub rotation: Rotation,
}

/// Longest fall simulated, s: a drop that has not reached the floor by
/// then is filmed as far as it got.
pub const MAX_SECONDS: f64 = 8.0;

/// The step of every drop of `model` in the experiment: Verlet at `--dt
/// auto` against the camera's frames. Found once per plate, not per
/// release: under the unsteady law it costs more than a short fall.
pub fn experiment_step(model: &Model) -> Result<f64, ExperimentError> {
    Ok(resolve_step(
        model,
        Integrator::Verlet,
        TimeStep::Auto,
        1.0 / FPS,
    )?)
}

/// Drops `model` (a plate of half-side `radius`) at step `dt`
/// ([`experiment_step`]) as `release` says, films it and measures it as
/// the experiment did.
pub fn simulate_drop(
    model: &Model,
    dt: f64,
    radius: f64,
    release: &Release,
    centres: &[[f64; 2]; 2],
) -> Result<SimulatedDrop, ExperimentError> {
    let frame_dt = 1.0 / FPS;
    let height = if release.on_edge {
        EDGE_HEIGHT
    } else {
        FLAT_HEIGHT
    };
    let start = V3::new(DROP_POINT[0], DROP_POINT[1], height);
    let mut state = State::released(model, release.rotation, start);
    let mut raw = Film::default();
    let mut normals = Vec::new();
    // The plate's best-fit rotation per frame, for what its rotation did
    // ([`rotation_of`]).
    let mut poses = (PoseTracker::new(model, release.rotation), Vec::new());
    type Poses = (PoseTracker, Vec<UnitQuaternion<f64>>);
    let record = |x: &[V3], raw: &mut Film, normals: &mut Vec<f64>, poses: &mut Poses| {
        raw.position.push(centroid(model, x));
        for (k, cam) in CAMERAS.iter().enumerate() {
            raw.area[k].push(projected_area(model, x, cam));
        }
        let t = &model.triangles[0];
        let [a, b, c] = t.corners;
        normals.push((x[b] - x[a]).cross(&(x[c] - x[a])).z);
        let (_, rotation) = poses.0.pose(model, x);
        poses.1.push(rotation);
    };
    // In chunks of 0.5 s until the floor.
    let chunk = (0.5 * FPS).round() as u64;
    record(&state.position, &mut raw, &mut normals, &mut poses);
    while raw.position.last().is_some_and(|p| p.z > 0.0) && state.time < MAX_SECONDS {
        run_sampled(
            model,
            &mut state,
            Integrator::Verlet,
            dt,
            frame_dt,
            chunk,
            |k, x| {
                if k > 0 {
                    record(x, &mut raw, &mut normals, &mut poses);
                }
            },
        )?;
    }
    let seconds = state.time;
    // Film: from the first frame at or below the first filmed height, cut
    // at the first below the floor; smoothed; x, y from the first frame.
    let first = if release.on_edge {
        raw.position
            .iter()
            .position(|p| p.z <= EDGE_SEEN)
            .unwrap_or(0)
    } else {
        0
    };
    let last = raw
        .position
        .iter()
        .position(|p| p.z < 0.0)
        .unwrap_or(raw.len());
    let cut = raw.slice(first, last.max(first));
    let flips = normals[first..last.max(first)]
        .windows(2)
        .filter(|w| w[0].signum() != w[1].signum())
        .count();
    let rotation = rotation_of(
        &Trajectory {
            time: (first..last.max(first)).map(|k| k as f64 / FPS).collect(),
            position: cut.position.clone(),
            orientation: poses.1[first..last.max(first)].to_vec(),
            areas: Vec::new(),
        },
        2.0 * radius,
    );
    let coord = |k: usize| smooth5(&cut.position.iter().map(|p| p[k]).collect::<Vec<_>>());
    let (xs, ys, zs) = (coord(0), coord(1), coord(2));
    let mut film = Film {
        position: (0..cut.len())
            .map(|k| V3::new(xs[k] - xs[0], ys[k] - ys[0], zs[k]))
            .collect(),
        area: [smooth5(&cut.area[0]), smooth5(&cut.area[1])],
    };
    let omega = film.tumbling_rate();
    // Segments (classifyBehaviour.m): trim the end below FLOOR_TRIM; a flat
    // release's start until 0.2 r sideways is steady.
    let mut n = film.len();
    while n > 0 && film.position[n - 1].z < FLOOR_TRIM {
        n -= 1;
    }
    film = film.slice(0, n);
    let departs = if release.on_edge {
        None
    } else {
        departure::departure(radius, &film).and_then(|d| d.departs)
    };
    let threshold = if release.on_edge { 0.01 } else { 0.2 * radius };
    let mut tc = 1;
    while tc < n && film.position[tc - 1].xy().norm() < threshold {
        tc += 1;
    }
    let mut segments = Vec::new();
    let mut fastest = None;
    let mut turn = None;
    let mut push = |from: usize, to: usize, steady: bool| {
        let cut = film.slice(from, to);
        if let Some(features) = cut.features() {
            let label = if steady {
                Label::Steady
            } else {
                fastest = cut.fastest_descent();
                turn = cut.path_turn();
                label_of(&features, centres)
            };
            segments.push(Measured { label, features });
        }
    };
    if !release.on_edge && tc > 2 {
        push(0, tc, true);
        if n > tc + 10 {
            push(tc - 1, n, false);
        }
    } else if !release.on_edge {
        push(0, n, false);
    } else if n > tc + 10 {
        push(tc - 1, n, false);
    }
    Ok(SimulatedDrop {
        on_edge: release.on_edge,
        segments,
        omega,
        flips,
        seconds,
        departs,
        fastest,
        turn,
        rotation,
    })
}

/// What a simulated fall did, read from its rotation rather than from the
/// experiment's labelling rule ([`label_of`], whose features have units:
/// a large plate tumbling end over end shows as few area maxima per second
/// as a small one falling chaotically).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Rotation {
    /// Turned end over end without reversing, a whole turn (two flips) or
    /// more.
    Tumbling,
    /// Swung back and forth without turning over.
    Fluttering,
    /// Both: turned over and swung back (the chaotic regime's mark).
    Mixed,
    /// Neither reversed nor turned over.
    Steady,
}

/// What a fall did by its plate's rotation over the whole of `trajectory`
/// (`size` its chord, m), read with the motion classifier's own kinematics
/// ([`leafmagic::motion::classify::pose_features`]: a reversal is a turning
/// point of a swing of at least 10° about the dominant axis, a flip the
/// normal crossing the horizontal with ±30° hysteresis): tumbling with no
/// reversal and at least two flips (a whole turn), fluttering with
/// reversals and no flip, mixed with both, steady otherwise.
pub fn rotation_of(trajectory: &Trajectory, size: f64) -> Rotation {
    let f = leafmagic::motion::classify::pose_features(trajectory, size);
    match (f.reversals > 0, f.normal_flips) {
        (false, flips) if flips >= 2 => Rotation::Tumbling,
        (true, 0) => Rotation::Fluttering,
        (true, _) => Rotation::Mixed,
        (false, _) => Rotation::Steady,
    }
}

/// How many of `drops` let go on edge (`on_edge`) or flat fell each way
/// ([`SimulatedDrop::rotation`]), in the order of [`Rotation`]'s variants:
/// tumbling, fluttering, mixed, steady.
pub fn rotation_counts(drops: &[SimulatedDrop], on_edge: bool) -> [usize; 4] {
    let mut counts = [0; 4];
    for d in drops.iter().filter(|d| d.on_edge == on_edge) {
        counts[d.rotation as usize] += 1;
    }
    counts
}

impl SimulatedDrop {
    /// The experiment's label of its moving (tumbling or chaotic) segment,
    /// if it has one.
    pub fn moving_label(&self) -> Option<Label> {
        self.segments
            .iter()
            .map(|s| s.label)
            .find(|&l| l != Label::Steady)
    }
}

/// Which releases one bin's simulation makes: `releases` drops at `seed`,
/// the first `flat` of them flat, let go as `protocol` says.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BinReleases {
    /// The bin's index in [`SQUARE_BINS`](super::SQUARE_BINS) (it seeds the releases).
    pub bin: usize,
    /// Drops in the bin.
    pub releases: usize,
    /// How many of them are flat ([`flat_releases`](super::flat_releases)).
    pub flat: usize,
    /// The seed.
    pub seed: u64,
    /// How they are let go.
    pub protocol: Protocol,
}

/// The simulated side of one bin: the drops of `run` with a plate of
/// `shape` and size `side` (twice the inradius, as `leafmagic plate` reads
/// it) under `aero` (air and paper of the experiment).
pub fn simulate_bin(
    shape: PlateShape,
    side: f64,
    aero: &AeroSpec,
    run: &BinReleases,
    centres: &[[f64; 2]; 2],
) -> Result<(BinStats, Vec<SimulatedDrop>), ExperimentError> {
    run.protocol.check().map_err(ExperimentError::Protocol)?;
    let mut spec = plate_meshed(
        shape,
        side,
        run.protocol.plate_aspect(shape),
        PAPER,
        aero.clone(),
        run.protocol.refine,
    )?;
    if let Some(d) = run.protocol.bending {
        spec = leafmagic::leaf::plates::flexible(spec, d)?;
    }
    let model = spec.model()?;
    // Each release's own draught, if any; the step is found once, under the
    // strongest of them (a faster relative flow only shortens it).
    let fields: Vec<Option<leafmagic::physics::field::WindField>> = (0..run.releases)
        .map(|k| {
            run.protocol
                .draught
                .map(|d| draught_field(&d, run.seed, run.bin, k, MAX_SECONDS))
        })
        .collect();
    let strongest = fields
        .iter()
        .flatten()
        .max_by(|a, b| a.speed_bound().total_cmp(&b.speed_bound()));
    let dt = match strongest {
        Some(field) => experiment_step(&Model {
            wind: field.clone(),
            ..model.clone()
        })?,
        None => experiment_step(&model)?,
    };
    let drops: Vec<SimulatedDrop> = (0..run.releases)
        .into_par_iter()
        .map(|k| {
            let gusty = fields[k].as_ref().map(|field| Model {
                wind: field.clone(),
                ..model.clone()
            });
            simulate_drop(
                gusty.as_ref().unwrap_or(&model),
                dt,
                0.5 * side,
                &release(&run.protocol, run.seed, run.bin, k, run.flat),
                centres,
            )
        })
        .collect::<Result<_, _>>()?;
    let segments: Vec<Measured> = drops
        .iter()
        .flat_map(|d| d.segments.iter().copied())
        .collect();
    let omegas: Vec<Option<f64>> = drops.iter().map(|d| d.omega).collect();
    Ok((stats(&segments, &omegas, drops.len(), side), drops))
}

/// The experiment's air in an `[aero]` table of law `law`: its density and
/// viscosity (the unsteady law), its density (the quadratic law).
pub fn experiment_air(mut aero: AeroSpec) -> AeroSpec {
    for (key, value) in [
        ("air_density", AIR_DENSITY),
        ("kinematic_viscosity", AIR_VISCOSITY),
    ] {
        if aero.takes(key) && aero.number(key).is_none() {
            aero.set_number(key, value);
        }
    }
    aero
}

/// The share of one simulated bin's moving drops (`drops`, as
/// [`sim_by_release`] splits them) that were let go flat: the share to
/// re-weight the films to ([`real_table_at_mix`](super::real_table_at_mix)); NaN without any.
pub fn sim_flat_share(drops: &[SimulatedDrop]) -> f64 {
    sim_by_release(drops).flat_share()
}

/// One bin's simulated drops split by release.
pub fn sim_by_release(drops: &[SimulatedDrop]) -> ByRelease {
    let side = |on_edge: bool| {
        let mine = drops.iter().filter(|d| d.on_edge == on_edge);
        let moving: Vec<MovingDrop> = mine
            .clone()
            .flat_map(|d| {
                d.segments
                    .iter()
                    .filter(|m| m.label != Label::Steady)
                    .map(|m| MovingDrop {
                        features: m.features,
                        omega: d.omega,
                        fastest: d.fastest,
                        turn: d.turn,
                    })
            })
            .collect();
        let steady: Vec<f64> = mine
            .clone()
            .flat_map(|d| d.segments.iter())
            .filter(|m| m.label == Label::Steady)
            .map(|m| m.features.time)
            .collect();
        let departs: Vec<f64> = mine.filter_map(|d| d.departs).collect();
        release_stats(&moving, &steady, &departs)
    };
    ByRelease {
        flat: side(false),
        edge: side(true),
    }
}
