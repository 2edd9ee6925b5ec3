//! PC2 point caches (the 3ds Max "Point Cache 2" format, read by Blender's
//! Mesh Cache modifier) and the rest-pose OBJ meshes they apply to.
//!
//! PC2 layout, all little-endian:
//!
//! ```text
//! char[12]  "POINTCACHE2\0"
//! int32     version = 1
//! int32     numPoints
//! float32   startFrame
//! float32   sampleRate      (frames between samples: 1 = every frame)
//! int32     numSamples
//! numSamples × numPoints × float32[3]   x, y, z
//! ```
//!
//! A cache only stores positions; the mesh comes from the OBJ, whose
//! vertices are written in the same order (vertex i of the OBJ is point i of
//! the cache) and at frame 0's positions, with the same f32 values. Both
//! keep the simulator's axes (z up), so import the OBJ into Blender with
//! Up = Z, Forward = Y, and keep the Mesh Cache modifier's default axes.

use crate::formats::clip::{Clip, ClipObject};
use crate::formats::error::ExportError;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// The 12-byte signature a PC2 file starts with.
pub const SIGNATURE: &[u8; 12] = b"POINTCACHE2\0";

/// Bytes before the first sample.
pub const HEADER_BYTES: usize = 32;

/// The PC2 bytes of per-sample point positions `samples[k][i]` (already in
/// f32), with the first sample at `start_frame` and `sample_rate` frames
/// between samples.
pub fn pc2_bytes(samples: &[Vec<[f32; 3]>], start_frame: f32, sample_rate: f32) -> Vec<u8> {
    let points = samples.first().map_or(0, Vec::len);
    let mut out = Vec::with_capacity(HEADER_BYTES + samples.len() * points * 12);
    out.extend_from_slice(SIGNATURE);
    out.extend_from_slice(&1i32.to_le_bytes());
    out.extend_from_slice(&(points as i32).to_le_bytes());
    out.extend_from_slice(&start_frame.to_le_bytes());
    out.extend_from_slice(&sample_rate.to_le_bytes());
    out.extend_from_slice(&(samples.len() as i32).to_le_bytes());
    for s in samples {
        for p in s {
            for c in p {
                out.extend_from_slice(&c.to_le_bytes());
            }
        }
    }
    out
}

/// The frame rate of the scene a cache is played in unless asked otherwise:
/// 24 fps, the default of Blender, Maya and Houdini.
pub const DEFAULT_HOST_FPS: f64 = 24.0;

/// One object's shown vertex positions per frame (the render mesh's, if it
/// has one), f32, simulator axes.
pub fn object_samples(clip: &Clip, o: &ClipObject) -> Vec<Vec<[f32; 3]>> {
    (0..clip.frames)
        .map(|k| {
            o.shown_positions(k)
                .iter()
                .map(|v| [v.x as f32, v.y as f32, v.z as f32])
                .collect()
        })
        .collect()
}

/// The OBJ text of an object at its first sample: `v` lines in cache order
/// (f32 values printed in their shortest round-trip form, so they read back
/// bit for bit), `vt` lines (one UV per vertex, see
/// [`crate::formats::clip::frame::outline_uvs`], or the render mesh's own), then faces
/// (`f v/vt`, 1-based) or lines (`l`).
pub fn obj_text(o: &ClipObject, first: &[[f32; 3]]) -> String {
    let mut s = format!(
        "# leafmagic {}: {} ({}), vertex order = the .pc2 point order\no {}\n",
        env!("CARGO_PKG_VERSION"),
        o.name,
        o.kind,
        o.name
    );
    for p in first {
        let _ = writeln!(s, "v {} {} {}", p[0], p[1], p[2]);
    }
    let (triangles, uvs) = match &o.render {
        Some(r) => (r.triangles.clone(), r.uvs.clone()),
        None => {
            let body = o.body_or_first_frame();
            (
                o.triangles.clone(),
                crate::formats::clip::dress::outline_uvs(&body.rest),
            )
        }
    };
    if !triangles.is_empty() {
        for t in &uvs {
            let _ = writeln!(s, "vt {} {}", t[0] as f32, t[1] as f32);
        }
    }
    for t in &triangles {
        let [a, b, c] = t.map(|i| i + 1);
        let _ = writeln!(s, "f {a}/{a} {b}/{b} {c}/{c}");
    }
    for l in &o.segments {
        let _ = writeln!(s, "l {} {}", l[0] + 1, l[1] + 1);
    }
    s
}

/// Writes `<object>.pc2` and `<object>.obj` for every object of `clip` into
/// `dir` (created if missing), atomically; returns the paths written. The
/// cache holds one sample per frame of a scene at `host_fps` from frame 0
/// (sampleRate 1): a clip at another rate is resampled onto the host's
/// frames first ([`Clip::resampled`]). Blender's Mesh Cache modifier, in
/// its default Frame mode, reads sample n at frame n whatever the header
/// says (measured with Blender's Python module), so only a cache on the
/// host's own frames plays in real time there without settings.
pub fn write_pc2(clip: &Clip, dir: &Path, host_fps: f64) -> Result<Vec<PathBuf>, ExportError> {
    clip.validate()?;
    if !(host_fps > 0.0 && host_fps.is_finite()) {
        return Err(ExportError::Data(format!(
            "the host frame rate must be positive, got {host_fps}"
        )));
    }
    std::fs::create_dir_all(dir).map_err(|e| ExportError::io(dir, e))?;
    let on_host;
    let clip = if clip.fps == host_fps {
        clip
    } else {
        on_host = clip.resampled(host_fps);
        &on_host
    };
    let sample_rate = 1.0;
    // Objects in parallel: each atomic write waits for its fsync, and a
    // scene of a hundred leaves is two hundred files.
    use rayon::prelude::*;
    let pairs: Vec<[PathBuf; 2]> = clip
        .objects
        .par_iter()
        .map(|o| {
            let samples = object_samples(clip, o);
            let pc2 = dir.join(format!("{}.pc2", o.name));
            crate::util::io::write_atomic(&pc2, &pc2_bytes(&samples, 0.0, sample_rate))
                .map_err(|e| ExportError::io(&pc2, e))?;
            let obj = dir.join(format!("{}.obj", o.name));
            crate::util::io::write_atomic(&obj, obj_text(o, &samples[0]).as_bytes())
                .map_err(|e| ExportError::io(&obj, e))?;
            Ok([pc2, obj])
        })
        .collect::<Result<_, ExportError>>()?;
    Ok(pairs.into_iter().flatten().collect())
}
