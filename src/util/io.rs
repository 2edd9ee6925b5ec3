//! File output that never leaves a half-written file behind.

use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Writes `bytes` to `path` atomically: the data go to a temporary file in the
/// same directory, which is flushed and then renamed over `path`. A reader sees
/// either the old file or the whole new one, never a partial write.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let tmp = temp_path(path);
    let result = (|| {
        let mut file = fs::File::create(&tmp)?;
        file.write_all(bytes)?;
        file.sync_all()?;
        fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    result
}

/// Particle positions per frame as CSV: a header `t,x0,y0,z0,x1,...` and
/// one row per frame, numbers in Rust's shortest round-trip form.
pub fn particle_csv(time: &[f64], frames: &[Vec<nalgebra::Vector3<f64>>]) -> Vec<u8> {
    use std::fmt::Write as _;
    let n = frames.first().map_or(0, Vec::len);
    let mut out = String::from("t");
    for i in 0..n {
        let _ = write!(out, ",x{i},y{i},z{i}");
    }
    out.push('\n');
    for (t, frame) in time.iter().zip(frames) {
        let _ = write!(out, "{t}");
        for p in frame {
            let _ = write!(out, ",{},{},{}", p.x, p.y, p.z);
        }
        out.push('\n');
    }
    out.into_bytes()
}

/// The temporary sibling used by [`write_atomic`]: same directory (so the
/// rename stays on one file system), name prefixed with a dot and suffixed
/// with the process id so that concurrent writers do not collide.
fn temp_path(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".to_string());
    let tmp_name = format!(".{name}.{}.tmp", std::process::id());
    match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => dir.join(tmp_name),
        _ => PathBuf::from(tmp_name),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn atomic_write_replaces_whole_file_and_leaves_no_temp() {
        let dir = std::env::temp_dir().join(format!("leafmagic-io-{}", std::process::id()));
        fs::create_dir_all(&dir).unwrap();
        let path = dir.join("a.csv");
        write_atomic(&path, b"first").unwrap();
        write_atomic(&path, b"second, longer").unwrap();
        assert_eq!(fs::read(&path).unwrap(), b"second, longer");
        let leftovers: Vec<_> = fs::read_dir(&dir)
            .unwrap()
            .filter_map(|e| e.ok())
            .filter(|e| e.file_name().to_string_lossy().ends_with(".tmp"))
            .collect();
        assert!(leftovers.is_empty(), "temporary files left: {leftovers:?}");
        fs::remove_dir_all(&dir).unwrap();
    }
}
