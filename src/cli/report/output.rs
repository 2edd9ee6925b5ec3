//! The human reports of `export` and `preview`: what was written, and where.

use leafmagic::output::export::{Clip, Format};
use std::path::Path;

/// `export`: the leaf files and index.csv (one line, without its newline).
pub fn leaves(count: usize, dir: &Path) -> String {
    format!("wrote {count} leaves and index.csv to {}", dir.display())
}

/// `export --format`: the fall files, re-dropped for `seconds` at `fps`, in
/// `elapsed_s` (one line, without its newline).
pub fn falls(files: usize, format: Format, seconds: f64, fps: f64, elapsed_s: f64) -> String {
    format!(
        "wrote {files} {format} files of their falls (re-dropped for {seconds} s, {fps} fps) in {elapsed_s:.2} s"
    )
}

/// `preview`: the page, its size and what it plays (one line, without its
/// newline).
pub fn preview(page: &Path, bytes: usize, clip: &Clip, elapsed_s: f64) -> String {
    format!(
        "wrote {} ({:.2} MB: {} objects, {} frames at {} fps) in {elapsed_s:.2} s",
        page.display(),
        bytes as f64 / 1e6,
        clip.objects.len(),
        clip.frames,
        clip.fps,
    )
}
