//! The session's collection exported for other tools: every kept leaf as
//! a leaf file and its fall (the lower-median release, dropped again as it
//! was evaluated) as glTF, USD, Alembic and a PC2 cache with its mesh,
//! written by the export layer's own writers.
//!
//! Nothing a request carries becomes a path: the folder is always
//! `<session>/export`, each file is named `leaf-<id>` after a number, and
//! the folder is written whole into a staging sibling and swapped in, so an
//! export killed midway leaves the previous one.

use super::session::{Session, StudioError};
use crate::formats::{alembic, gltf, pc2, usd};
use crate::output::export::{drop_clip_released, side_by_side};
use nalgebra::Vector3;
use std::path::PathBuf;

/// The export folder's name in the session directory.
pub const EXPORT_DIR: &str = "export";
/// Frame rates an export may be asked for, frames per second: from film's
/// lowest to the simulation's own 240 Hz.
pub const FPS_RANGE: [f64; 2] = [1.0, 240.0];
/// Start heights an export may be asked for, metres above the ground: a
/// leaf from the grass to the top of a tall tree, and then some.
pub const HEIGHT_RANGE_M: [f64; 2] = [0.0, 100.0];

/// How the collection is exported.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExportRequest {
    /// Frames per second of the falls.
    pub fps: f64,
    /// Height of each leaf's release, metres (the falls start at the
    /// origin: this is added to their z).
    pub start_height_m: f64,
}

impl ExportRequest {
    /// Checks both numbers, naming the bad one.
    pub fn validate(&self) -> Result<(), StudioError> {
        let [lo, hi] = FPS_RANGE;
        if !(lo..=hi).contains(&self.fps) {
            return Err(StudioError::Input(format!(
                "the frame rate must be {lo} to {hi} frames per second, got {}",
                self.fps
            )));
        }
        let [lo, hi] = HEIGHT_RANGE_M;
        if !(lo..=hi).contains(&self.start_height_m) {
            return Err(StudioError::Input(format!(
                "the start height must be {lo} to {hi} m, got {}",
                self.start_height_m
            )));
        }
        Ok(())
    }
}

/// Writes the collection of `session` to `<session>/export` and returns
/// the files written, relative to the session directory. An empty
/// collection is refused.
pub fn export_collection(
    session: &Session,
    request: ExportRequest,
) -> Result<Vec<PathBuf>, StudioError> {
    request.validate()?;
    let kept = &session.file().kept;
    if kept.is_empty() {
        return Err(StudioError::Input(
            "the collection is empty: keep a leaf first".to_string(),
        ));
    }
    let out = session.dir().join(EXPORT_DIR);
    let io = |e: &dyn std::fmt::Display| StudioError::File {
        path: out.clone(),
        message: e.to_string(),
    };
    let staging = crate::util::io::staging_dir(&out).map_err(|e| io(&e))?;
    let written = write_all(session, kept, request, &staging);
    let written = match written {
        Ok(w) => w,
        Err(e) => {
            let _ = std::fs::remove_dir_all(&staging);
            return Err(e);
        }
    };
    crate::util::io::swap_dir(&staging, &out).map_err(|e| {
        let _ = std::fs::remove_dir_all(&staging);
        io(&e)
    })?;
    // The swapped-out previous export, if the file system kept it aside.
    let _ = std::fs::remove_dir_all(&staging);
    Ok(written
        .into_iter()
        .map(|p| PathBuf::from(EXPORT_DIR).join(p))
        .collect())
}

/// Every kept leaf's files into `dir`; their names, relative to it.
fn write_all(
    session: &Session,
    kept: &[u64],
    request: ExportRequest,
    dir: &std::path::Path,
) -> Result<Vec<PathBuf>, StudioError> {
    use rayon::prelude::*;
    let proto = session.prototype();
    let seconds = session.file().settings.seconds;
    let per_leaf: Vec<Vec<PathBuf>> = kept
        .par_iter()
        .map(|&id| {
            let (_, c, _) = session.find(id).ok_or_else(|| {
                StudioError::Input(format!("kept candidate {id} is not in the session"))
            })?;
            let name = format!("leaf-{id}");
            let failed = |e: &dyn std::fmt::Display| StudioError::File {
                path: dir.join(&name),
                message: e.to_string(),
            };
            let mut files = Vec::new();
            let toml = format!("{name}.toml");
            crate::util::io::write_atomic(
                &dir.join(&toml),
                c.genome.to_leaf(proto).to_toml().as_bytes(),
            )
            .map_err(|e| failed(&e))?;
            files.push(PathBuf::from(toml));
            let model = c.genome.model(proto).map_err(|e| failed(&e))?;
            let mut object = drop_clip_released(
                &name,
                c.evaluation.class_name(),
                &model,
                seconds,
                request.fps,
                c.evaluation.release_deg,
            )
            .map_err(|e| failed(&e))?;
            object.translate(Vector3::new(0.0, 0.0, request.start_height_m));
            let clip =
                side_by_side(&name, vec![object], request.fps, 0.0).map_err(|e| failed(&e))?;
            // The frame rate asked for is the scene's the files play in
            // (Blender's default 24, the page's default): USD's time codes
            // and the cache's samples count its frames.
            let host_fps = request.fps;
            let write_usd = |c: &_, p: &_| usd::write_usd(c, p, host_fps);
            for (ext, write) in [
                ("glb", &gltf::write_glb as &dyn Fn(&_, &_) -> _),
                ("usda", &write_usd),
                ("abc", &alembic::write_abc),
            ] {
                let file = format!("{name}.{ext}");
                write(&clip, &dir.join(&file)).map_err(|e| failed(&e))?;
                files.push(PathBuf::from(file));
            }
            for path in pc2::write_pc2(&clip, dir, host_fps).map_err(|e| failed(&e))? {
                files.extend(path.file_name().map(PathBuf::from));
            }
            Ok(files)
        })
        .collect::<Result<_, StudioError>>()?;
    Ok(per_leaf.into_iter().flatten().collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_rates_and_heights_out_of_range_are_refused_by_name() {
        let ok = ExportRequest {
            fps: 24.0,
            start_height_m: 2.0,
        };
        assert!(ok.validate().is_ok());
        for fps in [0.0, -1.0, 241.0, f64::NAN, f64::INFINITY] {
            let e = ExportRequest { fps, ..ok }.validate().unwrap_err();
            assert!(e.to_string().contains("frame rate"), "{fps}: {e}");
        }
        for start_height_m in [-0.1, 100.5, f64::NAN] {
            let e = ExportRequest {
                start_height_m,
                ..ok
            }
            .validate()
            .unwrap_err();
            assert!(
                e.to_string().contains("start height"),
                "{start_height_m}: {e}"
            );
        }
    }
}
