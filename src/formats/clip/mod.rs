//! The format-free form every writer, reader and the previewer share: a
//! [`Clip`], objects on one uniform time grid, each with its shape and
//! motion, and the resampling of recorded frames onto that grid; with what
//! the writers dress it in: each object's body frame ([`frame`]), normals
//! and texture coordinates ([`dress`]), colour and material ([`look`]), the
//! artist's render meshes bound to it ([`render_mesh`]) and the wind's
//! glyphs ([`WindGlyph`]).
//!
//! A clip is a set of objects sampled on one uniform time grid at the
//! output frame rate ([`DEFAULT_FPS`] unless asked otherwise). Recorded
//! frames (240 Hz for drops, the scene's rate for scenes) are resampled onto
//! it by linear interpolation of positions and spherical interpolation of
//! rotations, so a player's linear interpolation between the exported keys
//! stays close to the simulated motion. Objects that move rigidly (rigid
//! bodies, rigid leaves) keep their shape in a body frame and carry a pose
//! per frame; deforming objects (mass-spring leaves, sheets, ropes) carry
//! every vertex's position per frame.
//!
//! The parts that read the clip ([`frame`], [`look`]) import it from here;
//! this module uses only the parts that do not ([`render_mesh`], `wind`),
//! so no import goes round in a circle.

pub mod dress;
pub mod frame;
pub mod look;
pub mod render_mesh;
mod wind;

use crate::formats::error::ExportError;
use crate::motion::trajectory::Trajectory;
use crate::physics::model::Model;
use nalgebra::{UnitQuaternion, Vector3};
use render_mesh::RenderMesh;
pub use wind::WindGlyph;

type V3 = Vector3<f64>;

/// Output frames per second unless asked otherwise: what animation tools
/// and the previewer play comfortably, and 8× fewer keys than a drop records.
pub const DEFAULT_FPS: f64 = 30.0;

/// The kind of a particle read from a point cloud (an Alembic `Points`
/// object): drawn as a marker its width across.
pub const POINT_KIND: &str = "point";

/// The kind of a recorded fall without orientation, drawn as a marker.
pub const MARKER_KIND: &str = "marker";

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

/// The rest shape of an object in its own body frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Body {
    /// Vertices in the body frame (for a leaf: z the plate normal, x the
    /// long axis), with the origin at their mass-weighted centre, m.
    pub rest: Vec<V3>,
    /// The weight of each vertex in the frame fit (its mass, kg).
    pub mass: Vec<f64>,
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
    /// The clip frame its motion starts at: 0, except for an object read
    /// from a file that appears after the clip's start (a particle born
    /// during it, a USD PointInstancer's leaf), whose motion then holds only
    /// the frames of its own life. Exports take objects that live the
    /// whole clip ([`Clip::validate`]).
    pub first_frame: usize,
}

impl ClipObject {
    /// A mesh read from an animation file: its vertices per frame, and
    /// nothing else known of it.
    pub fn read_mesh(
        name: String,
        triangles: Vec<[u32; 3]>,
        frames: Vec<Vec<Vector3<f64>>>,
    ) -> Self {
        ClipObject {
            name,
            kind: "mesh".to_string(),
            label: String::new(),
            regime: String::new(),
            features: Vec::new(),
            triangles,
            segments: Vec::new(),
            body: None,
            render: None,
            motion: Motion::Deforming { frames },
            first_frame: 0,
        }
    }

    /// A marker: three crossed lines of length `size` along the world
    /// axes, centred on `translation` per frame, claiming no attitude (a
    /// path from video, a particle of an Alembic point cloud). `kind` says
    /// which ([`POINT_KIND`] for a particle); [`crate::formats::fall::fall_of`]
    /// reads such an object's centre only.
    pub fn marker(name: String, kind: &str, size: f64, translation: Vec<V3>) -> Self {
        let h = 0.5 * size;
        let local = (0..3)
            .flat_map(|axis| {
                let mut e = V3::zeros();
                e[axis] = h;
                [-e, e]
            })
            .collect();
        let rotation = vec![UnitQuaternion::identity(); translation.len()];
        ClipObject {
            name,
            kind: kind.to_string(),
            label: String::new(),
            regime: String::new(),
            features: Vec::new(),
            triangles: Vec::new(),
            segments: vec![[0, 1], [2, 3], [4, 5]],
            body: None,
            render: None,
            motion: Motion::Rigid {
                local,
                translation,
                rotation,
            },
            first_frame: 0,
        }
    }

    /// Whether it is a marker ([`Self::marker`]): a position whose drawn
    /// lines say nothing of an attitude.
    pub fn is_marker(&self) -> bool {
        matches!(self.kind.as_str(), MARKER_KIND | POINT_KIND)
    }

    /// Number of frames its motion holds.
    pub fn frame_count(&self) -> usize {
        match &self.motion {
            Motion::Rigid { translation, .. } => translation.len(),
            Motion::Deforming { frames } => frames.len(),
        }
    }

    /// When it lives in a clip at `fps`, s: the times of its first and
    /// last frames.
    pub fn life_s(&self, fps: f64) -> (f64, f64) {
        let last = self.first_frame + self.frame_count().max(1) - 1;
        (self.first_frame as f64 / fps, last as f64 / fps)
    }

    /// Whether it lives the whole of a clip of `frames` frames.
    pub fn lives_whole(&self, frames: usize) -> bool {
        self.first_frame == 0 && self.frame_count() == frames
    }

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

    /// Scales every length of the object by `factor` (a read file's unit
    /// to metres: Alembic carries none, and Maya writes centimetres). Its
    /// motion and rest shape; a clip read from a file has no render mesh.
    pub fn scale(&mut self, factor: f64) {
        match &mut self.motion {
            Motion::Rigid {
                local, translation, ..
            } => local
                .iter_mut()
                .chain(translation.iter_mut())
                .for_each(|x| *x *= factor),
            Motion::Deforming { frames } => frames.iter_mut().flatten().for_each(|x| *x *= factor),
        }
        if let Some(body) = &mut self.body {
            body.rest.iter_mut().for_each(|x| *x *= factor);
        }
    }

    /// Moves the whole motion by `offset` (to lay objects side by side).
    pub fn translate(&mut self, offset: V3) {
        match &mut self.motion {
            Motion::Rigid { translation, .. } => translation.iter_mut().for_each(|t| *t += offset),
            Motion::Deforming { frames } => frames.iter_mut().flatten().for_each(|x| *x += offset),
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
    /// The aerodynamic law the falls were simulated under, as leaf files
    /// name it (`linear`, `unsteady`, `quadratic`); empty when not known (a
    /// file from elsewhere). Written into the files' metadata.
    pub aero_law: String,
    /// What the reader of a file left out or doubted without refusing the
    /// file, one sentence each, for the user to see (`warning: FILE: …`).
    pub warnings: Vec<String>,
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
        self.check(true)
    }

    /// A clip read from a file named `name`: its `objects` sampled at
    /// `frames` frames of `fps`, checked as [`Self::validate_read`] checks.
    pub fn read(
        name: &str,
        fps: f64,
        frames: usize,
        objects: Vec<ClipObject>,
    ) -> Result<Clip, String> {
        let clip = Clip::bare(name, fps, frames, objects);
        clip.validate_read().map_err(|e| e.to_string())?;
        Ok(clip)
    }

    /// `objects` at `frames` frames of `fps`, named `name`, without ground
    /// or wind, unchecked.
    pub(crate) fn bare(name: &str, fps: f64, frames: usize, objects: Vec<ClipObject>) -> Clip {
        Clip {
            name: name.to_string(),
            fps,
            frames,
            objects,
            ground: None,
            wind: Vec::new(),
            aero_law: String::new(),
            warnings: Vec::new(),
        }
    }

    /// The clip on the grid k / `fps` over the same span: each object at
    /// the grid times within its life (from its first frame's time to its
    /// last's, to 1e-9 s), linearly between its own frames (a rigid one's
    /// rotation by spherical interpolation), as the previewer and glTF's
    /// LINEAR play them. An object whose whole life falls between two grid
    /// times keeps one frame, its first, at the nearest.
    pub fn resampled(&self, fps: f64) -> Clip {
        let frames = frame_count(0.0, self.duration(), fps);
        let objects = self
            .objects
            .iter()
            .map(|o| {
                let own = o.frame_count();
                let (born, dies) = o.life_s(self.fps);
                let mut first = ((born * fps) - 1e-9).ceil().max(0.0) as usize;
                let last = ((dies * fps) + 1e-9).floor() as usize;
                let mut count = (last + 1)
                    .saturating_sub(first)
                    .min(frames - first.min(frames));
                // Where the object lies at grid time j / fps: frame index
                // and weight within its own frames.
                let mut at: Vec<(usize, f64)> = (first..first + count)
                    .map(|j| {
                        let f = ((j as f64 / fps - born) * self.fps).clamp(0.0, (own - 1) as f64);
                        let k = (f.floor() as usize).min(own.saturating_sub(2));
                        (k, if own > 1 { f - k as f64 } else { 0.0 })
                    })
                    .collect();
                if count == 0 {
                    first = ((born * fps).round() as usize).min(frames - 1);
                    count = 1;
                    at = vec![(0, 0.0)];
                }
                debug_assert_eq!(at.len(), count);
                let motion = match &o.motion {
                    Motion::Rigid {
                        local,
                        translation,
                        rotation,
                    } => Motion::Rigid {
                        local: local.clone(),
                        translation: at
                            .iter()
                            .map(|&(k, s)| {
                                translation[k].lerp(&translation[(k + 1).min(own - 1)], s)
                            })
                            .collect(),
                        rotation: at
                            .iter()
                            .map(|&(k, s)| {
                                let (a, b) = (rotation[k], rotation[(k + 1).min(own - 1)]);
                                a.try_slerp(&b, s, 1e-12)
                                    .unwrap_or(if s < 0.5 { a } else { b })
                            })
                            .collect(),
                    },
                    Motion::Deforming { frames: f } => Motion::Deforming {
                        frames: at
                            .iter()
                            .map(|&(k, s)| {
                                let next = &f[(k + 1).min(own - 1)];
                                f[k].iter().zip(next).map(|(a, b)| a.lerp(b, s)).collect()
                            })
                            .collect(),
                    },
                };
                ClipObject {
                    name: o.name.clone(),
                    kind: o.kind.clone(),
                    label: o.label.clone(),
                    regime: o.regime.clone(),
                    features: o.features.clone(),
                    triangles: o.triangles.clone(),
                    segments: o.segments.clone(),
                    body: o.body.clone(),
                    render: o.render.clone(),
                    motion,
                    first_frame: first,
                }
            })
            .collect();
        Clip {
            name: self.name.clone(),
            fps,
            frames,
            objects,
            ground: self.ground,
            wind: self.wind.clone(),
            aero_law: self.aero_law.clone(),
            warnings: self.warnings.clone(),
        }
    }

    /// [`Self::validate`] for a clip read from a file, whose objects may
    /// live a part of it ([`ClipObject::first_frame`]): each holds at
    /// least one frame and ends by the clip's last.
    pub fn validate_read(&self) -> Result<(), ExportError> {
        self.check(false)
    }

    /// The checks of [`Self::validate`]; `whole`: every object lives the
    /// whole clip.
    fn check(&self, whole: bool) -> Result<(), ExportError> {
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
            let lives = if whole {
                o.lives_whole(self.frames)
            } else {
                o.frame_count() > 0 && o.first_frame + o.frame_count() <= self.frames
            };
            let frames_ok = lives
                && match &o.motion {
                    Motion::Rigid {
                        translation,
                        rotation,
                        local,
                    } => {
                        rotation.len() == translation.len()
                            && local.iter().chain(translation).all(finite)
                    }
                    Motion::Deforming { frames } => {
                        frames.iter().all(|f| f.len() == n && f.iter().all(finite))
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

/// A rigid object's motion on the grid t0 + k / fps (k < `count`): the rest
/// shape of `model` about its centre of mass, placed by `trajectory` (the
/// pose of that model) resampled onto the grid.
pub fn rigid_motion(model: &Model, trajectory: &Trajectory, fps: f64, count: usize) -> Motion {
    let com = model.centre_of_mass(&model.rest_position);
    let r = trajectory.resampled(fps);
    let take = count.min(r.len());
    Motion::Rigid {
        local: model.rest_position.iter().map(|x| x - com).collect(),
        translation: pad(r.position[..take].to_vec(), count),
        rotation: pad(r.orientation[..take].to_vec(), count),
    }
}

/// Pads a per-frame list to `count` by repeating its last entry (a pose
/// recording may end a round-off short of the last grid time).
fn pad<T: Clone>(mut v: Vec<T>, count: usize) -> Vec<T> {
    if let Some(last) = v.last().cloned() {
        v.resize(count, last);
    }
    v
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

pub(crate) fn to_u32(t: &[usize; 3]) -> [u32; 3] {
    t.map(|i| i as u32)
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

    /// A read mesh of three vertices moving as `at(t)` (vertex i offset by
    /// i along x), over clip frames `first..first + count` at `fps`.
    fn moving(
        name: &str,
        fps: f64,
        first: usize,
        count: usize,
        at: impl Fn(f64) -> V3,
    ) -> ClipObject {
        let frames = (first..first + count)
            .map(|k| {
                let p = at(k as f64 / fps);
                (0..3).map(|i| p + V3::x() * i as f64).collect()
            })
            .collect();
        ClipObject {
            first_frame: first,
            ..ClipObject::read_mesh(name.into(), vec![[0, 1, 2]], frames)
        }
    }

    #[test]
    fn a_resampled_clip_keeps_each_object_s_life_and_linear_motion() {
        let at = |t: f64| V3::new(0.3 * t, -t, 2.0 - 0.5 * t);
        // 24 keys per second over 10 s; one object lives it all, one is
        // born at 2.5 s, one dies at 4.5 s, one lives 1/48 s between two
        // frames of a 12 Hz grid.
        let clip = Clip::bare(
            "c",
            24.0,
            241,
            vec![
                moving("whole", 24.0, 0, 241, at),
                moving("born", 24.0, 60, 181, at),
                moving("dies", 24.0, 0, 109, at),
                moving("brief", 24.0, 13, 1, at),
            ],
        );
        clip.validate_read().unwrap();
        let out = clip.resampled(12.0);
        out.validate_read().unwrap();
        assert_eq!(out.frames, 121);
        let lives: Vec<(usize, usize)> = out
            .objects
            .iter()
            .map(|o| (o.first_frame, o.frame_count()))
            .collect();
        // 2.5 s is frame 30 of 12 Hz; 4.5 s is frame 54; 13/24 s lies
        // between frames 6 and 7, nearer 7 (6.5 rounds up).
        assert_eq!(lives, [(0, 121), (30, 91), (0, 55), (7, 1)]);
        for o in &out.objects[..3] {
            for k in 0..o.frame_count() {
                let t = (o.first_frame + k) as f64 / 12.0;
                let p = o.positions(k);
                assert!((p[0] - at(t)).norm() < 1e-12, "{} at {t} s", o.name);
                assert!((p[2] - at(t) - V3::x() * 2.0).norm() < 1e-12);
            }
        }
        // A 7 Hz grid falls between the keys: interpolated, still exact.
        let out = clip.resampled(7.0);
        let born = &out.objects[1];
        assert_eq!(born.first_frame, 18); // ceil(2.5 × 7)
        for k in 0..born.frame_count() {
            let t = (born.first_frame + k) as f64 / 7.0;
            assert!((born.positions(k)[0] - at(t)).norm() < 1e-12);
        }
    }

    #[test]
    fn a_rigid_object_resamples_by_its_rotation_and_scales_by_its_lengths() {
        // Turning at 1 rad/s about z, its centre moving along x.
        let n = 31;
        let mut o = ClipObject::read_mesh("r".into(), vec![[0, 1, 2]], vec![]);
        o.motion = Motion::Rigid {
            local: vec![V3::x(), V3::y(), V3::zeros()],
            translation: (0..n).map(|k| V3::x() * k as f64 / 10.0).collect(),
            rotation: (0..n)
                .map(|k| UnitQuaternion::from_axis_angle(&Vector3::z_axis(), k as f64 / 10.0))
                .collect(),
        };
        let clip = Clip::bare("c", 10.0, n, vec![o]);
        // At 4 Hz, t = 0.25 s falls between keys 2 and 3: the rotation is
        // spherically interpolated, so the vertex stays on its circle at
        // the angle t.
        let out = clip.resampled(4.0);
        let r = &out.objects[0];
        for k in 0..r.frame_count() {
            let t = k as f64 / 4.0;
            let p = r.positions(k)[0];
            let want = V3::new(t + t.cos(), t.sin(), 0.0);
            assert!((p - want).norm() < 1e-12, "t = {t}: {p:?} against {want:?}");
        }
        // Centimetres to metres: every vertex at every frame × 0.01.
        let mut cm = clip.clone();
        cm.objects[0].scale(0.01);
        for k in 0..n {
            for (a, b) in cm.objects[0]
                .positions(k)
                .iter()
                .zip(clip.objects[0].positions(k))
            {
                assert!((a - b * 0.01).norm() < 1e-15);
            }
        }
    }
}
