//! Reading a scene file and compiling it into one [`Scene`]: parse errors
//! pointed at their key's line, the top-level settings checked, wind
//! primitives that can never act left out, the objects placed in file order,
//! one aerodynamic law for the whole scene, and the model built with its
//! errors naming the object that made the item.

use super::bounds::Limits;
use super::builder::Builder;
use super::compiled::{ObjectKind, Scene};
use super::error::{Ctx, SceneError, check_name};
use super::objects::{SplitMix, add_leaf, add_rigid, add_rope, add_sheet};
use super::shapes::Part;
use super::spec::{DtSpec, FixedPoint, SceneSpec};
use crate::physics::field::{
    Flow, LineSink, LineSource, LineVortex, PointSink, PointSource, Uniform, WindField,
};
use crate::physics::integrate::{RUNAWAY_DISTANCE, runaway_speed};
use crate::physics::model::{Model, ModelError};
use crate::physics::params::TimeStep;
use crate::physics::state::State;
use crate::util::bad_input::BadInput;
use nalgebra::{UnitQuaternion, Vector3};
use std::collections::HashMap;
use std::path::Path;

type V3 = Vector3<f64>;

impl Scene {
    /// Reads and compiles a scene file; leaf paths are relative to its
    /// directory.
    pub fn load(path: &Path) -> Result<Scene, SceneError> {
        Scene::load_within(path, &Limits::default())
    }

    /// [`Scene::load`] held to `limits`: a scene whose estimated memory or
    /// work passes them is refused from the parsed file, before any object
    /// is built (`sim/scene/bounds.rs`); the scene keeps them for its run.
    pub fn load_within(path: &Path, limits: &Limits) -> Result<Scene, SceneError> {
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path)
            .map_err(|e| BadInput::file(file.clone(), format!("cannot read: {e}")))?;
        let base = path.parent().map(Path::to_path_buf).unwrap_or_default();
        Scene::from_toml_within(&text, &file, &base, limits)
    }

    /// Parses and compiles scene text; `file` names it in errors and leaf
    /// paths are relative to `base`.
    pub fn from_toml(text: &str, file: &str, base: &Path) -> Result<Scene, SceneError> {
        Scene::from_toml_within(text, file, base, &Limits::default())
    }

    /// [`Scene::from_toml`] held to `limits` ([`Scene::load_within`]).
    pub fn from_toml_within(
        text: &str,
        file: &str,
        base: &Path,
        limits: &Limits,
    ) -> Result<Scene, SceneError> {
        let spec: SceneSpec =
            toml::from_str(text).map_err(|e| BadInput::toml_parse(file, text, &e))?;
        compile(
            &spec,
            &Ctx {
                text,
                file,
                base,
                law: limits.law,
            },
            limits,
        )
    }

    /// Compiles an already parsed scene (for programs that build or edit
    /// one); errors name the field but no line.
    pub fn from_spec(spec: &SceneSpec, file: &str, base: &Path) -> Result<Scene, SceneError> {
        compile(
            spec,
            &Ctx {
                text: "",
                file,
                base,
                law: None,
            },
            &Limits::default(),
        )
    }
}

/// Whether a wind primitive can never contribute (zero strength or all keys 0).
fn inert(p: &crate::physics::field::Primitive) -> Option<&'static str> {
    if p.keys().is_some_and(|k| k.max_abs() == 0.0) {
        return Some("all strength keys are 0");
    }
    let zero = match p.flow() {
        Flow::Uniform(Uniform { velocity }) => *velocity == V3::zeros(),
        Flow::PointSource(PointSource { flux, .. })
        | Flow::PointSink(PointSink { flux, .. })
        | Flow::LineSource(LineSource { flux, .. })
        | Flow::LineSink(LineSink { flux, .. }) => *flux == 0.0,
        Flow::LineVortex(LineVortex { circulation, .. }) => *circulation == 0.0,
    };
    zero.then_some("zero strength")
}

fn compile(spec: &SceneSpec, ctx: &Ctx<'_>, limits: &Limits) -> Result<Scene, SceneError> {
    check_settings(spec, ctx, limits)?;

    let mut b = Builder::default();
    let mut names: HashMap<String, String> = HashMap::new();
    let mut primitives = Vec::new();
    for (i, p) in spec.wind.primitives().iter().enumerate() {
        match inert(p) {
            Some(why) => b.pruned.push(format!("wind[{i}]: {why}")),
            None => primitives.push(p.clone()),
        }
    }
    let mut rng = SplitMix(spec.seed);

    for (k, obj) in spec.leaves.iter().enumerate() {
        add_leaf(ctx, &mut b, &mut names, &mut rng, k, obj)?;
    }
    for (k, obj) in spec.rigid.iter().enumerate() {
        add_rigid(ctx, &mut b, &mut names, k, obj)?;
    }
    for (k, obj) in spec.sheets.iter().enumerate() {
        add_sheet(ctx, &mut b, &mut names, k, obj)?;
    }
    for (k, obj) in spec.fixed.iter().enumerate() {
        add_fixed(ctx, &mut b, &mut names, k, obj)?;
    }
    for (k, obj) in spec.ropes.iter().enumerate() {
        add_rope(ctx, &mut b, &mut names, k, obj)?;
    }
    if b.parts.mass.is_empty() {
        return Err(ctx.err("(document)", "the scene has no objects"));
    }

    check_one_law(ctx, &b)?;
    b.parts.gravity = V3::from(spec.gravity);
    b.parts.wind = WindField::new(primitives);
    b.parts.ground = spec.ground;
    let velocity = std::mem::take(&mut b.velocity);
    let model = Model::new(std::mem::take(&mut b.parts)).map_err(|e: ModelError| {
        let owner = b
            .owner_of(&e.item)
            .unwrap_or_else(|| "(document)".to_string());
        ctx.err(owner, format!("{} (model item {})", e.reason, e.item))
    })?;
    let mut initial = State::at_rest(&model);
    initial.velocity = velocity;
    check_start(ctx, &b, &model, &initial)?;
    let dt = match spec.dt {
        DtSpec::Auto => TimeStep::Auto,
        DtSpec::Seconds(h) => TimeStep::Fixed(h),
    };
    if dt == TimeStep::Auto {
        check_auto_step(spec, ctx, &b, &model, dt)?;
    }
    Ok(Scene {
        name: spec.name.clone(),
        description: spec.description.clone(),
        source: ctx.file.to_string(),
        model,
        initial,
        objects: b.objects,
        integrator: spec.integrator,
        dt,
        duration: spec.duration,
        frame_rate: spec.frame_rate,
        pruned: b.pruned,
        max_work: limits.max_work,
        max_memory: limits.max_memory,
    })
}

/// The scene's own settings checked, and its work and memory bounded from
/// the file before anything is built ([`super::bounds`]).
fn check_settings(spec: &SceneSpec, ctx: &Ctx<'_>, limits: &Limits) -> Result<(), SceneError> {
    // The scene's name becomes a directory name.
    check_name(ctx, "name", &spec.name, &mut HashMap::new())?;
    ctx.positive("duration", spec.duration)?;
    ctx.positive("frame_rate", spec.frame_rate)?;
    crate::physics::run::check_frames(spec.duration, spec.frame_rate)
        .map_err(|e| ctx.err("frame_rate", e.to_string()))?;
    if let DtSpec::Seconds(h) = spec.dt {
        ctx.positive("dt", h)?;
        // The step as written (the run snaps it to divide the frame, which
        // at most doubles the count; far below the limit it changes nothing).
        crate::physics::run::check_steps(spec.duration, h, spec.integrator)
            .map_err(|e| ctx.err("dt", e.to_string()))?;
    }
    ctx.vector("gravity", &spec.gravity)?;
    if let Some(ground) = &spec.ground {
        ground
            .validate()
            .map_err(|e| ctx.err(e.item.clone(), e.reason.clone()))?;
    }
    spec.wind
        .validate()
        .map_err(|e| ctx.err(e.item.clone(), e.reason.clone()))?;
    super::bounds::check(spec, ctx, limits)?;
    Ok(())
}

/// A `[[fixed]]` point: one fixed particle of unit mass.
fn add_fixed(
    ctx: &Ctx<'_>,
    b: &mut Builder,
    names: &mut HashMap<String, String>,
    k: usize,
    obj: &FixedPoint,
) -> Result<(), SceneError> {
    let path = format!("fixed[{k}]");
    check_name(ctx, &format!("{path}.name"), &obj.name, names)?;
    ctx.vector(&format!("{path}.position"), &obj.position)?;
    let part = Part {
        mass: vec![1.0],
        position: vec![V3::zeros()],
        fixed: vec![true],
        ..Default::default()
    };
    let ids = b.add_part(
        &path,
        &part,
        &[],
        (0.0, 0.0),
        V3::zeros(),
        UnitQuaternion::identity(),
        V3::from(obj.position),
        V3::zeros(),
        V3::zeros(),
    );
    b.push_object(obj.name.clone(), ObjectKind::Fixed, ids, None, false, &path);
    Ok(())
}

/// Rigid bodies and sheets carry linear-law coefficients; under a law
/// that replaces them they would be silently ignored, so say so instead.
fn check_one_law(ctx: &Ctx<'_>, b: &Builder) -> Result<(), SceneError> {
    let Some(first) = &b.aero_from else {
        return Ok(());
    };
    if b.parts.aero.uses_triangle_alpha() {
        return Ok(());
    }
    if let Some(t) = b
        .parts
        .triangles
        .iter()
        .position(|t| t.alpha_n != 0.0 || t.alpha_t != 0.0)
    {
        return Err(ctx.err(
            b.triangle_owner[t].clone(),
            format!(
                "has linear-law coefficients αⁿ, αᵗ, but {first} uses the {} law; a scene has one aerodynamic law (set them to 0 or use linear-law leaves)",
                b.parts.aero.name()
            ),
        ));
    }
    Ok(())
}

/// No particle placed or launched past where the simulator counts it as
/// run away (it would be reported as diverging at step 0).
fn check_start(
    ctx: &Ctx<'_>,
    b: &Builder,
    model: &Model,
    initial: &State,
) -> Result<(), SceneError> {
    // Past these the simulator counts a particle as run away: one placed
    // or launched there would be reported as diverging at step 0.
    let speed_limit = runaway_speed(model);
    for (i, (x, v)) in initial.position.iter().zip(&initial.velocity).enumerate() {
        let (key, value, limit, unit, what) = if x.norm() > RUNAWAY_DISTANCE {
            (
                "position",
                x.norm(),
                RUNAWAY_DISTANCE,
                "m",
                "from the origin",
            )
        } else if v.norm() > speed_limit {
            let what = "fast (with what its angular velocity adds)";
            ("velocity", v.norm(), speed_limit, "m/s", what)
        } else {
            continue;
        };
        let owner = b
            .owner_of(&format!("particle[{i}]"))
            .unwrap_or_else(|| "(document)".to_string());
        return Err(ctx.err(
            format!("{owner}.{key}"),
            format!(
                "starts a particle {value:.3e} {unit} {what}, past the {limit:.3e} {unit} at which \
                 the simulator stops a run as run away"
            ),
        ));
    }
    Ok(())
}

/// `dt = auto` on a model too stiff or light for the integrator: the
/// error names the object of the stiffest spring (else `dt`).
fn check_auto_step(
    spec: &SceneSpec,
    ctx: &Ctx<'_>,
    b: &Builder,
    model: &Model,
    dt: TimeStep,
) -> Result<(), SceneError> {
    // dt = auto on a model too stiff or light for the integrator: the
    // error names the object of the stiffest spring (else `dt`).
    crate::physics::run::resolve_dt(model, spec.integrator, dt, 1.0 / spec.frame_rate)
        .and_then(|h| crate::physics::run::check_steps(spec.duration, h, spec.integrator))
        .map_err(|e| {
            let stiffest = crate::physics::stability::estimate(model)
                .stiffest_spring
                .and_then(|k| b.owner_of(&format!("spring[{k}]")))
                .unwrap_or_else(|| "dt".to_string());
            ctx.err(stiffest, format!("dt = auto: {e}"))
        })?;

    Ok(())
}
