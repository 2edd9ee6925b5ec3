//! The HTML previewer: one self-contained page that plays a [`Clip`] in 3-D
//! with no network access. The page is `page.html` with the viewer
//! (`viewer.js`, plain JavaScript written for leafmagic: a small WebGL
//! renderer and a Canvas 2D fallback) and the data inlined. Vertex positions
//! go in as base64 little-endian float32 arrays, frame after frame, which
//! keeps 100 leaves × 10 s × 30 fps near 3.4 MB.

use crate::breed::{self, Run};
use crate::formats::ExportError;
use crate::formats::clip::look::colour;
use crate::formats::clip::{Clip, ClipObject, DEFAULT_FPS, MARKER_KIND, Motion};
use crate::formats::fall::{self, AnimationFormat};
use crate::formats::gltf;
use crate::motion::trajectory::Trajectory;
use crate::output::export;
use crate::sim::scene::{GOALS_FILE, GoalsRecord};
use crate::util::confined::ReadPolicy;
use crate::util::setting::Setting;
use base64::Engine as _;
use nalgebra::Vector3;

type V3 = Vector3<f64>;
use serde_json::json;
use std::path::Path;

/// The page template; `/*DATA*/` and `/*VIEWER*/` are replaced.
const PAGE: &str = include_str!("page.html");
/// The viewer script.
const VIEWER: &str = include_str!("viewer.js");

/// Bred leaves are laid side by side this many of their largest extents
/// apart, so that drifting falls rarely overlap.
pub const GRID_SPACING_CHORDS: f64 = 3.0;

/// What `preview` plays: the clip, whether it is a grid of bred leaves,
/// and how many of its objects were labelled here by the class of their
/// fall ([`label_falls`]).
#[derive(Clone, Debug)]
pub struct Preview {
    /// The motion to play.
    pub clip: Clip,
    /// A grid of bred leaves: every object labelled, laid side by side.
    pub grid: bool,
    /// The objects of a file labelled with their fall's class here
    /// ([`label_falls`]), by index.
    pub classified: Vec<usize>,
    /// A directed scene's goals and its leaves' verdicts (its output's
    /// `goals.json`), drawn on the page.
    pub goals: Option<GoalsRecord>,
}

/// How to read a file for [`load`]: the ones that apply to it.
#[derive(Clone, Copy, Debug, Default)]
pub struct FileOptions<'a> {
    /// Frames per second of the page [default: a leafmagic `.glb`'s own
    /// rate, 30 for another `.glb`, the keys' own rate for other files].
    pub fps: Option<f64>,
    /// The glTF animation to play where several move the same object.
    pub animation: Option<&'a str>,
    /// Metres per unit of an Alembic archive (which carries no unit;
    /// 0.01 for Maya's centimetres) [default: 1].
    pub scale: Option<f64>,
    /// What an animation file's references may reach and its read may
    /// take [default: its own folder, the default budget].
    pub policy: Option<&'a ReadPolicy>,
}

/// The clip to preview from `input`:
///
/// - a breeding run directory (`run.toml`): the `top` best of the last
///   generation, re-dropped as breeding dropped them
///   ([`export::drop_individuals`]), side by side with their classes;
/// - a scene output directory (`summary.toml`), see [`export::from_scene_dir`];
/// - an animation file: a `.glb` sampled from 0 at the page's rate
///   ([`gltf::from_glb`]), a `.gltf`, USD or Alembic file at its own keys
///   ([`fall::read_clip`]), resampled where `file.fps` asks; each
///   object over its own life (a particle born or killed during the shot),
///   and each falling one the file does not label labelled with the class
///   `classify` gives its fall ([`label_falls`]).
pub fn load(input: &Path, top: usize, file: FileOptions<'_>) -> Result<Preview, ExportError> {
    if !input.exists() {
        return Err(ExportError::input(input, "no such file or directory"));
    }
    if input.is_file() {
        return load_file(input, file);
    }
    for (flag, given) in [
        (Setting::Animation, file.animation.is_some()),
        (Setting::Scale, file.scale.is_some()),
    ] {
        if given {
            return Err(ExportError::input(
                input,
                format!("{flag} applies to an animation file, not to a directory"),
            ));
        }
    }
    let fps = file.fps.unwrap_or(DEFAULT_FPS);
    let plain = |clip| Preview {
        clip,
        grid: false,
        classified: Vec::new(),
        goals: None,
    };
    if input.join("run.toml").is_file() {
        let run = Run::open(input).map_err(|e| ExportError::input(input, e.to_string()))?;
        let Some(cp) = &run.checkpoint else {
            return Err(ExportError::input(
                input,
                "the run has no completed generation yet",
            ));
        };
        let chosen: Vec<&breed::Individual> = breed::selection::rank(&cp.population)
            .into_iter()
            .take(top)
            .collect();
        let objects = export::drop_individuals(&run, &chosen, fps)?;
        let extent = objects
            .iter()
            .map(|o| {
                let p = o.positions(0);
                let c = o.centre(0);
                p.iter().map(|x| (x - c).norm()).fold(0.0, f64::max) * 2.0
            })
            .fold(0.0, f64::max);
        let name = input
            .file_name()
            .map_or("run".to_string(), |n| n.to_string_lossy().into_owned());
        let spacing = GRID_SPACING_CHORDS * extent;
        let mut clip = export::side_by_side(&name, objects, fps, spacing)?;
        clip.aero_law = run.proto.aero.law.as_str().to_string();
        if let (Some(like), Some(example)) = (&run.settings().like, run.example()) {
            let size = like.size_m.unwrap_or(extent);
            let mut o = example_object(&example, size, &clip, spacing)?;
            if let Some(class) = like.class {
                o.label = class.to_string();
            }
            clip.objects.insert(0, o);
            clip.validate_read()?;
        }
        return Ok(Preview {
            clip,
            grid: true,
            classified: Vec::new(),
            goals: None,
        });
    }
    if input.join("summary.toml").is_file() {
        let mut preview = plain(export::from_scene_dir(input, fps)?);
        preview.goals = scene_goals(input)?;
        return Ok(preview);
    }
    Err(ExportError::input(
        input,
        "neither a breeding run (no run.toml) nor a scene output directory (no summary.toml)",
    ))
}

/// The goals a directed scene's run recorded beside its summary
/// ([`GOALS_FILE`]), if it has any.
fn scene_goals(dir: &Path) -> Result<Option<GoalsRecord>, ExportError> {
    let path = dir.join(GOALS_FILE);
    if !path.is_file() {
        return Ok(None);
    }
    let text = std::fs::read_to_string(&path)
        .map_err(|e| ExportError::input(&path, format!("cannot read: {e}")))?;
    let record: GoalsRecord = serde_json::from_str(&text)
        .map_err(|e| ExportError::input(&path, format!("not a scene's goals record: {e}")))?;
    Ok(Some(record))
}

/// The example fall of a `--like` run as one more object of the row of its
/// bred leaves `row` (laid `spacing` apart): its plate or marker
/// ([`from_record`]) on the row's frames, one place left of the first
/// leaf, released at the leaves' height. A real fall filmed over a metre
/// ends long before a 10 s drop: it lives its own span and is then gone,
/// rather than hang where the camera last saw it.
fn example_object(
    example: &Trajectory,
    size: f64,
    row: &Clip,
    spacing: f64,
) -> Result<ClipObject, ExportError> {
    let played = from_record("example", example, size, Some(row.fps))?;
    let mut o = played
        .objects
        .into_iter()
        .next()
        .expect("from_record gives the fall first");
    if let Motion::Rigid {
        translation,
        rotation,
        ..
    } = &mut o.motion
    {
        translation.truncate(row.frames);
        rotation.truncate(row.frames);
    }
    let first = row.objects.first().map_or(V3::zeros(), |l| l.centre(0));
    let n = row.objects.len() as f64;
    let slot = V3::new(-(n + 1.0) / 2.0 * spacing, 0.0, first.z);
    o.translate(slot - o.centre(0));
    Ok(o)
}

/// [`load`] of an animation file.
fn load_file(input: &Path, file: FileOptions<'_>) -> Result<Preview, ExportError> {
    let Some(format) = AnimationFormat::of(input) else {
        return Err(ExportError::input(
            input,
            "not an animation file (preview reads a breeding run directory, a scene output directory, or a .glb, .gltf, .usd, .usda, .usdc, .usdz or .abc file)",
        ));
    };
    if let Some(scale) = file.scale {
        if format != AnimationFormat::Alembic {
            return Err(ExportError::input(
                input,
                format!(
                    "{}: applies to an Alembic archive, which carries no unit; glTF is in metres, and USD says its metersPerUnit",
                    Setting::Scale.set(scale)
                ),
            ));
        }
        if !(scale > 0.0 && scale.is_finite()) {
            return Err(ExportError::input(
                input,
                format!(
                    "{} must be a positive number of metres per unit, got {scale}",
                    Setting::Scale
                ),
            ));
        }
    }
    // Classified as `classify` reads the file, at its own keys, before any
    // resampling for the page: a .glb's page is sampled from 0 at 30 fps,
    // which can turn a 24 fps tumble into another class.
    let default = ReadPolicy::default();
    let policy = file.policy.unwrap_or(&default);
    let mut keys = fall::read_clip_in(input, file.animation, policy)?;
    if let Some(scale) = file.scale {
        keys.objects.iter_mut().for_each(|o| o.scale(scale));
    }
    let classified = label_falls(&mut keys);
    let glb = input
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("glb"));
    let clip = if glb {
        // The same nodes in the same order, on the page's grid.
        let mut page = gltf::from_glb(input, file.fps, file.animation)?;
        for &k in &classified {
            let from = &keys.objects[k];
            if let Some(to) = page.objects.get_mut(k).filter(|to| to.name == from.name) {
                to.label.clone_from(&from.label);
                to.regime.clone_from(&from.regime);
            }
        }
        page
    } else if let Some(fps) = file.fps {
        keys.resampled(fps)
    } else {
        keys
    };
    Ok(Preview {
        clip,
        grid: false,
        classified,
        goals: None,
    })
}

/// Labels each object of `clip` that falls (it has a surface and moves,
/// or is a particle) and carries no label of its own with the class and
/// regime `classify` gives its fall ([`fall::classify_objects`], sized as
/// `classify` sizes a file's fall), so that a client's cache shows which
/// leaves float, spin or lilt; returns the indices of those it labelled.
/// Leafmagic's own files keep their labels (a bred leaf's class), and
/// ropes and rigid props are left as they are.
pub fn label_falls(clip: &mut Clip) -> Vec<usize> {
    let labels = fall::classify_objects(clip, None, |o| o.label.is_empty());
    let mut labelled = Vec::new();
    for (k, (o, label)) in clip.objects.iter_mut().zip(labels).enumerate() {
        if let Some(c) = label {
            (o.label, o.regime) = (c.class.to_string(), c.regime.to_string());
            labelled.push(k);
        }
    }
    labelled
}

/// Several inputs' previews on one page, to compare their falls by eye:
/// each `(name, preview)` keeps its objects (without a record's still
/// path, which the side-by-side view would leave behind), named
/// `name/object` (a record's fall keeps its own name), its first object
/// released at the page's origin height in a place of its own along x,
/// `GRID_SPACING_CHORDS` of the largest chord apart beyond its own width;
/// as a grid, so every fall is labelled and can be drawn at one height
/// with how far it fell and drifted. All are played at `fps`, or at the
/// highest of their own rates (at most [`MAX_RECORD_FPS`]); one that ends
/// before the others is then gone.
pub fn together(parts: Vec<(String, Preview)>, fps: Option<f64>) -> Result<Preview, ExportError> {
    let fps = fps.unwrap_or_else(|| {
        parts
            .iter()
            .map(|(_, p)| p.clip.fps)
            .fold(0.0, f64::max)
            .min(MAX_RECORD_FPS)
    });
    let mut placed: Vec<(Vec<ClipObject>, Vec<bool>)> = Vec::new();
    let (mut widest, mut chord) = (0.0f64, 0.0f64);
    for (name, part) in parts {
        let clip = if part.clip.fps == fps {
            part.clip
        } else {
            part.clip.resampled(fps)
        };
        let mut was_labelled = vec![false; clip.objects.len()];
        for &k in &part.classified {
            was_labelled[k] = true;
        }
        let mut objects = Vec::new();
        let mut labelled = Vec::new();
        for (mut o, was) in clip.objects.into_iter().zip(was_labelled) {
            if o.kind == TRAIL {
                continue;
            }
            if o.name != name {
                o.name = format!("{name}/{}", o.name);
            }
            let p = o.positions(0);
            let c = p.iter().sum::<V3>() / p.len().max(1) as f64;
            chord = chord.max(2.0 * p.iter().map(|x| (x - c).norm()).fold(0.0, f64::max));
            labelled.push(was);
            objects.push(o);
        }
        let Some(anchor) = objects.first().map(|o| o.centre(0)) else {
            return Err(ExportError::Data(format!("{name}: nothing in it to play")));
        };
        for o in &mut objects {
            o.translate(-anchor);
        }
        let xs = objects.iter().map(|o| o.centre(0).x);
        let (lo, hi) = xs.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| {
            (lo.min(x), hi.max(x))
        });
        widest = widest.max(hi - lo);
        placed.push((objects, labelled));
    }
    let spacing = widest + GRID_SPACING_CHORDS * chord;
    let m = placed.len() as f64;
    let mut objects = Vec::new();
    let mut classified = Vec::new();
    for (i, (part, labelled)) in placed.into_iter().enumerate() {
        let slot = Vector3::new((i as f64 - (m - 1.0) / 2.0) * spacing, 0.0, 0.0);
        for (mut o, was) in part.into_iter().zip(labelled) {
            o.translate(slot);
            if was {
                classified.push(objects.len());
            }
            objects.push(o);
        }
    }
    let frames = objects
        .iter()
        .map(|o| o.first_frame + o.frame_count())
        .max()
        .unwrap_or(1);
    let clip = Clip::bare("compare", fps, frames, objects);
    clip.validate_read()?;
    Ok(Preview {
        clip,
        grid: true,
        classified,
        goals: None,
    })
}

/// Most frames a recorded fall's page is sampled at per second when its
/// own rate is higher (a 240 Hz simulation record): twice what a screen
/// shows, and fine enough that a plate tumbling at 20 rad/s (MuJoCo's
/// tumbling card turns at 15) turns under 10° a frame.
pub const MAX_RECORD_FPS: f64 = 120.0;

/// A recorded fall (a CSV record: its centre and, where it has one, its
/// orientation) as a clip of one object named `name`, for `preview`:
///
/// - with an orientation, the plate it records: a square in the body's
///   xy-plane (body z its normal, x its long axis, as
///   [`crate::motion::trajectory`] defines them) whose diagonal is
///   `chord`, the chord the fall was classified with;
/// - without one (a path from video), a marker, three crossed lines of
///   length `chord` that say where it is and nothing of its attitude;
/// - and its whole path, a still line drawn at every time ([`TRAIL`]).
///
/// Sampled at `fps`, or at the record's own rate (its median sample
/// interval, to four significant digits, at most [`MAX_RECORD_FPS`]), from
/// its first sample, the page's t = 0. Positions and orientations are
/// interpolated as [`Trajectory::resampled`] interpolates them.
pub fn from_record(
    name: &str,
    trajectory: &Trajectory,
    chord: f64,
    fps: Option<f64>,
) -> Result<Clip, ExportError> {
    let n = trajectory.time.len();
    if n < 2 {
        return Err(ExportError::Data(format!(
            "{name}: {n} sample{}: a fall to play needs two",
            if n == 1 { "" } else { "s" }
        )));
    }
    let fps = fps.unwrap_or_else(|| {
        let mut gaps: Vec<f64> = trajectory.time.windows(2).map(|w| w[1] - w[0]).collect();
        gaps.sort_by(f64::total_cmp);
        // To four significant digits: times written to the microsecond
        // make a 98 fps camera's rate 98.0008.
        let rate = 1.0 / gaps[gaps.len() / 2];
        let unit = 10f64.powi(rate.log10().floor() as i32 - 3);
        ((rate / unit).round() * unit).min(MAX_RECORD_FPS)
    });
    let r = trajectory.resampled(fps);
    let frames = r.time.len();
    let object = if trajectory.has_orientation() {
        // Corners on the body axes' diagonals: a square of diagonal `chord`.
        let side = 0.5 * chord * std::f64::consts::FRAC_1_SQRT_2;
        let local = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
            .map(|(x, y)| Vector3::new(x * side, y * side, 0.0))
            .to_vec();
        ClipObject {
            name: name.to_string(),
            kind: "leaf".to_string(),
            label: String::new(),
            regime: String::new(),
            features: Vec::new(),
            triangles: vec![[0, 1, 2], [0, 2, 3]],
            segments: Vec::new(),
            body: None,
            render: None,
            motion: Motion::Rigid {
                local,
                translation: r.position.clone(),
                rotation: r.orientation.clone(),
            },
            first_frame: 0,
        }
    } else {
        ClipObject::marker(name.to_string(), MARKER_KIND, chord, r.position.clone())
    };
    // The whole path as a still trail beside it, so that the fall shows
    // against something when the camera follows it (a record has no
    // ground): at most TRAIL_POINTS points of the record's own samples.
    let step = n.div_ceil(TRAIL_POINTS).max(1);
    let mut points: Vec<Vector3<f64>> = trajectory.position.iter().step_by(step).copied().collect();
    if (n - 1) % step != 0 {
        points.push(trajectory.position[n - 1]);
    }
    let trail = ClipObject {
        name: format!("{name} path"),
        kind: TRAIL.to_string(),
        label: String::new(),
        regime: String::new(),
        features: Vec::new(),
        triangles: Vec::new(),
        segments: (1..points.len() as u32).map(|i| [i - 1, i]).collect(),
        body: None,
        render: None,
        motion: Motion::Deforming {
            frames: vec![points],
        },
        first_frame: 0,
    };
    let clip = Clip::bare(name, fps, frames, vec![object, trail]);
    clip.validate_read()?;
    Ok(clip)
}

/// The kind of a still object the page draws at every time from its one
/// frame: a recorded fall's path ([`from_record`]).
pub const TRAIL: &str = "path";

/// Most points of a recorded fall's drawn path.
const TRAIL_POINTS: usize = 2000;

/// The page's data as JSON: names, labels, colours, topology, and every
/// object's vertex positions per frame of its life (from clip frame
/// `first`) as base64 float32; of a marker, its centre and its size.
pub fn data_json(clip: &Clip, grid: bool) -> serde_json::Value {
    data_json_with(clip, grid, None)
}

/// [`data_json`] with a directed scene's `goals` and verdicts, which the
/// viewer draws (regions, boxes, marks) and shows on each leaf.
pub fn data_json_with(clip: &Clip, grid: bool, goals: Option<&GoalsRecord>) -> serde_json::Value {
    let b64 = base64::engine::general_purpose::STANDARD;
    let objects: Vec<serde_json::Value> = clip
        .objects
        .iter()
        .map(|o| {
            let n = page_vertices(o);
            let mut bytes = Vec::with_capacity(o.frame_count() * n * 12);
            for k in 0..o.frame_count() {
                let points = if o.is_marker() {
                    vec![o.centre(k)]
                } else {
                    o.positions(k)
                };
                for p in points {
                    for c in [p.x, p.y, p.z] {
                        bytes.extend_from_slice(&(c as f32).to_le_bytes());
                    }
                }
            }
            let mut object = json!({
                "name": o.name,
                "kind": o.kind,
                "label": o.label,
                "color": colour(o),
                "n": n,
                "first": o.first_frame,
                "still": o.kind == TRAIL,
                "tris": o.triangles.iter().flatten().collect::<Vec<_>>(),
                "segs": o.segments.iter().flatten().collect::<Vec<_>>(),
                "pos": b64.encode(&bytes),
            });
            if o.is_marker() {
                // Its centre per frame, and its size: the viewer draws the
                // three crossed lines (a particle cache's thousands of
                // markers take a sixth of the page).
                object["marker"] = json!(fall::chord(&o.positions(0)));
                object["segs"] = json!([]);
            }
            object
        })
        .collect();
    json!({
        "name": clip.name,
        "fps": clip.fps,
        "frames": clip.frames,
        "grid": grid,
        "ground": clip.ground,
        "wind": clip.wind,
        "goals": goals.map_or(&[][..], |g| &g.goals[..]),
        "objects": objects,
    })
}

/// How many vertices per frame the page holds of `o`: one for a marker
/// (its centre; [`data_json`]), else all.
fn page_vertices(o: &ClipObject) -> usize {
    if o.is_marker() { 1 } else { o.vertex_count() }
}

/// Refuses a clip whose page would hold a number that is not finite or a
/// vertex past [`fall::MAX_COORDINATE_M`]: what `describe` refuses of the
/// same file ([`fall::far_out`]). JSON has no NaN (serde writes `null`)
/// and float32 turns 1e39 into infinity, so such a page would draw
/// nothing where the file is at fault; the error names the object, the
/// vertex and the key.
fn finite_in_page(clip: &Clip) -> Result<(), ExportError> {
    let refuse = |m: String| Err(ExportError::Data(format!("{}: {m}", clip.name)));
    if clip.ground.is_some_and(|g| !g.is_finite()) {
        return refuse(format!("its ground height {:?} is not finite", clip.ground));
    }
    for o in &clip.objects {
        if let Err(e) = fall::far_out(o) {
            return refuse(e);
        }
    }
    for w in &clip.wind {
        let numbers = w.point.iter().chain(&w.direction).chain([&w.strength]);
        if numbers.into_iter().any(|x| !x.is_finite()) {
            return refuse(format!(
                "its {} wind primitive has a number that is not finite",
                w.kind
            ));
        }
    }
    Ok(())
}

/// Refuses goals with a number that is not finite, which JSON would write
/// as `null` and the page would draw nowhere.
fn goals_finite(name: &str, record: &GoalsRecord) -> Result<(), ExportError> {
    for g in &record.goals {
        let numbers = g
            .polygon
            .iter()
            .flatten()
            .flatten()
            .chain(g.min.iter().flatten())
            .chain(g.max.iter().flatten())
            .chain(g.point.iter().flatten())
            .chain(g.tolerance.iter())
            .chain(g.ground.iter())
            .chain([&g.from, &g.to, &g.met_fraction, &g.mean_distance])
            .chain(g.leaves.iter().map(|l| &l.distance));
        if numbers.into_iter().any(|x| !x.is_finite()) {
            return Err(ExportError::Data(format!(
                "{name}: goal '{}' has a number that is not finite",
                g.name
            )));
        }
    }
    Ok(())
}

/// JSON made inert inside the page's `<script type="application/json">`
/// element: `<`, `>` and `&` written as `\u003c`, `\u003e`, `\u0026`, so
/// that no name can end the element (`</script>`), open a comment (`<!--`,
/// which makes the HTML tokenizer swallow the scripts after it) or start
/// a tag; U+2028 and U+2029 as escapes too, since older JavaScript reads
/// them as line ends. Outside strings JSON has none of these characters,
/// so the data parses to the same values.
fn inert_json(json: &str) -> String {
    let mut out = String::with_capacity(json.len());
    for c in json.chars() {
        match c {
            '<' => out.push_str("\\u003c"),
            '>' => out.push_str("\\u003e"),
            '&' => out.push_str("\\u0026"),
            '\u{2028}' => out.push_str("\\u2028"),
            '\u{2029}' => out.push_str("\\u2029"),
            c => out.push(c),
        }
    }
    out
}

/// `s` as HTML text: markup characters as entities, and the line and
/// paragraph separators as character references, as in the data.
fn escape_html(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
        .replace('\u{2028}', "&#x2028;")
        .replace('\u{2029}', "&#x2029;")
}

/// Most characters of page data a browser is asked to hold: the viewer
/// reads the data as one JavaScript string, and Chrome's V8 holds none
/// over 2^29 − 24 characters (about 537 million; Firefox about a billion).
pub const MAX_PAGE_DATA_CHARS: usize = 500_000_000;

/// An upper bound on the characters of `clip`'s page data
/// ([`data_json`]): each object's positions as base64 (4 characters per 3
/// bytes of float32), at most 12 characters per index of its topology
/// (ten digits and a comma), and 512 for its name, label and keys.
pub fn page_data_chars(clip: &Clip) -> usize {
    clip.objects
        .iter()
        .map(|o| {
            let bytes = o.frame_count() * page_vertices(o) * 12;
            let indices = 3 * o.triangles.len() + 2 * o.segments.len();
            4 * bytes.div_ceil(3) + 12 * indices + 512 + 2 * (o.name.len() + o.label.len())
        })
        .sum::<usize>()
        + 4096
        + clip.wind.len() * 512
}

/// Refuses a clip whose page no browser could open
/// ([`MAX_PAGE_DATA_CHARS`]), saying how big it would be and at what frame
/// rate it would fit, before anything is built.
fn fits_a_browser(clip: &Clip) -> Result<(), ExportError> {
    let chars = page_data_chars(clip);
    if chars <= MAX_PAGE_DATA_CHARS {
        return Ok(());
    }
    // The positions dominate and scale with the frame rate.
    let fits = (clip.fps * MAX_PAGE_DATA_CHARS as f64 / chars as f64 * 0.95).floor();
    Err(ExportError::Data(format!(
        "{}: its page would hold about {:.0} MB of data ({} objects, {} frames at {} fps), more than a browser holds in one page ({:.0} MB; Chrome's largest string): {}",
        clip.name,
        chars as f64 / 1e6,
        clip.objects.len(),
        clip.frames,
        clip.fps,
        MAX_PAGE_DATA_CHARS as f64 / 1e6,
        if fits >= 1.0 {
            format!(
                "pass {} or lower, or export it ({} abc, usd) for a client",
                Setting::Fps.set(fits),
                Setting::Format
            )
        } else {
            format!(
                "export it instead ({} abc, usd) for a client",
                Setting::Format
            )
        }
    )))
}

/// The self-contained HTML page for `clip` (`grid`: label every object, as
/// for a grid of bred leaves). Its objects may live a part of it
/// ([`Clip::validate_read`]): the page shows each over its own life.
pub fn html(clip: &Clip, grid: bool) -> Result<String, ExportError> {
    html_with(clip, grid, None)
}

/// [`html`] with a directed scene's `goals` drawn ([`data_json_with`]).
pub fn html_with(
    clip: &Clip,
    grid: bool,
    goals: Option<&GoalsRecord>,
) -> Result<String, ExportError> {
    clip.validate_read()?;
    if let Some(g) = goals {
        goals_finite(&clip.name, g)?;
    }
    finite_in_page(clip)?;
    fits_a_browser(clip)?;
    let data = inert_json(
        &serde_json::to_string(&data_json_with(clip, grid, goals))
            .map_err(|e| ExportError::Data(format!("cannot serialise the page data: {e}")))?,
    );
    // Split the template rather than search-and-replace in the result, so
    // nothing in the data (an object's name) can be taken for a placeholder.
    let (head, rest) = PAGE
        .split_once("/*DATA*/")
        .expect("page.html has a /*DATA*/ placeholder");
    let (middle, tail) = rest
        .split_once("/*VIEWER*/")
        .expect("page.html has a /*VIEWER*/ placeholder");
    // The title says the law the falls were simulated under, when known.
    let title = match clip.aero_law.as_str() {
        "" => clip.name.clone(),
        law => format!("{} ({law} aerodynamics)", clip.name),
    };
    let head = head.replace("{{TITLE}}", &escape_html(&title));
    Ok([head.as_str(), &data, middle, VIEWER, tail].concat())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn clip() -> Clip {
        Clip {
            name: "t</script>".into(),
            fps: 10.0,
            frames: 2,
            objects: vec![ClipObject {
                first_frame: 0,
                name: "o".into(),
                kind: "leaf".into(),
                label: "floater".into(),
                regime: String::new(),
                features: vec![],
                triangles: vec![[0, 1, 2]],
                segments: vec![],
                body: None,
                render: None,
                motion: Motion::Deforming {
                    frames: vec![
                        vec![Vector3::zeros(), Vector3::x(), Vector3::y()],
                        vec![Vector3::z(), Vector3::x(), Vector3::y()],
                    ],
                },
            }],
            ground: Some(0.0),
            wind: vec![],
            aero_law: String::new(),
            warnings: vec![],
        }
    }

    #[test]
    fn page_is_self_contained_and_escapes_names() {
        let page = html(&clip(), true).unwrap();
        assert!(!page.contains("/*DATA*/") && !page.contains("/*VIEWER*/"));
        assert!(
            !page.contains("http://") && !page.contains("https://"),
            "no network references"
        );
        assert!(!page.contains("<script src"), "no external scripts");
        // The name's "</script>" must not close the data element.
        assert_eq!(page.matches("</script>").count(), 2);
        assert!(page.contains("t&lt;/script&gt; · leafmagic"));
    }

    /// Names that would end the data element, open a comment that
    /// swallows the viewer, start a tag, break a string or a line: the
    /// page keeps exactly its own tags, and its data parses back to the
    /// very names.
    #[test]
    fn no_name_can_change_the_page() {
        let names = [
            "<!--<script>",
            "</script><script>alert(1)</script>",
            "a\"b'c",
            "line\u{2028}sep\u{2029}end",
            "&amp; <b>",
            "<!-- -->",
        ];
        for name in names {
            let mut c = clip();
            c.name = name.into();
            c.objects[0].name = name.into();
            c.objects[0].label = name.into();
            let page = html(&c, true).unwrap();
            let template = html(&clip(), true).unwrap();
            for tag in ["<script", "</script>", "<!--", "-->"] {
                assert_eq!(
                    page.matches(tag).count(),
                    template.matches(tag).count(),
                    "{name:?}: {tag}"
                );
            }
            assert!(!page.contains('\u{2028}') && !page.contains('\u{2029}'));
            let open = "id=\"leafmagic-data\">";
            let start = page.find(open).unwrap() + open.len();
            let end = start + page[start..].find("</script>").unwrap();
            let data: serde_json::Value = serde_json::from_str(&page[start..end]).unwrap();
            assert_eq!(data["name"], name);
            assert_eq!(data["objects"][0]["name"], name);
            assert_eq!(data["objects"][0]["label"], name);
        }
    }

    /// A page holds only finite numbers: a NaN or far-out vertex is
    /// refused with the object named, as `describe` refuses it.
    #[test]
    fn a_page_with_a_number_that_is_not_finite_is_refused() {
        for bad in [f64::NAN, f64::INFINITY, 1e39, -2e6] {
            let mut c = clip();
            if let Motion::Deforming { frames } = &mut c.objects[0].motion {
                frames[1][2].y = bad;
            }
            let e = html(&c, false).unwrap_err().to_string();
            assert!(
                e.contains("object o:") || e.contains("object `o`: vertex 2 at key 1"),
                "{bad}: {e}"
            );
        }
        let mut c = clip();
        c.ground = Some(f64::NAN);
        assert!(html(&c, false).unwrap_err().to_string().contains("ground"));
    }

    #[test]
    fn positions_are_float32_frame_by_frame() {
        let d = data_json(&clip(), false);
        let b = base64::engine::general_purpose::STANDARD
            .decode(d["objects"][0]["pos"].as_str().unwrap())
            .unwrap();
        assert_eq!(b.len(), 2 * 3 * 3 * 4);
        let f: Vec<f32> = b
            .chunks(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect();
        assert_eq!(&f[..3], &[0.0, 0.0, 0.0]);
        assert_eq!(&f[9..12], &[0.0, 0.0, 1.0]);
    }

    #[test]
    fn the_page_data_estimate_bounds_the_page_and_a_page_too_big_is_refused() {
        // A hundred deforming leaves of seven vertices over 301 frames.
        let leaf = |k: usize| {
            let frames = (0..301)
                .map(|f| {
                    (0..7)
                        .map(|i| V3::new(k as f64, i as f64 * 0.01, -(f as f64) * 0.003))
                        .collect()
                })
                .collect();
            ClipObject {
                label: "floater".into(),
                ..ClipObject::read_mesh(
                    format!("leaf-{k:03}"),
                    vec![[0, 1, 2], [2, 3, 4], [4, 5, 6]],
                    frames,
                )
            }
        };
        // The estimate is at least the page's data, and over it by less
        // than `1 / over` of it.
        let bounds = |clip: &Clip, over: usize| {
            let data = serde_json::to_string(&data_json(clip, false))
                .unwrap()
                .len();
            let estimate = page_data_chars(clip);
            assert!(
                estimate >= data && estimate < data + data / over,
                "{estimate} against {data}"
            );
        };
        let clip = Clip::read("hundred", 30.0, 301, (0..100).map(leaf).collect()).unwrap();
        bounds(&clip, 20);
        assert!(html(&clip, false).is_ok());
        // A thousand particles over 240 frames: a marker's centre per frame.
        let particles: Vec<ClipObject> = (0..1000)
            .map(|k| {
                let path = (0..240).map(|f| V3::new(k as f64, 0.0, -0.01 * f as f64));
                ClipObject::marker(
                    format!("leaves/{k}"),
                    crate::formats::clip::POINT_KIND,
                    0.04,
                    path.collect(),
                )
            })
            .collect();
        // Within a fifth: the 512 characters kept per object for its name
        // and keys weigh more beside 240 centres than beside a leaf's frames.
        bounds(&Clip::read("cache", 24.0, 240, particles).unwrap(), 5);
        // A rigid mesh of a million vertices over 100 frames at 30 fps:
        // 1.2 GB of float32, 1.6 billion characters of base64. Refused
        // before anything is built, with the rate that would fit.
        let mut big = ClipObject::read_mesh("scan".into(), vec![[0, 1, 2]], Vec::new());
        big.motion = Motion::Rigid {
            local: vec![V3::zeros(); 1_000_000],
            translation: vec![V3::zeros(); 100],
            rotation: vec![nalgebra::UnitQuaternion::identity(); 100],
        };
        let big = Clip::read("scan", 30.0, 100, vec![big]).unwrap();
        assert!(page_data_chars(&big) > 1_600_000_000);
        let e = html(&big, false).unwrap_err().to_string();
        assert!(
            e.contains("more than a browser holds") && e.contains("fps = 8 or lower"),
            "{e}"
        );
    }
}
