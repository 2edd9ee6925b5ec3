//! The HTML previewer: one self-contained page that plays a [`Clip`] in 3-D
//! with no network access. The page is `page.html` with the viewer
//! (`viewer.js`, plain JavaScript written for leafmagic: a small WebGL
//! renderer and a Canvas 2D fallback) and the data inlined. Vertex positions
//! go in as base64 little-endian float32 arrays, frame after frame, which
//! keeps 100 leaves × 10 s × 30 fps near 3.4 MB.

use crate::breed::{self, Run};
use crate::output::export::{self, Clip, DEFAULT_FPS, ExportError, glb::colour};
use base64::Engine as _;
use serde_json::json;
use std::path::Path;

/// The page template; `/*DATA*/` and `/*VIEWER*/` are replaced.
const PAGE: &str = include_str!("page.html");
/// The viewer script.
const VIEWER: &str = include_str!("viewer.js");

/// Bred leaves are laid side by side this many of their largest extents
/// apart, so that drifting falls rarely overlap.
pub const GRID_SPACING_CHORDS: f64 = 3.0;

/// The clip to preview from `input` and whether it is a grid of bred leaves:
///
/// - a breeding run directory (`run.toml`): the `top` best of the last
///   generation, re-dropped as breeding dropped them
///   ([`export::drop_individuals`]), side by side with their classes;
/// - a scene output directory (`summary.toml`), see [`export::from_scene_dir`];
/// - a `.glb` file, see [`export::from_glb`].
///
/// `fps` defaults to [`DEFAULT_FPS`] (or a leafmagic `.glb`'s own rate);
/// `animation` names the take of a `.glb` that holds several.
pub fn load(
    input: &Path,
    top: usize,
    fps: Option<f64>,
    animation: Option<&str>,
) -> Result<(Clip, bool), ExportError> {
    if !input.exists() {
        return Err(ExportError::input(input, "no such file or directory"));
    }
    if input.is_file() {
        let is_glb = input
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("glb"));
        if !is_glb {
            return Err(ExportError::input(
                input,
                "not a .glb file (preview reads a breeding run directory, a scene output directory or a .glb file)",
            ));
        }
        return Ok((export::from_glb(input, fps, animation)?, false));
    }
    if let Some(want) = animation {
        return Err(ExportError::input(
            input,
            format!("--animation {want}: picks one of a .glb file's animations, not a directory's"),
        ));
    }
    let fps = fps.unwrap_or(DEFAULT_FPS);
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
        let clip = export::side_by_side(&name, objects, fps, GRID_SPACING_CHORDS * extent)?;
        return Ok((clip, true));
    }
    if input.join("summary.toml").is_file() {
        return Ok((export::from_scene_dir(input, fps)?, false));
    }
    Err(ExportError::input(
        input,
        "neither a breeding run (no run.toml) nor a scene output directory (no summary.toml)",
    ))
}

/// The page's data as JSON: names, labels, colours, topology, and every
/// object's vertex positions per frame as base64 float32.
pub fn data_json(clip: &Clip, grid: bool) -> serde_json::Value {
    let b64 = base64::engine::general_purpose::STANDARD;
    let objects: Vec<serde_json::Value> = clip
        .objects
        .iter()
        .map(|o| {
            let mut bytes = Vec::with_capacity(clip.frames * o.vertex_count() * 12);
            for k in 0..clip.frames {
                for p in o.positions(k) {
                    for c in [p.x, p.y, p.z] {
                        bytes.extend_from_slice(&(c as f32).to_le_bytes());
                    }
                }
            }
            json!({
                "name": o.name,
                "kind": o.kind,
                "label": o.label,
                "color": colour(o),
                "n": o.vertex_count(),
                "tris": o.triangles.iter().flatten().collect::<Vec<_>>(),
                "segs": o.segments.iter().flatten().collect::<Vec<_>>(),
                "pos": b64.encode(&bytes),
            })
        })
        .collect();
    json!({
        "name": clip.name,
        "fps": clip.fps,
        "frames": clip.frames,
        "grid": grid,
        "ground": clip.ground,
        "wind": clip.wind,
        "objects": objects,
    })
}

fn escape_html(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// The self-contained HTML page for `clip` (`grid`: label every object, as
/// for a grid of bred leaves).
pub fn html(clip: &Clip, grid: bool) -> Result<String, ExportError> {
    clip.validate()?;
    let data = serde_json::to_string(&data_json(clip, grid))
        .map_err(|e| ExportError::Data(format!("cannot serialise the page data: {e}")))?
        // Inside <script>, "</" could end the element; "<\/" means the same in JSON.
        .replace("</", "<\\/");
    // Split the template rather than search-and-replace in the result, so
    // nothing in the data (an object's name) can be taken for a placeholder.
    let (head, rest) = PAGE
        .split_once("/*DATA*/")
        .expect("page.html has a /*DATA*/ placeholder");
    let (middle, tail) = rest
        .split_once("/*VIEWER*/")
        .expect("page.html has a /*VIEWER*/ placeholder");
    let head = head.replace("{{TITLE}}", &escape_html(&clip.name));
    Ok([head.as_str(), &data, middle, VIEWER, tail].concat())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::export::{ClipObject, Motion};
    use nalgebra::Vector3;

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
}
