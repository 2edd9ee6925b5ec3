//! A scene's output directory read back as a clip: `summary.toml`, the pose
//! and particle CSVs it lists, and the scene file it names for the shapes
//! (what `leafmagic scene` wrote; built into a clip as a run in memory is,
//! by [`super::scene`]).

use super::scene::build_scene_clip;
use crate::formats::ExportError;
use crate::formats::clip::Clip;
use crate::motion::trajectory::Trajectory;
use crate::sim::scene::Scene;
use nalgebra::Vector3;
use serde::Deserialize;
use std::path::{Path, PathBuf};

type V3 = Vector3<f64>;

#[derive(Deserialize)]
struct SummaryFile {
    scene: String,
    source: String,
    /// The leaves' law (`scene --law` may have set it over the files'
    /// that compile here); absent in a summary written before it.
    #[serde(default)]
    aero_law: String,
    #[serde(rename = "object", default)]
    objects: Vec<SummaryObject>,
}

#[derive(Deserialize)]
struct SummaryObject {
    name: String,
    pose: Option<String>,
    positions: Option<String>,
}

/// Where the scene file named in a summary is: as written (relative to the
/// working directory the scene ran in), else relative to the output
/// directory or any directory above it (`runs/scene-x` under the repository
/// that holds `scenes/x.toml`).
fn find_source(dir: &Path, source: &str) -> Option<PathBuf> {
    let p = PathBuf::from(source);
    if p.is_file() {
        return Some(p);
    }
    let abs = std::fs::canonicalize(dir).ok()?;
    abs.ancestors().map(|a| a.join(&p)).find(|c| c.is_file())
}

/// Reads `t,x0,y0,z0,x1,...` as written by [`crate::util::io::particle_csv`].
fn read_particles(path: &Path) -> Result<(Vec<f64>, Vec<Vec<V3>>), ExportError> {
    let text = std::fs::read_to_string(path).map_err(|e| ExportError::io(path, e))?;
    let mut lines = text.lines();
    let header = lines
        .next()
        .ok_or_else(|| ExportError::input(path, "empty file, expected header `t,x0,y0,z0,...`"))?;
    let columns = header.split(',').count();
    if !header.starts_with("t,") || (columns - 1) % 3 != 0 {
        return Err(ExportError::input(
            path,
            format!("line 1: expected header `t,x0,y0,z0,...`, found `{header}`"),
        ));
    }
    let (mut time, mut frames) = (Vec::new(), Vec::new());
    for (k, line) in lines.enumerate() {
        let v: Vec<f64> = line
            .split(',')
            .map(|x| x.parse::<f64>())
            .collect::<Result<_, _>>()
            .map_err(|e| ExportError::input(path, format!("line {}: {e}", k + 2)))?;
        if v.len() != columns {
            return Err(ExportError::input(
                path,
                format!("line {}: {} fields, expected {columns}", k + 2, v.len()),
            ));
        }
        time.push(v[0]);
        frames.push(
            v[1..]
                .chunks(3)
                .map(|c| V3::new(c[0], c[1], c[2]))
                .collect(),
        );
    }
    if time.is_empty() {
        return Err(ExportError::input(path, "no data rows after the header"));
    }
    Ok((time, frames))
}

/// The clip of a scene's output directory (what `leafmagic scene` wrote),
/// on the grid at `fps`. The shapes come from the scene file the summary
/// names, which must still be there and compile to the same objects.
pub fn from_scene_dir(dir: &Path, fps: f64) -> Result<Clip, ExportError> {
    let summary_path = dir.join("summary.toml");
    let text = std::fs::read_to_string(&summary_path).map_err(|e| {
        ExportError::input(
            dir,
            format!("not a scene output directory (cannot read summary.toml: {e})"),
        )
    })?;
    let summary: SummaryFile = toml::from_str(&text)
        .map_err(|e| ExportError::input(&summary_path, e.message().to_string()))?;
    let source = find_source(dir, &summary.source).ok_or_else(|| {
        ExportError::input(
            &summary_path,
            format!(
                "the scene file it names, {}, is not found (it holds the objects' shapes)",
                summary.source
            ),
        )
    })?;
    let scene = Scene::load(&source).map_err(|e| ExportError::input(&source, e.to_string()))?;
    if scene.name != summary.scene {
        return Err(ExportError::input(
            &summary_path,
            format!(
                "written by scene '{}', but {} is now scene '{}'",
                summary.scene,
                source.display(),
                scene.name
            ),
        ));
    }
    let mut poses = Vec::new();
    let mut particles = Vec::new();
    let mut time: Option<Vec<f64>> = None;
    for obj in &scene.objects {
        let entry = summary.objects.iter().find(|o| o.name == obj.name);
        let pose = match entry.and_then(|e| e.pose.as_ref()) {
            Some(file) => {
                let t = Trajectory::read_csv(&dir.join(file))
                    .map_err(|e| ExportError::input(dir.join(file), e.to_string()))?;
                time.get_or_insert_with(|| t.time.clone());
                Some(t)
            }
            None => None,
        };
        let parts = match entry.and_then(|e| e.positions.as_ref()) {
            Some(file) => {
                let path = dir.join(file);
                let (t, frames) = read_particles(&path)?;
                if frames[0].len() != obj.particles.len() {
                    return Err(ExportError::input(
                        &path,
                        format!(
                            "{} particles per row, but object {} of {} has {}",
                            frames[0].len(),
                            obj.name,
                            source.display(),
                            obj.particles.len()
                        ),
                    ));
                }
                let t = time.get_or_insert(t).clone();
                Some((t, frames))
            }
            None => None,
        };
        poses.push(pose);
        particles.push(parts);
    }
    let Some(time) = time else {
        return Err(ExportError::input(
            dir,
            "summary.toml lists no recorded object",
        ));
    };
    let pose_refs: Vec<Option<&Trajectory>> = poses.iter().map(Option::as_ref).collect();
    let particle_refs: Vec<Option<&[Vec<V3>]>> = particles
        .iter()
        .map(|p| p.as_ref().map(|(_, f)| f.as_slice()))
        .collect();
    let mut clip = build_scene_clip(&scene, &time, &pose_refs, &particle_refs, fps)?;
    if !summary.aero_law.is_empty() {
        clip.aero_law = summary.aero_law;
    }
    Ok(clip)
}
