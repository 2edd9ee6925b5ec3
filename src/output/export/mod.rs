//! Export of recorded motion for other tools: binary glTF ([`glb`]) and PC2
//! point caches with rest-pose OBJ meshes ([`pc2`]), plus the common,
//! format-free form both (and the HTML previewer, [`crate::output::preview`]) start
//! from: a [`Clip`].
//!
//! A clip is a set of objects sampled on one uniform time grid at the output
//! frame rate ([`DEFAULT_FPS`] unless asked otherwise). Recorded frames
//! (240 Hz for drops, the scene's rate for scenes) are resampled onto it by
//! linear interpolation of positions and spherical interpolation of
//! rotations, so a glTF player's LINEAR interpolation between the exported
//! keys stays close to the simulated motion.
//!
//! Objects that move rigidly (rigid bodies, rigid leaves) keep their shape in
//! a body frame and carry a pose per frame; deforming objects (mass-spring
//! leaves, sheets, ropes) carry every vertex's position per frame.

mod dress;
mod error;
pub mod frame;
pub mod glb;
pub mod pc2;
mod read;
pub mod render_mesh;
pub mod usd;

pub use error::ExportError;
pub use frame::{Body, Framed};
pub use read::{from_glb, from_glb_bytes, from_scene_dir};
pub use render_mesh::RenderMesh;

use crate::motion::trajectory::Trajectory;
use crate::physics::field::{
    Flow, LineSink, LineSource, LineVortex, PointSink, PointSource, Region, Uniform,
};
use crate::physics::model::Model;
use crate::sim::drop::{DropParams, drop_leaf};
use crate::sim::scene::{ObjectKind, Scene, SceneRun};
use nalgebra::{UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};
use std::fmt;
use std::str::FromStr;

type V3 = Vector3<f64>;

/// Output frames per second unless asked otherwise: what animation tools
/// and the previewer play comfortably, and 8× fewer keys than a drop records.
pub const DEFAULT_FPS: f64 = 30.0;

/// An export file format.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// Binary glTF 2.0 (`.glb`): meshes with normals and UVs, node TRS
    /// animation for the rigid part of every object's motion, a fixed set of
    /// morph targets for the deformation of deforming ones.
    Glb,
    /// PC2 point cache (`.pc2`) with the rest-pose mesh (`.obj`), per object.
    Pc2,
    /// USD (`.usda`, text): an Xform per object with the rigid part of its
    /// motion time-sampled, and a Mesh with its points, normals and UVs.
    Usd,
}

/// A name that is no export format's.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum UnknownFormat {
    /// Not a format at all.
    #[error("unknown export format '{0}' (expected glb, pc2, usd or usda)")]
    Unknown(String),
    /// Binary USD, which is made from the text by Pixar's library.
    #[error("{}", usd::USDC_HINT)]
    Usdc,
}

impl FromStr for Format {
    type Err = UnknownFormat;
    fn from_str(s: &str) -> Result<Format, UnknownFormat> {
        match s {
            "glb" => Ok(Format::Glb),
            "pc2" => Ok(Format::Pc2),
            "usd" | "usda" => Ok(Format::Usd),
            "usdc" => Err(UnknownFormat::Usdc),
            _ => Err(UnknownFormat::Unknown(s.to_string())),
        }
    }
}

impl fmt::Display for Format {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Format::Glb => "glb",
            Format::Pc2 => "pc2",
            Format::Usd => "usd",
        })
    }
}

/// How an object moves.
#[derive(Clone, Debug, PartialEq)]
pub enum Motion {
    /// As a rigid body: `local` vertices in the body frame (centre of mass at
    /// the origin), placed at frame k by `translation[k] + rotation[k] · local`.
    Rigid {
        /// Vertices in the body frame, m.
        local: Vec<V3>,
        /// Centre of mass per frame, m.
        translation: Vec<V3>,
        /// Body-to-world rotation per frame.
        rotation: Vec<UnitQuaternion<f64>>,
    },
    /// Deforming: every vertex's world position per frame, m.
    Deforming {
        /// `frames[k][i]`: vertex i at frame k.
        frames: Vec<Vec<V3>>,
    },
}

/// One exported object.
#[derive(Clone, Debug, PartialEq)]
pub struct ClipObject {
    /// Unique name (the scene object's, or `leaf-<id>`).
    pub name: String,
    /// What it is: `leaf`, `rigid`, `sheet`, `rope`.
    pub kind: String,
    /// A label to show next to it (the motion class of a bred leaf), may be empty.
    pub label: String,
    /// The sub-regime of its motion class, may be empty.
    pub regime: String,
    /// Numbers that describe it (a bred leaf's features: descent speed,
    /// drift, turns, …), SI units, written as custom attributes where the
    /// format has them.
    pub features: Vec<(String, f64)>,
    /// Surface triangles (vertex indices).
    pub triangles: Vec<[u32; 3]>,
    /// Line segments (vertex indices), for ropes.
    pub segments: Vec<[u32; 2]>,
    /// Its rest shape in its own body frame, when known (leaves, rigid
    /// objects); else the first frame stands for it ([`frame`]).
    pub body: Option<Body>,
    /// A finer textured mesh bound to this one, exported in its place.
    pub render: Option<RenderMesh>,
    /// The motion.
    pub motion: Motion,
}

impl ClipObject {
    /// Number of vertices.
    pub fn vertex_count(&self) -> usize {
        match &self.motion {
            Motion::Rigid { local, .. } => local.len(),
            Motion::Deforming { frames } => frames.first().map_or(0, Vec::len),
        }
    }

    /// World positions of every vertex at frame `k`.
    pub fn positions(&self, k: usize) -> Vec<V3> {
        match &self.motion {
            Motion::Rigid {
                local,
                translation,
                rotation,
            } => local
                .iter()
                .map(|x| translation[k] + rotation[k] * x)
                .collect(),
            Motion::Deforming { frames } => frames[k].clone(),
        }
    }

    /// World positions of the vertices a client is shown at frame `k`: the
    /// render mesh placed on the simulated vertices, or those.
    pub fn shown_positions(&self, k: usize) -> Vec<V3> {
        let p = self.positions(k);
        match &self.render {
            Some(r) => r.place(&p, &self.triangles),
            None => p,
        }
    }

    /// Mean of the vertices at frame `k` (the previewer's camera target).
    pub fn centre(&self, k: usize) -> V3 {
        let p = self.positions(k);
        p.iter().sum::<V3>() / p.len().max(1) as f64
    }

    /// Moves the whole motion by `offset` (to lay objects side by side).
    pub fn translate(&mut self, offset: V3) {
        match &mut self.motion {
            Motion::Rigid { translation, .. } => translation.iter_mut().for_each(|t| *t += offset),
            Motion::Deforming { frames } => frames.iter_mut().flatten().for_each(|x| *x += offset),
        }
    }
}

/// A wind primitive reduced to what a glyph needs.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct WindGlyph {
    /// `uniform`, `point_source`, `point_sink`, `line_source`, `line_sink`, `line_vortex`.
    pub kind: String,
    /// Where to draw it: the primitive's point, or the centre of a uniform
    /// flow's bounds (the origin when unbounded), m.
    pub point: [f64; 3],
    /// Unit flow direction (uniform) or axis (line primitives); zero for point primitives.
    pub direction: [f64; 3],
    /// Speed (uniform, m/s), flux (sources, sinks) or circulation (vortex).
    pub strength: f64,
}

impl WindGlyph {
    /// The glyph of one primitive of a wind field.
    pub fn of(p: &crate::physics::field::Primitive) -> WindGlyph {
        let unit = |v: &V3| -> [f64; 3] {
            let n = v.norm();
            if n > 0.0 { (v / n).into() } else { [0.0; 3] }
        };
        let (kind, point, direction, strength) = match p.flow() {
            Flow::Uniform(Uniform { velocity }) => {
                let centre = match p.bounds().map(|b| &b.region) {
                    Some(Region::Sphere { center, .. }) => *center,
                    Some(Region::Box { min, max }) => (min + max) / 2.0,
                    Some(Region::Cylinder { point, .. }) => *point,
                    None => V3::zeros(),
                };
                ("uniform", centre, unit(velocity), velocity.norm())
            }
            Flow::PointSource(PointSource { point, flux, .. }) => {
                ("point_source", *point, [0.0; 3], *flux)
            }
            Flow::PointSink(PointSink { point, flux, .. }) => {
                ("point_sink", *point, [0.0; 3], *flux)
            }
            Flow::LineSource(LineSource {
                point, axis, flux, ..
            }) => ("line_source", *point, unit(axis), *flux),
            Flow::LineSink(LineSink {
                point, axis, flux, ..
            }) => ("line_sink", *point, unit(axis), *flux),
            Flow::LineVortex(LineVortex {
                point,
                axis,
                circulation,
                ..
            }) => ("line_vortex", *point, unit(axis), *circulation),
        };
        WindGlyph {
            kind: kind.to_string(),
            point: point.into(),
            direction,
            strength,
        }
    }
}

/// Objects sampled on one uniform time grid, frame k at t = k / `fps`.
#[derive(Clone, Debug, PartialEq)]
pub struct Clip {
    /// Name (scene name, run directory name, file stem).
    pub name: String,
    /// Frames per second.
    pub fps: f64,
    /// Number of frames (t = 0 included).
    pub frames: usize,
    /// The objects.
    pub objects: Vec<ClipObject>,
    /// Height of the ground plane (z up), if there is one, m.
    pub ground: Option<f64>,
    /// The wind primitives as glyphs.
    pub wind: Vec<WindGlyph>,
}

impl Clip {
    /// Frame times, s.
    pub fn times(&self) -> Vec<f64> {
        (0..self.frames).map(|k| k as f64 / self.fps).collect()
    }

    /// Duration, s.
    pub fn duration(&self) -> f64 {
        (self.frames.saturating_sub(1)) as f64 / self.fps
    }

    /// Checks the invariants every writer relies on: at least one object and
    /// one frame, every object with `frames` frames of its vertex count,
    /// indices in range, finite numbers.
    pub fn validate(&self) -> Result<(), ExportError> {
        let bad = |m: String| Err(ExportError::Data(format!("{}: {m}", self.name)));
        if !(self.fps > 0.0 && self.fps.is_finite()) {
            return bad(format!("frame rate {} is not positive", self.fps));
        }
        if self.frames == 0 {
            return bad("no frames to export".into());
        }
        if self.objects.is_empty() {
            return bad("no objects to export".into());
        }
        let mut names = std::collections::BTreeSet::new();
        if let Some(o) = self.objects.iter().find(|o| !names.insert(o.name.as_str())) {
            return bad(format!(
                "two objects are named {}; names must be unique",
                o.name
            ));
        }
        for o in &self.objects {
            let n = o.vertex_count();
            let frames_ok = match &o.motion {
                Motion::Rigid {
                    translation,
                    rotation,
                    local,
                } => {
                    translation.len() == self.frames
                        && rotation.len() == self.frames
                        && local.iter().chain(translation).all(finite)
                }
                Motion::Deforming { frames } => {
                    frames.len() == self.frames
                        && frames.iter().all(|f| f.len() == n && f.iter().all(finite))
                }
            };
            if !frames_ok {
                return bad(format!(
                    "object {}: frames missing, of unequal size or not finite",
                    o.name
                ));
            }
            if n == 0 {
                return bad(format!("object {} has no vertices", o.name));
            }
            let in_range = o
                .triangles
                .iter()
                .flatten()
                .chain(o.segments.iter().flatten())
                .all(|&i| (i as usize) < n);
            if !in_range {
                return bad(format!("object {}: a vertex index is out of range", o.name));
            }
            if let Some(b) = &o.body
                && (b.rest.len() != n || b.mass.len() != n || !b.mass.iter().all(|m| *m > 0.0))
            {
                return bad(format!(
                    "object {}: its rest shape has {} vertices and {} positive masses, expected {n}",
                    o.name,
                    b.rest.len(),
                    b.mass.iter().filter(|m| **m > 0.0).count()
                ));
            }
            if let Some(r) = &o.render {
                let m = r.vertex_count();
                let ok = r.uvs.len() == m
                    && r.bindings
                        .iter()
                        .all(|b| (b.triangle as usize) < o.triangles.len())
                    && r.triangles.iter().flatten().all(|&i| (i as usize) < m);
                if !ok {
                    return bad(format!(
                        "object {}: the render mesh {} does not fit it (its bindings, UVs or triangles are out of range)",
                        o.name, r.source
                    ));
                }
            }
        }
        Ok(())
    }
}

fn finite(v: &V3) -> bool {
    v.iter().all(|x| x.is_finite())
}

/// The uniform output grid over a recording from `t0` to `t1`:
/// t0 + k / fps for every k with t0 + k / fps ≤ t1 (to 1e-9 s).
pub fn frame_count(t0: f64, t1: f64, fps: f64) -> usize {
    ((t1 - t0) * fps + 1e-9).floor().max(0.0) as usize + 1
}

/// Resamples per-frame vertex positions recorded at `time` onto the grid
/// t0 + k / fps (k < `count`) by linear interpolation between the two
/// recorded frames around each output time; exact for motion linear in time.
pub fn resample_positions(
    time: &[f64],
    frames: &[Vec<V3>],
    fps: f64,
    count: usize,
) -> Vec<Vec<V3>> {
    let n = time.len().min(frames.len());
    if n == 0 {
        return Vec::new();
    }
    let t0 = time[0];
    let mut j = 0usize;
    (0..count)
        .map(|k| {
            let t = t0 + k as f64 / fps;
            while j + 2 < n && time[j + 1] <= t {
                j += 1;
            }
            if n == 1 {
                return frames[0].clone();
            }
            let (ta, tb) = (time[j], time[j + 1]);
            let s = ((t - ta) / (tb - ta)).clamp(0.0, 1.0);
            if s == 0.0 {
                return frames[j].clone();
            }
            frames[j]
                .iter()
                .zip(&frames[j + 1])
                .map(|(a, b)| a.lerp(b, s))
                .collect()
        })
        .collect()
}

fn to_u32(t: &[usize; 3]) -> [u32; 3] {
    t.map(|i| i as u32)
}

/// The colour-free kind name of a scene object.
fn kind_name(kind: ObjectKind) -> &'static str {
    kind.name()
}

/// A clip of a scene run: every object but fixed points, on the grid at
/// `fps`. Rigid bodies (rigid objects, rigid leaves) move by their pose;
/// everything else by its particles.
pub fn from_scene_run(scene: &Scene, run: &SceneRun, fps: f64) -> Result<Clip, ExportError> {
    let poses: Vec<Option<&Trajectory>> = run.poses.iter().map(Option::as_ref).collect();
    let particles: Vec<Option<&[Vec<V3>]>> = run.particles.iter().map(|p| p.as_deref()).collect();
    build_scene_clip(scene, &run.time, &poses, &particles, fps)
}

/// Shared by [`from_scene_run`] and the scene-directory reader.
pub(crate) fn build_scene_clip(
    scene: &Scene,
    time: &[f64],
    poses: &[Option<&Trajectory>],
    particles: &[Option<&[Vec<V3>]>],
    fps: f64,
) -> Result<Clip, ExportError> {
    if !(fps > 0.0 && fps.is_finite()) {
        return Err(ExportError::Data(format!(
            "the frame rate must be positive, got {fps}"
        )));
    }
    let (Some(&t0), Some(&t1)) = (time.first(), time.last()) else {
        return Err(ExportError::Data(format!(
            "scene {}: no frames recorded",
            scene.name
        )));
    };
    let count = frame_count(t0, t1, fps);
    let mut objects = Vec::new();
    for (o, obj) in scene.objects.iter().enumerate() {
        if obj.kind == ObjectKind::Fixed {
            continue;
        }
        let triangles: Vec<[u32; 3]> = obj.surface.iter().map(to_u32).collect();
        let segments: Vec<[u32; 2]> = if obj.kind == ObjectKind::Rope {
            (0..obj.particles.len().saturating_sub(1) as u32)
                .map(|i| [i, i + 1])
                .collect()
        } else {
            Vec::new()
        };
        // A leaf's or rigid object's own frame: its model alone, turned as
        // released (the frame its pose trajectory is given in).
        let body = obj.pose.as_ref().map(|frame| {
            let m = &frame.model;
            let com = m.centre_of_mass(&m.rest_position);
            Body {
                rest: m.rest_position.iter().map(|x| x - com).collect(),
                mass: m.mass.clone(),
            }
        });
        let motion = match (obj.rigid_body, &obj.pose, poses.get(o).copied().flatten()) {
            (Some(_), Some(frame), Some(traj)) => {
                let m = &frame.model;
                let com = m.centre_of_mass(&m.rest_position);
                let r = traj.resampled(fps);
                let take = count.min(r.len());
                Motion::Rigid {
                    local: m.rest_position.iter().map(|x| x - com).collect(),
                    translation: pad(r.position[..take].to_vec(), count),
                    rotation: pad(r.orientation[..take].to_vec(), count),
                }
            }
            _ => match particles.get(o).copied().flatten() {
                Some(frames) => Motion::Deforming {
                    frames: resample_positions(time, frames, fps, count),
                },
                None => {
                    return Err(ExportError::Data(format!(
                        "scene {}: object {} has no recorded motion",
                        scene.name, obj.name
                    )));
                }
            },
        };
        objects.push(ClipObject {
            name: obj.name.clone(),
            kind: kind_name(obj.kind).to_string(),
            label: String::new(),
            regime: String::new(),
            features: Vec::new(),
            triangles,
            segments,
            body,
            render: None,
            motion,
        });
    }
    let clip = Clip {
        name: scene.name.clone(),
        fps,
        frames: count,
        objects,
        ground: scene.model.ground.map(|g| g.height),
        wind: scene
            .model
            .wind
            .primitives()
            .iter()
            .map(WindGlyph::of)
            .collect(),
    };
    clip.validate()?;
    Ok(clip)
}

/// Pads a per-frame list to `count` by repeating its last entry (a pose
/// recording may end a round-off short of the last grid time).
fn pad<T: Clone>(mut v: Vec<T>, count: usize) -> Vec<T> {
    if let Some(last) = v.last().cloned() {
        v.resize(count, last);
    }
    v
}

/// Drops `model` as breeding and `drop` do ([`DropParams`] defaults, for
/// `seconds`) and returns its fall as a one-object clip on the grid at
/// `fps`: the leaf's triangles, every particle per frame (a mass-spring leaf
/// deforms, so it is exported as a deforming object).
pub fn drop_clip(
    name: &str,
    label: &str,
    model: &Model,
    seconds: f64,
    fps: f64,
) -> Result<ClipObject, ExportError> {
    drop_clip_released(
        name,
        label,
        model,
        seconds,
        fps,
        DropParams::default().tilt_deg,
    )
}

/// [`drop_clip`] released at `tilt_deg` (about the leaf's x and y axes, as
/// `drop --tilt`): a bred leaf's fall is the one of the release its score
/// is that of ([`crate::breed::Evaluation::release_deg`]).
pub fn drop_clip_released(
    name: &str,
    label: &str,
    model: &Model,
    seconds: f64,
    fps: f64,
    tilt_deg: [f64; 2],
) -> Result<ClipObject, ExportError> {
    let params = DropParams {
        seconds,
        record_particles: true,
        tilt_deg,
        ..DropParams::default()
    };
    let result = drop_leaf(model, &params)
        .map_err(|e| ExportError::Data(format!("{name}: the drop failed: {e}")))?;
    let frames = result.particles.unwrap_or_default();
    let time = &result.trajectory.time;
    let (Some(&t0), Some(&t1)) = (time.first(), time.last()) else {
        return Err(ExportError::Data(format!("{name}: no frames recorded")));
    };
    let count = frame_count(t0, t1, fps);
    let com = model.centre_of_mass(&model.rest_position);
    Ok(ClipObject {
        name: name.to_string(),
        kind: "leaf".to_string(),
        label: label.to_string(),
        regime: String::new(),
        features: Vec::new(),
        triangles: model.triangles.iter().map(|t| to_u32(&t.corners)).collect(),
        segments: Vec::new(),
        body: Some(Body {
            rest: model.rest_position.iter().map(|x| x - com).collect(),
            mass: model.mass.clone(),
        }),
        render: None,
        motion: Motion::Deforming {
            frames: resample_positions(time, &frames, fps, count),
        },
    })
}

/// Lays `objects` (falls from the origin) side by side along x, `spacing`
/// metres apart and centred on x = 0, as one clip: the previewer's grid of
/// bred leaves. All objects must have the same number of frames.
pub fn side_by_side(
    name: &str,
    mut objects: Vec<ClipObject>,
    fps: f64,
    spacing: f64,
) -> Result<Clip, ExportError> {
    let n = objects.len();
    for (k, o) in objects.iter_mut().enumerate() {
        let x = (k as f64 - (n as f64 - 1.0) / 2.0) * spacing;
        o.translate(V3::new(x, 0.0, 0.0));
    }
    let frames = match objects.first().map(|o| &o.motion) {
        Some(Motion::Deforming { frames }) => frames.len(),
        Some(Motion::Rigid { translation, .. }) => translation.len(),
        None => 0,
    };
    let clip = Clip {
        name: name.to_string(),
        fps,
        frames,
        objects,
        ground: None,
        wind: Vec::new(),
    };
    clip.validate()?;
    Ok(clip)
}

/// Re-drops chosen individuals of a breeding run exactly as breeding
/// dropped them (the run's duration, the release attitude whose score the
/// individual's is, [`crate::breed::Evaluation::release_deg`], so the same
/// fall that earned the recorded class) and returns each fall as an object
/// named `leaf-<id>` and labelled with its recorded class, in parallel.
/// The run keeps no trajectories, and a leaf file alone has no motion: this
/// re-simulation is where the motion comes from.
pub fn drop_individuals(
    run: &crate::breed::Run,
    chosen: &[&crate::breed::Individual],
    fps: f64,
) -> Result<Vec<ClipObject>, ExportError> {
    use rayon::prelude::*;
    let seconds = run.settings().seconds;
    chosen
        .par_iter()
        .map(|ind| {
            let name = format!("leaf-{}", ind.id);
            let model = ind
                .genome
                .model(&run.proto)
                .map_err(|e| ExportError::Data(format!("{name}: invalid leaf: {e}")))?;
            let mut o = drop_clip_released(
                &name,
                ind.eval.class_name(),
                &model,
                seconds,
                fps,
                ind.eval.release_deg,
            )?;
            o.features = vec![("score".to_string(), ind.eval.score)];
            if let Some(f) = ind.eval.fall() {
                o.regime = f.regime.to_string();
                o.features.extend(
                    [
                        ("margin", f.margin),
                        ("descent_m_s", f.descent_m_s),
                        ("drift_ratio", f.drift_ratio),
                        ("net_turns", f.net_turns),
                        ("yaw_turns", f.yaw_turns),
                        ("spin_rad_s", f.spin_rad_s),
                        ("reversals", f.reversals as f64),
                        ("flips", f.flips as f64),
                        ("tilt_deg", f.tilt_deg),
                    ]
                    .map(|(k, v)| (k.to_string(), v)),
                );
            }
            Ok(o)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resampling_reproduces_linear_motion_exactly() {
        // x = (1, -2, 0.5) t + (0, 0, 3), recorded at 240 Hz for 1 s.
        let time: Vec<f64> = (0..=240).map(|k| k as f64 / 240.0).collect();
        let at = |t: f64| V3::new(t, -2.0 * t, 0.5 * t + 3.0);
        let frames: Vec<Vec<V3>> = time.iter().map(|&t| vec![at(t), at(t) * 2.0]).collect();
        let n = frame_count(0.0, 1.0, 30.0);
        assert_eq!(n, 31);
        let out = resample_positions(&time, &frames, 30.0, n);
        assert_eq!(out.len(), 31);
        for (k, f) in out.iter().enumerate() {
            let t = k as f64 / 30.0;
            assert!((f[0] - at(t)).norm() < 1e-14, "frame {k}: {:?}", f[0]);
            assert!((f[1] - at(t) * 2.0).norm() < 1e-14);
        }
        // Output times between recorded ones (a 7 Hz grid) interpolate too.
        let out = resample_positions(&time, &frames, 7.0, frame_count(0.0, 1.0, 7.0));
        assert_eq!(out.len(), 8);
        for (k, f) in out.iter().enumerate() {
            assert!((f[0] - at(k as f64 / 7.0)).norm() < 1e-14);
        }
    }

    #[test]
    fn format_parses_and_names_unknown_ones() {
        assert_eq!("glb".parse::<Format>(), Ok(Format::Glb));
        assert_eq!("pc2".parse::<Format>(), Ok(Format::Pc2));
        let e = "fbx".parse::<Format>().unwrap_err().to_string();
        assert!(e.contains("fbx") && e.contains("glb, pc2, usd"), "{e}");
        assert_eq!("usd".parse::<Format>(), Ok(Format::Usd));
        assert_eq!("usda".parse::<Format>(), Ok(Format::Usd));
        let e = "usdc".parse::<Format>().unwrap_err().to_string();
        assert!(e.contains("usd-core") && e.contains("Export"), "{e}");
    }

    #[test]
    fn side_by_side_spaces_objects_about_the_origin() {
        let model = crate::leaf::LeafSpec::load("a").unwrap().model().unwrap();
        let a = drop_clip("a", "", &model, 0.5, 30.0).unwrap();
        let mut b = a.clone();
        let e = side_by_side("pair", vec![a.clone(), b.clone()], 30.0, 0.2).unwrap_err();
        assert!(e.to_string().contains("two objects are named a"), "{e}");
        b.name = "b".into();
        let clip = side_by_side("pair", vec![a.clone(), b], 30.0, 0.2).unwrap();
        assert_eq!(clip.frames, 16);
        let d = clip.objects[1].centre(0) - clip.objects[0].centre(0);
        assert!((d - V3::new(0.2, 0.0, 0.0)).norm() < 1e-12);
        assert!((clip.objects[0].centre(5).x - (a.centre(5).x - 0.1)).abs() < 1e-12);
    }
}
