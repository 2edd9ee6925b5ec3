//! A scene's run as a clip: every object but fixed points, rigid bodies by
//! their pose and everything else by its particles, from a run in memory or
//! from the frames the scene-directory reader gives back.

use crate::formats::ExportError;
use crate::formats::clip::WindGlyph;
use crate::formats::clip::{
    Body, Clip, ClipObject, Motion, frame_count, resample_positions, rigid_motion, to_u32,
};
use crate::motion::trajectory::Trajectory;
use crate::sim::scene::{ObjectKind, Scene, SceneRun};
use nalgebra::Vector3;

type V3 = Vector3<f64>;

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
            (Some(_), Some(frame), Some(traj)) => rigid_motion(&frame.model, traj, fps, count),
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
            first_frame: 0,
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
        aero_law: scene.model.aero.name().to_string(),
        warnings: Vec::new(),
    };
    clip.validate()?;
    Ok(clip)
}
