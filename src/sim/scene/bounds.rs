//! The scene's cost estimated from the parsed file, before any object is
//! built: its particles, the frames it records and the memory they take,
//! and a lower bound of its particle-steps. A scene past its limits is
//! refused here, in well under a second, instead of after building a model
//! of hundreds of thousands of particles (65,536 leaves took 11 s and 0.6
//! GB before the run's own checks refused them).

use super::builder::MAX_PARTICLES;
use super::compiled::MAX_MEMORY;
use super::error::{Ctx, SceneError};
use super::spec::{DtSpec, SceneSpec, Shape};
use crate::leaf::LeafSpec;
use crate::physics::run::{MAX_WORK, REFERENCE_RATE, approximate_duration};
use crate::physics::stability;
use crate::util::setting::Setting;
use std::collections::HashMap;

/// The limits a scene is held to, and what the command line sets over the
/// file: the duration it will run for and the law its leaves fall under.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Limits {
    /// Particle-steps (`scene --max-work`).
    pub max_work: f64,
    /// Bytes of recorded frames (`scene --max-memory`).
    pub max_memory: f64,
    /// The run's duration when not the file's (`scene --seconds`).
    pub seconds: Option<f64>,
    /// The aerodynamic law of every leaf when not its file's (`scene
    /// --law`, [`crate::leaf::LeafSpec::under_law`]).
    pub law: Option<crate::leaf::AeroLawName>,
}

impl Default for Limits {
    fn default() -> Limits {
        Limits {
            max_work: MAX_WORK,
            max_memory: MAX_MEMORY,
            seconds: None,
            law: None,
        }
    }
}

/// What the file asks for, counted without building it.
#[derive(Clone, Debug, Default, PartialEq)]
struct Estimate {
    /// Particles of every object.
    particles: f64,
    /// Particles whose positions are recorded every frame.
    recorded_particles: f64,
    /// Objects whose pose is recorded every frame.
    poses: f64,
    /// The largest step any leaf allows (its own stability bound), s.
    leaf_dt: Option<f64>,
    /// The object with the most particles, and how many.
    largest: Option<(String, f64)>,
}

impl Estimate {
    fn add(&mut self, field: String, particles: f64, recorded: f64, poses: f64) {
        self.particles += particles;
        self.recorded_particles += recorded;
        self.poses += poses;
        if self.largest.as_ref().is_none_or(|(_, n)| particles > *n) {
            self.largest = Some((field, particles));
        }
    }
}

/// Refuses a scene whose estimated memory or work passes `limits`, naming
/// the estimate, the limit and the flag that raises it. Numbers the
/// compiler would refuse anyway (a negative duration) are left to it.
pub(super) fn check(spec: &SceneSpec, ctx: &Ctx<'_>, limits: &Limits) -> Result<(), SceneError> {
    let seconds = limits.seconds.unwrap_or(spec.duration);
    let rate = spec.frame_rate;
    if !(seconds > 0.0 && seconds.is_finite() && rate > 0.0 && rate.is_finite()) {
        return Ok(());
    }
    let frame_dt = 1.0 / rate;
    let e = estimate(spec, ctx, frame_dt);
    // Past the particle count a scene may hold, the builder refuses it
    // before building it, naming the object's own count (segments, cells,
    // copies): a sharper message than a cost.
    if e.particles > MAX_PARTICLES as f64 {
        return Ok(());
    }
    let field = e
        .largest
        .as_ref()
        .map_or_else(|| "(document)".to_string(), |(f, _)| f.clone());
    // As `Scene::recorded_bytes` counts them once built.
    let frames = (seconds * rate).round() + 1.0;
    let bytes = frames * (e.recorded_particles * 99.0 + e.poses * 264.0);
    if bytes > limits.max_memory {
        return Err(ctx.err(
            field,
            format!(
                "the scene would record about {bytes:.1e} bytes ({} particles and {} poses at \
                 {} frames: {} s at {} frames per second), more than the limit of {:.1e} bytes \
                 (estimated from the file, before anything was built); use fewer copies, a \
                 shorter duration (or {}) or a lower frame_rate, or raise the limit with `{}`",
                count(e.recorded_particles),
                count(e.poses),
                count(frames),
                seconds,
                rate,
                limits.max_memory,
                Setting::Duration,
                Setting::MaxMemory.set(format_args!("{:.1e}", bytes * 1.01)),
            ),
        ));
    }
    // At least one step per frame (the auto step never exceeds the frame),
    // and at least as many as the step of the stiffest leaf asks.
    let dt = match spec.dt {
        DtSpec::Seconds(h) if h > 0.0 => h.min(frame_dt),
        _ => e.leaf_dt.unwrap_or(frame_dt).min(frame_dt),
    };
    let steps = (seconds / dt).ceil();
    let work = e.particles * steps;
    if work > limits.max_work {
        // A leaf has some 4 elements per particle (the rate's unit).
        let core = approximate_duration(work * 4.0 / REFERENCE_RATE);
        return Err(ctx.err(
            field,
            format!(
                "the scene needs at least {work:.1e} particle-steps ({} particles × at least {} \
                 steps in {} s), {core} of one core or more, past the limit of {:.1e} \
                 particle-steps (estimated from the file, before anything was built); use \
                 fewer copies or a shorter duration (or {}), or raise the limit with `{}`",
                count(e.particles),
                count(steps),
                seconds,
                limits.max_work,
                Setting::Duration,
                Setting::MaxWork.set(format_args!("{:.1e}", work * 1.01)),
            ),
        ));
    }
    Ok(())
}

/// A leaf file's particles, whether it is one rigid body, and the largest
/// step it allows.
type LeafCost = (f64, bool, Option<f64>);

/// Counts every object's particles. A leaf file is read once however many
/// objects name it; one that cannot be read counts nothing here (the
/// compiler names it).
fn estimate(spec: &SceneSpec, ctx: &Ctx<'_>, frame_dt: f64) -> Estimate {
    let mut e = Estimate::default();
    let mut leaves: HashMap<&str, Option<LeafCost>> = HashMap::new();
    for (k, obj) in spec.leaves.iter().enumerate() {
        let leaf = *leaves.entry(obj.leaf.as_str()).or_insert_with(|| {
            let file = match obj.leaf.as_str() {
                "a" | "b" => LeafSpec::load(&obj.leaf),
                p => LeafSpec::read(&ctx.base.join(p)),
            }
            .ok()
            .map(|s| ctx.under_law(s))?;
            let model = file.model().ok()?;
            let dt = stability::estimate(&model).auto_step(spec.integrator, frame_dt);
            Some((model.len() as f64, file.rigid, dt))
        });
        let Some((n, rigid_file, dt)) = leaf else {
            continue;
        };
        let copies = obj.count as f64;
        let rigid = obj.rigid.unwrap_or(rigid_file);
        let recorded = if rigid { 0.0 } else { copies * n };
        e.add(format!("leaf[{k}].count"), copies * n, recorded, copies);
        if !rigid && let Some(dt) = dt {
            e.leaf_dt = Some(e.leaf_dt.map_or(dt, |d: f64| d.min(dt)));
        }
    }
    for (k, obj) in spec.rigid.iter().enumerate() {
        let n = match obj.shape {
            Shape::Box => 8.0,
            Shape::Cylinder => {
                obj.segments.unwrap_or(16) as f64 * obj.rings.unwrap_or(2) as f64 + 1.0
            }
        };
        e.add(format!("rigid[{k}]"), n, 0.0, 1.0);
    }
    for (k, obj) in spec.sheets.iter().enumerate() {
        let n = (obj.cells[0] as f64 + 1.0) * (obj.cells[1] as f64 + 1.0);
        e.add(format!("sheet[{k}].cells"), n, n, 0.0);
    }
    for (k, _) in spec.fixed.iter().enumerate() {
        e.add(format!("fixed[{k}]"), 1.0, 0.0, 0.0);
    }
    for (k, obj) in spec.ropes.iter().enumerate() {
        let added = (obj.segments as f64 - 1.0).max(0.0);
        e.add(format!("rope[{k}].segments"), added, added + 2.0, 0.0);
    }
    e
}

/// A count for a message: whole below a million, then scientific.
fn count(n: f64) -> String {
    if n < 1e6 {
        format!("{n:.0}")
    } else {
        format!("{n:.2e}")
    }
}
