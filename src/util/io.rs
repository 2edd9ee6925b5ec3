//! File output that never leaves a half-written file behind, and folder
//! output that never leaves the folder absent or half-written: a folder is
//! written into a staging sibling and swapped into place whole.

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

/// A new, empty staging folder beside `out` to write its next content
/// into: `.{name}.partial-{pid}` (the parent is made if need be). Staging
/// folders of `out` left by processes that are gone (killed mid-write) are
/// removed first.
pub fn staging_dir(out: &Path) -> std::io::Result<PathBuf> {
    let (parent, name) = split_output(out)?;
    fs::create_dir_all(&parent)?;
    remove_stale_staging(&parent, &name);
    let staging = parent.join(format!(".{name}.partial-{}", std::process::id()));
    // Ours from an earlier attempt in this process: of no further use.
    let _ = fs::remove_dir_all(&staging);
    fs::create_dir(&staging)?;
    Ok(staging)
}

/// Puts the complete `staging` folder where `out` is, and removes what was
/// at `out`. With an `out` there, the two are exchanged in one step
/// (renameat2's RENAME_EXCHANGE), so `out` is never absent; where the file
/// system does not support the exchange, the old `out` is moved aside and
/// the staging folder renamed in its place (the old one is put back if that
/// fails). On an error `staging` is left for the caller to remove.
pub fn swap_dir(staging: &Path, out: &Path) -> std::io::Result<()> {
    if fs::symlink_metadata(out).is_err() {
        return fs::rename(staging, out);
    }
    use rustix::fs::{CWD, RenameFlags, renameat_with};
    match renameat_with(CWD, staging, CWD, out, RenameFlags::EXCHANGE) {
        // `staging` now holds the old content.
        Ok(()) => {
            remove_any(staging);
            Ok(())
        }
        Err(e)
            if e == rustix::io::Errno::INVAL
                || e == rustix::io::Errno::NOSYS
                || e == rustix::io::Errno::OPNOTSUPP =>
        {
            let aside = with_suffix(staging, ".old");
            remove_any(&aside);
            fs::rename(out, &aside)?;
            if let Err(e) = fs::rename(staging, out) {
                let _ = fs::rename(&aside, out);
                return Err(e);
            }
            remove_any(&aside);
            Ok(())
        }
        Err(e) => Err(e.into()),
    }
}

/// Removes the staging folders of `name` in `parent` (`.{name}.partial-PID`,
/// its `.old`, and `.{name}.PID.tmp` of earlier versions) whose process no
/// longer runs. A live process's folder is being written: it is kept.
pub fn remove_stale_staging(parent: &Path, name: &str) {
    // Without /proc no process can be told alive: remove nothing.
    if !Path::new("/proc/self").exists() {
        return;
    }
    let Ok(entries) = fs::read_dir(parent) else {
        return;
    };
    let partial = format!(".{name}.partial-");
    let legacy = format!(".{name}.");
    for e in entries.flatten() {
        let file = e.file_name().to_string_lossy().into_owned();
        let pid = if let Some(rest) = file.strip_prefix(&partial) {
            rest.strip_suffix(".old").unwrap_or(rest)
        } else if let Some(rest) = file.strip_prefix(&legacy) {
            rest.strip_suffix(".tmp").unwrap_or("")
        } else {
            continue;
        };
        let Ok(pid) = pid.parse::<u32>() else {
            continue;
        };
        if pid != std::process::id() && !Path::new("/proc").join(pid.to_string()).exists() {
            remove_any(&e.path());
        }
    }
}

/// `out`'s parent folder (`.` for a bare name) and its file name.
fn split_output(out: &Path) -> std::io::Result<(PathBuf, String)> {
    let name = out.file_name().ok_or_else(|| {
        std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            format!("{}: not a folder name", out.display()),
        )
    })?;
    let parent = match out.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    Ok((parent, name.to_string_lossy().into_owned()))
}

fn with_suffix(path: &Path, suffix: &str) -> PathBuf {
    let mut s = path.as_os_str().to_os_string();
    s.push(suffix);
    PathBuf::from(s)
}

/// Removes a folder tree or a file, whichever is there (best effort).
fn remove_any(path: &Path) {
    match fs::symlink_metadata(path) {
        Ok(m) if m.is_dir() => {
            let _ = fs::remove_dir_all(path);
        }
        Ok(_) => {
            let _ = fs::remove_file(path);
        }
        Err(_) => {}
    }
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

    #[test]
    fn stale_staging_of_a_gone_process_goes_and_a_live_ones_stays() {
        let dir = std::env::temp_dir().join(format!("leafmagic-stale-{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).unwrap();
        let out = dir.join("x");
        // A process that has ended (and been waited for): its pid is gone.
        let mut ended = std::process::Command::new("true").spawn().unwrap();
        let dead = ended.id();
        ended.wait().unwrap();
        let mut live = std::process::Command::new("sleep")
            .arg("30")
            .spawn()
            .unwrap();
        let stale = dir.join(format!(".x.partial-{dead}"));
        let stale_old = dir.join(format!(".x.partial-{dead}.old"));
        let legacy = dir.join(format!(".x.{dead}.tmp"));
        let kept = dir.join(format!(".x.partial-{}", live.id()));
        let other = dir.join(format!(".y.partial-{dead}"));
        for d in [&stale, &stale_old, &legacy, &kept, &other] {
            fs::create_dir_all(d.join("sub")).unwrap();
        }
        let staging = staging_dir(&out).unwrap();
        assert!(staging.is_dir());
        assert!(!stale.exists() && !stale_old.exists() && !legacy.exists());
        assert!(kept.is_dir(), "a live process's staging folder was removed");
        assert!(other.is_dir(), "another output's folder was touched");
        let _ = live.kill();
        let _ = live.wait();
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_swap_puts_the_new_folder_whole_and_removes_the_old() {
        let dir = std::env::temp_dir().join(format!("leafmagic-swap-{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).unwrap();
        let out = dir.join("out");
        for round in 0..3 {
            let staging = staging_dir(&out).unwrap();
            fs::write(staging.join(format!("new-{round}.csv")), b"whole").unwrap();
            fs::create_dir(staging.join("sub")).unwrap();
            fs::write(staging.join("sub/b.csv"), format!("{round}")).unwrap();
            swap_dir(&staging, &out).unwrap();
            let mut names: Vec<String> = fs::read_dir(&out)
                .unwrap()
                .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
                .collect();
            names.sort();
            assert_eq!(names, [format!("new-{round}.csv"), "sub".to_string()]);
            assert_eq!(
                fs::read_to_string(out.join("sub/b.csv")).unwrap(),
                format!("{round}")
            );
            // Nothing but the output is left beside it.
            let beside: Vec<_> = fs::read_dir(&dir).unwrap().collect();
            assert_eq!(beside.len(), 1, "{beside:?}");
        }
        fs::remove_dir_all(&dir).unwrap();
    }
}
