//! Any supported file as a fall: the one entry point, [`read_any_fall`],
//! decides by the file's name how it becomes a [`Trajectory`] for
//! `classify`, `describe`, `compare` and `breed --like`. A CSV record is
//! read by [`crate::motion::trajectory`]; of an animation file (glTF 2.0,
//! `.glb` or `.gltf`; USD; Alembic: what leafmagic exports, and what
//! Blender, Houdini or a game engine bake) the fall of one object is
//! measured here.
//!
//! A recorded fall is a centre and, where known, a body-to-world rotation
//! whose body z is the plate's normal and body x its long axis
//! ([`crate::motion::trajectory`]). An animation file carries neither as
//! such: it carries a mesh in the node's own frame, whose origin and axes
//! are the modeller's (Blender's default plane lies in its local xy-plane,
//! another tool's in xz, a leaf may be modelled tilted), moved by the
//! node's translation and rotation per key, or deformed by morph targets.
//! So both are measured from the shape, as a uniform sheet's would be:
//!
//! - each triangle's area is lumped a third to each of its corners, which
//!   puts the weighted mean of the vertices exactly at the sheet's centroid;
//! - the body axes are the principal axes of the triangles' exact second
//!   moment of area about it: x the direction of largest extent, z of the
//!   smallest (the normal of a flat sheet), y = z × x;
//! - a rigid node's fall is its pose applied to that frame; a deforming
//!   mesh's is the best-fitting rigid motion of its first frame onto each
//!   frame (area-weighted least squares, solved by SVD: Kabsch 1976).
//!
//! A shape with no plane (a rope, a point) gives a centre only, which the
//! path classifier reads. The axes of a square or a disk are arbitrary in
//! its plane (equal moments); the classifier needs only the normal there.
//!
//! The file is sampled at its own keys ([`crate::formats::gltf::read_gltf_keys`],
//! [`crate::formats::usd::read_usda_keys`]): from the first key to the last, at one frame
//! per shortest key interval.

use crate::formats::alembic::read_abc;
use crate::formats::clip::frame::{MAX_SOLVER_ITERATIONS, kabsch};
use crate::formats::clip::{Clip, ClipObject, Motion, POINT_KIND};
use crate::formats::error::ExportError;
use crate::formats::gltf::read_gltf_keys;
use crate::formats::usd::read_usd_file;
use crate::motion::classify::{Classification, classify};
use crate::motion::trajectory::{ReadNotes, Trajectory, UpAxis};
use crate::util::confined::{ReadPolicy, ReadScope};
use crate::util::setting::Setting;
use nalgebra::{Matrix3, SymmetricEigen, UnitQuaternion, Vector3};
use std::path::Path;

type V3 = Vector3<f64>;

/// Vertices beyond which the chord is measured on a subsample (every k-th
/// vertex) rather than over all pairs: 4000² / 2 pairs take about 10 ms.
const MAX_CHORD_VERTICES: usize = 4000;

/// A moving object's largest displacement from its first frame must exceed
/// this fraction of its chord to count as moving: a static ground plane or
/// a prop is left out, float noise in a static key is not motion.
const MOVING_FRACTION_OF_CHORD: f64 = 1e-6;

/// The animation formats a fall is read from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AnimationFormat {
    /// glTF 2.0: `.glb`, `.gltf`.
    Gltf,
    /// USD: `.usda`, `.usd`, `.usdc`, `.usdz` (text, binary crate files,
    /// packages; composed stages flattened first).
    Usd,
    /// Alembic: `.abc` (Ogawa; [`crate::formats::alembic::read_abc`]).
    Alembic,
}

impl AnimationFormat {
    /// The format `path` names by its extension (any case); `None` for any
    /// other file (a CSV record).
    pub fn of(path: &Path) -> Option<AnimationFormat> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "glb" | "gltf" => Some(AnimationFormat::Gltf),
            "usda" | "usd" | "usdc" | "usdz" => Some(AnimationFormat::Usd),
            "abc" => Some(AnimationFormat::Alembic),
            _ => None,
        }
    }
}

/// The fall of one object of an animation file.
#[derive(Clone, Debug)]
pub struct AnimationFall {
    /// Centre and orientation per key (times from the file's first key).
    pub trajectory: Trajectory,
    /// The object's name in the file (the node's; `node-N` if unnamed).
    pub object: String,
    /// Its longest extent (the largest distance between two vertices of
    /// its first frame), m: the `--size` a classification needs.
    pub chord: f64,
    /// The rate the file was sampled at, Hz (its keys' own).
    pub rate_hz: f64,
    /// Objects of the file that do not move (a ground, a prop), left out.
    pub still: Vec<String>,
    /// Why the record has no orientation, when it has none.
    pub no_orientation: Option<String>,
    /// When the object appears, s after the file's first key: 0 but for
    /// one that lives only a part of the file (a PointInstancer's leaf
    /// born during it), whose trajectory's times start at 0 there.
    pub appears_s: f64,
    /// What reading the file left out without refusing it
    /// ([`Clip::warnings`]).
    pub warnings: Vec<String>,
}

/// Reads the fall of `object` (or of the only object that moves) from a
/// glTF or USD file ([`AnimationFormat::of`] its name; glTF if it names
/// none). Errors name the file and, when the file holds several moving
/// objects and none is named, list them.
pub fn read_fall(path: &Path, object: Option<&str>) -> Result<AnimationFall, ExportError> {
    read_fall_of(path, object, None)
}

/// [`read_fall`], of the glTF animation `animation` names where the file
/// holds several ([`crate::formats::gltf::read_gltf_keys`]); a USD stage holds one, and
/// naming one there is refused.
pub fn read_fall_of(
    path: &Path,
    object: Option<&str>,
    animation: Option<&str>,
) -> Result<AnimationFall, ExportError> {
    read_fall_in(path, object, animation, &ReadPolicy::default())
}

/// [`read_fall_of`] under `policy` ([`read_clip_in`]).
pub fn read_fall_in(
    path: &Path,
    object: Option<&str>,
    animation: Option<&str>,
    policy: &ReadPolicy,
) -> Result<AnimationFall, ExportError> {
    let clip = read_clip_in(path, animation, policy)?;
    // Each object's chord, measured once: it sets what counts as moving,
    // and the chosen one's is the fall's size.
    let objects = &clip.objects;
    let chords: Vec<f64> = objects.iter().map(|o| chord(&o.positions(0))).collect();
    let (moving, still): (Vec<usize>, Vec<usize>) =
        (0..objects.len()).partition(|&k| moves(&objects[k], chords[k]));
    let named = |ks: &[usize]| {
        listed(
            &ks.iter().map(|&k| &objects[k]).collect::<Vec<_>>(),
            clip.frames,
            clip.fps,
        )
    };
    let chosen = match object {
        Some(want) => objects.iter().position(|o| o.name == want).ok_or_else(|| {
            ExportError::input(
                path,
                format!(
                    "{}: no object of that name; it holds {}",
                    Setting::Object.set(want),
                    named(&(0..objects.len()).collect::<Vec<_>>())
                ),
            )
        })?,
        None => match moving.as_slice() {
            [one] => *one,
            [] => {
                return Err(ExportError::input(
                    path,
                    format!(
                        "nothing in it moves ({}, over {} key{}): a fall needs an animated object",
                        named(&still),
                        clip.frames,
                        if clip.frames == 1 { "" } else { "s" }
                    ),
                ));
            }
            many => {
                return Err(ExportError::input(
                    path,
                    format!(
                        "{} objects move in it ({}): name the one to read with {}",
                        many.len(),
                        named(many),
                        Setting::Object.set("NAME")
                    ),
                ));
            }
        },
    };
    far_out(&objects[chosen]).map_err(|e| ExportError::input(path, e))?;
    let (trajectory, no_orientation) = fall_of(&objects[chosen], clip.fps);
    Ok(AnimationFall {
        trajectory,
        object: objects[chosen].name.clone(),
        chord: chords[chosen],
        rate_hz: clip.fps,
        still: still
            .iter()
            .filter(|&&k| k != chosen)
            .map(|&k| objects[k].name.clone())
            .collect(),
        no_orientation,
        appears_s: objects[chosen].first_frame as f64 / clip.fps,
        warnings: clip.warnings.clone(),
    })
}

/// How a CSV record's numbers are read: its vertical axis, the metres in
/// one of its length units (a tracker's pixel, once measured against a
/// ruler in the frame), and the frame rate if its `t` counts frames.
/// Animation files say their own, but for an Alembic archive's length unit:
/// Alembic carries none (metres are assumed, as Blender and Houdini write;
/// Maya writes centimetres), so `scale` says what one of its units is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RecordUnits {
    /// The record's vertical axis.
    pub up: UpAxis,
    /// Metres per unit of its x, y, z (1 for metres).
    pub scale: f64,
    /// Frames per second when `t` is a frame number.
    pub frame_rate: Option<f64>,
}

impl Default for RecordUnits {
    /// A record in metres and seconds, z up.
    fn default() -> RecordUnits {
        RecordUnits {
            up: UpAxis::Z,
            scale: 1.0,
            frame_rate: None,
        }
    }
}

/// A fall as read from any supported file ([`read_any_fall`]).
#[derive(Clone, Debug)]
pub enum RecordedFall {
    /// A CSV record, in metres and seconds, z up.
    Record {
        /// The record.
        trajectory: Trajectory,
        /// What the CSV reader noticed without refusing the file.
        notes: ReadNotes,
    },
    /// One object's fall of an animation file, in the file's own units
    /// (an Alembic archive's scaled by [`RecordUnits::scale`]).
    Animation {
        /// The file's format.
        format: AnimationFormat,
        /// The fall, and what the file told of it.
        fall: AnimationFall,
    },
}

impl RecordedFall {
    /// The fall's record.
    pub fn trajectory(&self) -> &Trajectory {
        match self {
            RecordedFall::Record { trajectory, .. } => trajectory,
            RecordedFall::Animation { fall, .. } => &fall.trajectory,
        }
    }
}

/// The one place that decides how a file becomes a fall, by its name
/// ([`AnimationFormat::of`]): a glTF, USD or Alembic file gives the fall of
/// `object` (or of the only object that moves; of the glTF animation
/// `animation` names, [`read_fall_in`]), any other file is a CSV record
/// read in `units` ([`Trajectory::read_csv_with`]), which holds one fall:
/// an object or an animation asked of it is refused. Errors name the file.
pub fn read_any_fall(
    path: &Path,
    units: RecordUnits,
    object: Option<&str>,
    animation: Option<&str>,
    policy: &ReadPolicy,
) -> Result<RecordedFall, ExportError> {
    let Some(format) = AnimationFormat::of(path) else {
        // Worded as the file's other refusals (see `read_fall_in`), by the
        // setting.
        for (option, given, what) in [
            (Setting::Object, object, "an object"),
            (Setting::Animation, animation, "an animation"),
        ] {
            if let Some(given) = given {
                return Err(ExportError::input(
                    path,
                    format!(
                        "{}: a CSV record holds one fall; {option} picks {what} of an animation file (.glb, .gltf, .usd, .abc)",
                        option.set(given)
                    ),
                ));
            }
        }
        let (mut trajectory, notes) = Trajectory::read_csv_with(path, units.up)?;
        trajectory.rescale(units.scale, units.frame_rate);
        return Ok(RecordedFall::Record { trajectory, notes });
    };
    let mut fall = read_fall_in(path, object, animation, policy)?;
    if format == AnimationFormat::Alembic && units.scale != 1.0 {
        fall.trajectory.rescale(units.scale, None);
        fall.chord *= units.scale;
    }
    Ok(RecordedFall::Animation { format, fall })
}

/// Every object of a glTF, USD or Alembic file ([`AnimationFormat::of`]
/// its name; glTF if it names none), sampled at the file's own keys: what
/// a fall is read from, and what `preview` plays of such a file. Of a glTF
/// file with several animations, `animation` names the one to read
/// ([`crate::formats::gltf::read_gltf_keys`]); a USD stage or an Alembic archive holds
/// one, and naming one there is refused. Errors name the file.
pub fn read_clip(path: &Path, animation: Option<&str>) -> Result<Clip, ExportError> {
    read_clip_in(path, animation, &ReadPolicy::default())
}

/// [`read_clip`] under `policy`: the folders the file's references may
/// reach besides its own and the memory its read may take ([`ReadScope`]).
pub fn read_clip_in(
    path: &Path,
    animation: Option<&str>,
    policy: &ReadPolicy,
) -> Result<Clip, ExportError> {
    let scope = &ReadScope::new(path, policy).map_err(|e| ExportError::input(path, e))?;
    let bytes = scope
        .check(path)
        .and_then(|real| scope.read_checked(&real))
        .map_err(|e| ExportError::input(path, e))?;
    let name = path.file_stem().map_or("animation".to_string(), |s| {
        s.to_string_lossy().into_owned()
    });
    let format = AnimationFormat::of(path);
    if let (Some(want), Some(AnimationFormat::Usd | AnimationFormat::Alembic)) = (animation, format)
    {
        return Err(ExportError::input(
            path,
            format!(
                "{}: a USD stage or an Alembic archive holds one animation; {} picks one of a glTF file's",
                Setting::Animation.set(want),
                Setting::Animation
            ),
        ));
    }
    match format {
        Some(AnimationFormat::Usd) => read_usd_file(path, &bytes, &name, scope),
        Some(AnimationFormat::Alembic) => read_abc(&bytes, &name).map_err(ExportError::Data),
        _ => {
            let dir = path.parent().unwrap_or(Path::new("."));
            read_gltf_keys(&bytes, &name, Some((dir, scope)), animation)
        }
    }
    .map_err(|e| match e {
        ExportError::Data(reason) => ExportError::input(path, reason),
        e => e,
    })
}

/// Whether `o` is a fall to classify: a surface that moves (a mesh, leaf
/// or sheet) or a particle, with more than one frame, within
/// [`MAX_COORDINATE_M`]. Still objects, ropes and rigid props are not.
fn is_fall(o: &ClipObject, chord: f64) -> bool {
    let kind = (!o.triangles.is_empty() && matches!(o.kind.as_str(), "mesh" | "leaf" | "sheet"))
        || o.kind == POINT_KIND;
    kind && o.frame_count() > 1 && moves(o, chord) && far_out(o).is_ok()
}

/// Every object of `clip` that `wanted` names classified as `classify
/// FILE --object NAME` classifies it ([`fall_of`] at the clip's keys, sized
/// by `size` or its chord; a particle by its width), in parallel; `None`
/// for an object not wanted or that is no fall to classify (still, a rope
/// or a prop).
pub fn classify_objects(
    clip: &Clip,
    size: Option<f64>,
    wanted: impl Fn(&ClipObject) -> bool + Sync,
) -> Vec<Option<Classification>> {
    use rayon::prelude::*;
    clip.objects
        .par_iter()
        .map(|o| {
            if !wanted(o) {
                return None;
            }
            let chord = chord(&o.positions(0));
            if !is_fall(o, chord) {
                return None;
            }
            let (trajectory, _) = fall_of(o, clip.fps);
            Some(classify(&trajectory, size.unwrap_or(chord)))
        })
        .collect()
}

/// Farthest a vertex may be from the origin, m: a thousand kilometres,
/// beyond any fall, and small enough that the areas and moments of the
/// shape stay finite (1e12 m², where a file with a coordinate of 1e308, a
/// corrupt or mis-scaled one, made them infinite and the eigen-solver spin).
pub const MAX_COORDINATE_M: f64 = 1e6;

/// Why `o` cannot be a fall if a vertex of it is farther than
/// [`MAX_COORDINATE_M`] from the origin at one of its frames.
pub(crate) fn far_out(o: &ClipObject) -> Result<(), String> {
    for k in 0..o.frame_count() {
        if let Some((i, p)) = o
            .positions(k)
            .iter()
            .enumerate()
            .find(|(_, p)| p.iter().any(|c| c.is_nan() || c.abs() > MAX_COORDINATE_M))
        {
            return Err(format!(
                "object `{}`: vertex {i} at key {} is at ({:.4e}, {:.4e}, {:.4e}) m, more than {MAX_COORDINATE_M:e} m from the origin: are its units or its keys right?",
                o.name,
                o.first_frame + k,
                p.x,
                p.y,
                p.z
            ));
        }
    }
    Ok(())
}

/// `a (rigid), b (deforming, 0.50–4.00 s of 10.00 s)`: names with how
/// they move, and when, for an object that lives only a part of a clip
/// of `frames` frames at `fps`.
fn listed(objects: &[&ClipObject], frames: usize, fps: f64) -> String {
    let mut names: Vec<String> = objects
        .iter()
        .take(LISTED)
        .map(|o| {
            let how = match o.motion {
                _ if o.is_marker() => "point",
                Motion::Rigid { .. } => "rigid",
                Motion::Deforming { .. } => "deforming",
            };
            if o.lives_whole(frames) {
                format!("`{}` ({how})", o.name)
            } else {
                let (born, dies) = o.life_s(fps);
                format!(
                    "`{}` ({how}, {born:.2}–{dies:.2} s of {:.2} s)",
                    o.name,
                    frames.saturating_sub(1) as f64 / fps
                )
            }
        })
        .collect();
    if objects.len() > LISTED {
        names.push(format!("and {} more", objects.len() - LISTED));
    }
    names.join(", ")
}

/// Most objects a message lists by name: a PointInstancer's thousands of
/// leaves would bury it.
const LISTED: usize = 20;

/// Whether any vertex of `o` leaves its first position by more than
/// [`MOVING_FRACTION_OF_CHORD`] of its `chord`.
pub(crate) fn moves(o: &ClipObject, chord: f64) -> bool {
    let frames = match &o.motion {
        Motion::Rigid { translation, .. } => translation.len(),
        Motion::Deforming { frames } => frames.len(),
    };
    let first = o.positions(0);
    let tol = MOVING_FRACTION_OF_CHORD * chord.max(f64::MIN_POSITIVE);
    (1..frames).any(|k| {
        o.positions(k)
            .iter()
            .zip(&first)
            .any(|(p, q)| (p - q).norm() > tol)
    })
}

/// The largest distance between two of `points` (over a subsample of every
/// k-th point above 4000 points).
pub fn chord(points: &[V3]) -> f64 {
    let step = points.len().div_ceil(MAX_CHORD_VERTICES).max(1);
    let p: Vec<&V3> = points.iter().step_by(step).collect();
    let mut best: f64 = 0.0;
    for (i, a) in p.iter().enumerate() {
        for b in &p[i + 1..] {
            best = best.max((*a - *b).norm());
        }
    }
    best
}

/// Each vertex's share of the surface: a third of the area of each
/// triangle it is a corner of; every vertex alike where the object has no
/// triangles or they have no area (a rope, points).
pub fn lumped_area(points: &[V3], triangles: &[[u32; 3]]) -> Vec<f64> {
    let mut m = vec![0.0; points.len()];
    for t in triangles {
        let [a, b, c] = t.map(|i| i as usize);
        if a.max(b).max(c) >= points.len() {
            continue;
        }
        let area = 0.5
            * (points[b] - points[a])
                .cross(&(points[c] - points[a]))
                .norm();
        for i in [a, b, c] {
            m[i] += area / 3.0;
        }
    }
    let total: f64 = m.iter().sum();
    if total.is_nan() || total <= 0.0 {
        m.iter_mut().for_each(|x| *x = 1.0);
    }
    m
}

/// The second moment of area of the triangles of `points` about the
/// origin, ∫ r rᵀ dA: for each triangle (A/12)(Σ vᵢvᵢᵀ + s sᵀ), s = Σ vᵢ,
/// exact for a uniform sheet. Lumped corner areas would not do here: a
/// quad split along one diagonal puts twice the area at two opposite
/// corners, and its axes would turn toward that diagonal (11° on a
/// 4 × 2 cm card).
fn area_moment(points: &[V3], triangles: &[[u32; 3]]) -> Matrix3<f64> {
    let mut j = Matrix3::zeros();
    for t in triangles {
        let [a, b, c] = t.map(|i| i as usize);
        if a.max(b).max(c) >= points.len() {
            continue;
        }
        let (a, b, c) = (points[a], points[b], points[c]);
        let area = 0.5 * (b - a).cross(&(c - a)).norm();
        let s = a + b + c;
        j += (a * a.transpose() + b * b.transpose() + c * c.transpose() + s * s.transpose())
            * (area / 12.0);
    }
    j
}

/// The principal frame of `rest` (about its centre): the rotation taking
/// body axes (x largest extent, z smallest) to the axes `rest` is written
/// in, or `None` if the shape spans no plane (or its moments are not
/// finite). From the triangles' second
/// moment of area, or from the points weighted by `mass` where there are
/// no triangles with area (a rope, points).
pub fn principal_frame(
    rest: &[V3],
    triangles: &[[u32; 3]],
    mass: &[f64],
) -> Option<UnitQuaternion<f64>> {
    let mut second = area_moment(rest, triangles);
    if second.trace().is_nan() || second.trace() <= 0.0 {
        second = Matrix3::zeros();
        for (r, m) in rest.iter().zip(mass) {
            second += r * r.transpose() * *m;
        }
    }
    // Bounded iterations: a matrix that is not finite would never converge.
    let eig = SymmetricEigen::try_new(second, f64::EPSILON, MAX_SOLVER_ITERATIONS)?;
    let mut order = [0usize, 1, 2];
    order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
    let (largest, middle) = (eig.eigenvalues[order[0]], eig.eigenvalues[order[1]]);
    // A line or a point: no second direction, so no plane to orient.
    if largest.is_nan() || largest <= 0.0 || middle <= 1e-9 * largest {
        return None;
    }
    let x: V3 = eig.eigenvectors.column(order[0]).into();
    let y0: V3 = eig.eigenvectors.column(order[1]).into();
    let z = x.cross(&y0).normalize();
    let y = z.cross(&x);
    let m = Matrix3::from_columns(&[x, y, z]);
    Some(UnitQuaternion::from_matrix(&m))
}

/// The fall of `o` sampled at `fps`: its centre and the orientation of its
/// principal frame per frame (see the module doc); with the reason when
/// the shape gives no orientation.
pub fn fall_of(o: &ClipObject, fps: f64) -> (Trajectory, Option<String>) {
    let first = o.positions(0);
    let mass = lumped_area(&first, &o.triangles);
    let total: f64 = mass.iter().sum();
    let centre = |f: &[V3]| f.iter().zip(&mass).map(|(x, m)| x * *m).sum::<V3>() / total;
    // The shape about its centre, in the coordinates the motion's rotation
    // acts on: the local mesh for a rigid node, the first frame for a
    // deforming one.
    let shape = match &o.motion {
        Motion::Rigid { local, .. } => local.as_slice(),
        Motion::Deforming { .. } => first.as_slice(),
    };
    let c_shape = centre(shape);
    let rest: Vec<V3> = shape.iter().map(|x| x - c_shape).collect();
    let (centre, rotation): (Vec<V3>, Vec<UnitQuaternion<f64>>) = match &o.motion {
        Motion::Rigid {
            translation,
            rotation,
            ..
        } => (
            translation
                .iter()
                .zip(rotation)
                .map(|(t, q)| t + q * c_shape)
                .collect(),
            rotation.clone(),
        ),
        Motion::Deforming { frames } => {
            // Each frame's best rigid fit of the first by its own SVD
            // (Kabsch), the global optimum: a Newton iteration started
            // from the previous frame (what the exporters' frame uses, for
            // small steps) can settle on a saddle 180° away when a card
            // turns 20–30° between keys, as a 24 fps bake of a tumble does.
            let mut previous: Option<UnitQuaternion<f64>> = None;
            frames
                .iter()
                .map(|f| {
                    let c = centre(f);
                    let mut a = Matrix3::zeros();
                    for ((p, r), m) in f.iter().zip(&rest).zip(&mass) {
                        a += (p - c) * (r * *m).transpose();
                    }
                    let mut q = kabsch(&a);
                    // q and −q are one rotation: keep the sign continuous.
                    if previous.is_some_and(|p| p.coords.dot(&q.coords) < 0.0) {
                        q = UnitQuaternion::new_unchecked(-q.into_inner());
                    }
                    previous = Some(q);
                    (c, q)
                })
                .unzip()
        }
    };
    // A marker's crossed lines have moments but no attitude to read.
    let principal = if o.is_marker() {
        None
    } else {
        principal_frame(&rest, &o.triangles, &mass)
    };
    let mut t = Trajectory::with_capacity(centre.len());
    for (k, c) in centre.iter().enumerate() {
        let time = k as f64 / fps;
        match principal {
            Some(p) => t.push(time, *c, rotation[k] * p),
            None => t.push_position(time, *c),
        }
    }
    let why = principal.is_none().then(|| {
        if o.is_marker() {
            format!(
                "`{}` is a point (a particle), with no attitude: read from its path only, sized by its width",
                o.name
            )
        } else {
            format!(
                "`{}` spans no plane (its vertices lie on a line or at a point): read from its centre only",
                o.name
            )
        }
    });
    (t, why)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A CSV record goes to the motion layer's reader, in the units asked,
    /// and an object or animation asked of it is refused naming the file.
    #[test]
    fn any_fall_reads_a_csv_record_in_its_units_and_refuses_picks() {
        let dir = std::env::temp_dir().join(format!("leafmagic-anyfall-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("fall.csv");
        std::fs::write(&path, "t,x,y,z\n0,0,0,100\n1,3,4,90\n2,6,8,80\n").unwrap();
        let units = RecordUnits {
            up: UpAxis::Z,
            scale: 0.01,
            frame_rate: Some(50.0),
        };
        let policy = ReadPolicy::default();
        let read = read_any_fall(&path, units, None, None, &policy).unwrap();
        let (mut want, _) = Trajectory::read_csv_with(&path, UpAxis::Z).unwrap();
        want.rescale(0.01, Some(50.0));
        assert!(matches!(&read, RecordedFall::Record { .. }));
        assert_eq!(read.trajectory(), &want);
        assert!((read.trajectory().position[1].z - 0.9).abs() < 1e-12);
        for (object, animation, option) in [
            (Some("leaf"), None, "object = leaf"),
            (None, Some("take"), "animation = take"),
        ] {
            let e = read_any_fall(&path, units, object, animation, &policy)
                .unwrap_err()
                .to_string();
            assert!(
                e.contains(path.to_str().unwrap()) && e.contains(option) && e.contains("CSV"),
                "{e}"
            );
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    fn plate(n: usize, long: f64, wide: f64) -> (Vec<V3>, Vec<[u32; 3]>) {
        // A grid of n × n cells over long × wide, in the xz-plane (as a
        // y-up modeller lays a plate down), triangulated.
        let mut p = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                let (s, t) = (i as f64 / n as f64 - 0.5, j as f64 / n as f64 - 0.5);
                p.push(V3::new(long * s, 0.0, wide * t));
            }
        }
        let mut tri = Vec::new();
        let at = |i: usize, j: usize| (j * (n + 1) + i) as u32;
        for j in 0..n {
            for i in 0..n {
                tri.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
                tri.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
            }
        }
        (p, tri)
    }

    #[test]
    fn lumped_areas_sum_to_the_area_and_centre_the_sheet() {
        let (p, tri) = plate(5, 0.04, 0.01);
        let m = lumped_area(&p, &tri);
        let total: f64 = m.iter().sum();
        assert!((total - 0.04 * 0.01).abs() < 1e-15);
        // A triangle's centroid is the mean of its corners, so the lumped
        // centre is the area centroid exactly: of an L-shape (two plates).
        let l: Vec<V3> = vec![
            V3::new(0.0, 0.0, 0.0),
            V3::new(2.0, 0.0, 0.0),
            V3::new(2.0, 1.0, 0.0),
            V3::new(0.0, 1.0, 0.0),
            V3::new(0.0, 3.0, 0.0),
            V3::new(1.0, 3.0, 0.0),
            V3::new(1.0, 1.0, 0.0),
        ];
        let tl = vec![[0, 1, 2], [0, 2, 3], [3, 6, 5], [3, 5, 4]];
        let m = lumped_area(&l, &tl);
        let c = l.iter().zip(&m).map(|(x, w)| x * *w).sum::<V3>() / m.iter().sum::<f64>();
        // 2 × 1 at (1, 0.5) and 1 × 2 at (0.5, 2): centroid (0.75, 1.25).
        assert!((c - V3::new(0.75, 1.25, 0.0)).norm() < 1e-15, "{c}");
    }

    #[test]
    fn a_strip_s_principal_frame_has_x_along_it_and_z_its_normal() {
        let (p, tri) = plate(8, 0.04, 0.01);
        let m = lumped_area(&p, &tri);
        let q = principal_frame(&p, &tri, &m).unwrap();
        let x = q * V3::x();
        let z = q * V3::z();
        assert!(x.cross(&V3::x()).norm() < 1e-9, "long axis {x}");
        assert!(z.cross(&V3::y()).norm() < 1e-9, "normal {z}");
        // Proper rotation: body y = z × x.
        assert!(((q * V3::y()) - z.cross(&x)).norm() < 1e-12);
    }

    #[test]
    fn a_line_has_no_frame() {
        let p: Vec<V3> = (0..5).map(|i| V3::new(0.0, i as f64, 0.0)).collect();
        assert!(principal_frame(&p, &[], &[1.0; 5]).is_none());
    }

    #[test]
    fn a_quad_split_along_a_diagonal_keeps_its_sides_as_axes() {
        // Two triangles over a 4 × 2 card: lumped areas would weight
        // corners 0 and 2 double and turn the axes toward that diagonal.
        let p = vec![
            V3::new(-0.02, -0.01, 0.0),
            V3::new(0.02, -0.01, 0.0),
            V3::new(0.02, 0.01, 0.0),
            V3::new(-0.02, 0.01, 0.0),
        ];
        let tri = [[0, 1, 2], [0, 2, 3]];
        let q = principal_frame(&p, &tri, &lumped_area(&p, &tri)).unwrap();
        assert!((q * V3::x()).cross(&V3::x()).norm() < 1e-12);
        assert!((q * V3::z()).cross(&V3::z()).norm() < 1e-12);
        // The exact moment of a rectangle: (A/12) diag(L², W², 0).
        let j = area_moment(&p, &tri);
        let area = 0.04 * 0.02;
        assert!((j[(0, 0)] - area * 0.04f64.powi(2) / 12.0).abs() < 1e-18);
        assert!((j[(1, 1)] - area * 0.02f64.powi(2) / 12.0).abs() < 1e-18);
        assert!(j[(0, 1)].abs() < 1e-20);
    }

    #[test]
    fn the_chord_is_the_largest_distance() {
        let (p, _) = plate(4, 0.04, 0.03);
        assert!((chord(&p) - 0.05).abs() < 1e-15);
    }

    /// A plate turned by a known rotation and moved, as a rigid node and as
    /// a deforming mesh: both read back the centre and a frame whose normal
    /// is the turned plate's normal, and the same rotation between frames.
    #[test]
    fn rigid_and_deforming_read_the_same_fall() {
        let (local, tri) = plate(4, 0.04, 0.01);
        let frames = 30;
        let pose = |k: usize| {
            let q = UnitQuaternion::from_scaled_axis(V3::new(0.2, 1.5, -0.4) * (k as f64 * 0.1));
            let t = V3::new(0.01 * k as f64, 0.0, 2.0 - 0.02 * k as f64);
            (t, q)
        };
        let rigid = ClipObject {
            first_frame: 0,
            name: "card".into(),
            kind: "mesh".into(),
            label: String::new(),
            regime: String::new(),
            features: vec![],
            triangles: tri.clone(),
            segments: vec![],
            body: None,
            render: None,
            motion: Motion::Rigid {
                local: local.clone(),
                translation: (0..frames).map(|k| pose(k).0).collect(),
                rotation: (0..frames).map(|k| pose(k).1).collect(),
            },
        };
        let deforming = ClipObject {
            first_frame: 0,
            motion: Motion::Deforming {
                frames: (0..frames)
                    .map(|k| {
                        let (t, q) = pose(k);
                        local.iter().map(|x| t + q * x).collect()
                    })
                    .collect(),
            },
            ..rigid.clone()
        };
        let (a, none_a) = fall_of(&rigid, 24.0);
        let (b, none_b) = fall_of(&deforming, 24.0);
        assert!(none_a.is_none() && none_b.is_none());
        for k in 0..frames {
            let (t, q) = pose(k);
            assert!((a.position[k] - t).norm() < 1e-12);
            assert!((b.position[k] - t).norm() < 1e-12);
            // Body z is the plate's normal (local y turned by q).
            let n = q * V3::y();
            assert!((a.orientation[k] * V3::z()).cross(&n).norm() < 1e-9);
            assert!((b.orientation[k] * V3::z()).cross(&n).norm() < 1e-9);
            // The rotation from the first frame is the same in both reads.
            let da = a.orientation[k] * a.orientation[0].inverse();
            let db = b.orientation[k] * b.orientation[0].inverse();
            assert!(da.angle_to(&db) < 1e-9, "frame {k}");
            assert!((a.time[k] - k as f64 / 24.0).abs() < 1e-15);
        }
    }

    #[test]
    fn long_lists_of_objects_name_the_first_twenty_and_count_the_rest() {
        let one = |k: usize| ClipObject::read_mesh(format!("leaves[{k}]"), vec![], vec![vec![]]);
        let objects: Vec<ClipObject> = (0..25).map(one).collect();
        let refs: Vec<&ClipObject> = objects.iter().collect();
        let text = listed(&refs, 1, 24.0);
        assert!(text.starts_with("`leaves[0]` (deforming), `leaves[1]` (deforming)"));
        assert!(text.contains("`leaves[19]`") && !text.contains("`leaves[20]`"));
        assert!(text.ends_with(", and 5 more"), "{text}");
        assert_eq!(
            listed(&refs[..2], 1, 24.0),
            "`leaves[0]` (deforming), `leaves[1]` (deforming)"
        );
    }

    #[test]
    fn an_object_that_lives_part_of_the_clip_is_listed_with_its_life() {
        let frames = |n: usize| vec![vec![V3::zeros()]; n];
        let mut born = ClipObject::read_mesh("leaves[4]".into(), vec![], frames(12));
        born.first_frame = 24;
        let whole = ClipObject::read_mesh("leaves[5]".into(), vec![], frames(241));
        assert_eq!(
            listed(&[&born, &whole], 241, 24.0),
            "`leaves[4]` (deforming, 1.00–1.46 s of 10.00 s), `leaves[5]` (deforming)"
        );
    }
}
