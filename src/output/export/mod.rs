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

mod clip;
mod dress;
mod error;
pub mod frame;
pub mod glb;
pub mod pc2;
mod read;
pub mod render_mesh;
pub mod usd;
mod wind;

pub use clip::{Clip, ClipObject, DEFAULT_FPS, Motion, frame_count, resample_positions};
pub use error::ExportError;
pub use frame::{Body, Framed};
pub use read::{from_glb, from_glb_bytes, from_scene_dir};
pub use render_mesh::RenderMesh;
pub use wind::WindGlyph;

use crate::motion::trajectory::Trajectory;
use crate::physics::model::Model;
use crate::sim::drop::{DropParams, drop_leaf};
use crate::sim::scene::{ObjectKind, Scene, SceneRun};
use nalgebra::Vector3;
use std::fmt;
use std::str::FromStr;

type V3 = Vector3<f64>;

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
