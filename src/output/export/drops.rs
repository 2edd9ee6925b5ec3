//! Leaf falls as clips: a leaf, or a breeding run's chosen individuals,
//! dropped again as breeding dropped them (neither a run nor a leaf file
//! keeps a motion), and falls laid side by side as one clip.

use crate::formats::ExportError;
use crate::formats::clip::{
    Body, Clip, ClipObject, Motion, frame_count, resample_positions, rigid_motion, to_u32,
};
use crate::physics::model::Model;
use crate::sim::drop::{DropParams, drop_leaf};
use nalgebra::Vector3;

type V3 = Vector3<f64>;

/// Drops `model` as breeding and `drop` do ([`DropParams`] defaults, for
/// `seconds`) and returns its fall as a one-object clip on the grid at
/// `fps`: the leaf's triangles and every particle per frame (a mass-spring
/// leaf deforms, so it is exported as a deforming object), or for a leaf
/// that is one rigid body, its pose per frame ([`Motion::Rigid`]).
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
    // A leaf that is one rigid body (every plate of `leafmagic plate`)
    // moves as one: its pose is its exact motion, and a client gets one
    // transform per frame instead of every vertex.
    let rigid = model.rigid.len() == 1 && model.rigid[0].members.len() == model.len();
    let params = DropParams {
        seconds,
        record_particles: !rigid,
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
        first_frame: 0,
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
        motion: if rigid {
            rigid_motion(model, &result.trajectory, fps, count)
        } else {
            Motion::Deforming {
                frames: resample_positions(time, &frames, fps, count),
            }
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
    let frames = objects.first().map_or(0, ClipObject::frame_count);
    let clip = Clip::bare(name, fps, frames, objects);
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
