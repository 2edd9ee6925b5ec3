//! Reading what a file refers to without trusting it. A glTF buffer URI or
//! a USD sublayer, reference or payload is a path written by whoever made
//! the file; followed blindly, a shared file could make leafmagic read any
//! file of the machine (and `preview` put its bytes in a page), block for
//! ever on a FIFO, or allocate for `/dev/zero`. A [`ReadScope`] says which
//! folders a read may reach (the given file's own, and those the user
//! opened, as USD's search paths do) and how many bytes it may hold; every
//! reference is resolved through it and refused, with the reason, when it
//! leaves them or is not a regular file.

use crate::util::setting::Setting;
use std::cell::Cell;
use std::fs;
use std::io::Read;
use std::path::{Component, Path, PathBuf};

/// The memory a read may take by default, bytes: 4 GiB, ten times the
/// largest point cache of the test data and well below this machine's
/// memory; `--max-memory` changes it.
pub const DEFAULT_READ_MEMORY: u64 = 4 << 30;

/// What the user lets a read reach beyond the file's own folder, and the
/// memory it may take: the same for every file a command reads.
#[derive(Clone, Debug)]
pub struct ReadPolicy {
    /// Folders references may reach besides the file's own
    /// (`--allow-references`).
    pub also_allowed: Vec<PathBuf>,
    /// Bytes a read may allocate for a file's data (`--max-memory`).
    pub max_memory: u64,
}

impl Default for ReadPolicy {
    fn default() -> Self {
        ReadPolicy {
            also_allowed: Vec::new(),
            max_memory: DEFAULT_READ_MEMORY,
        }
    }
}

/// The folders a file's references may resolve into, and the memory its
/// read may take.
#[derive(Clone, Debug)]
pub struct ReadScope {
    /// Canonical folders: the read file's own first, then the user's.
    roots: Vec<PathBuf>,
    /// Bytes the whole read may allocate for the file's data.
    max_memory: u64,
    /// Bytes charged so far ([`ReadScope::charge`]).
    used: Cell<u64>,
}

impl ReadScope {
    /// The scope of reading `file` under `policy`: its own folder and the
    /// policy's, its memory budget.
    pub fn new(file: &Path, policy: &ReadPolicy) -> Result<ReadScope, String> {
        let mut scope = ReadScope::of_file(file)?.with_max_memory(policy.max_memory);
        for dir in &policy.also_allowed {
            scope = scope
                .allow(dir)
                .map_err(|e| format!("{} {e}", Setting::AllowReferences))?;
        }
        Ok(scope)
    }

    /// The scope of reading `file`: references stay inside its folder,
    /// with the default memory budget.
    pub fn of_file(file: &Path) -> Result<ReadScope, String> {
        let dir = match file.parent() {
            Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
            _ => PathBuf::from("."),
        };
        let root = fs::canonicalize(&dir)
            .map_err(|e| format!("cannot resolve its folder {}: {e}", dir.display()))?;
        Ok(ReadScope {
            roots: vec![root],
            max_memory: DEFAULT_READ_MEMORY,
            used: Cell::new(0),
        })
    }

    /// A scope with no folder, for a read of bytes that came without a
    /// file (a `.glb` handed over in memory): it refuses every reference
    /// and still holds the read to the default memory budget.
    pub fn unanchored() -> ReadScope {
        ReadScope {
            roots: Vec::new(),
            max_memory: DEFAULT_READ_MEMORY,
            used: Cell::new(0),
        }
    }

    /// Opens `dir` to references too (`--allow-references DIR`).
    pub fn allow(mut self, dir: &Path) -> Result<ReadScope, String> {
        let root = fs::canonicalize(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        if !root.is_dir() {
            return Err(format!("{} is not a folder", dir.display()));
        }
        if !self.roots.contains(&root) {
            self.roots.push(root);
        }
        Ok(self)
    }

    /// Sets the memory budget of the read, bytes (`--max-memory`).
    pub fn with_max_memory(mut self, bytes: u64) -> ReadScope {
        self.max_memory = bytes;
        self
    }

    /// The folders references may reach, canonical, the file's own first.
    pub fn roots(&self) -> &[PathBuf] {
        &self.roots
    }

    /// The memory budget of the read, bytes.
    pub fn max_memory(&self) -> u64 {
        self.max_memory
    }

    /// Counts `bytes` more against the budget before they are allocated
    /// for `what`; refused, with both figures, past it.
    pub fn charge(&self, bytes: u64, what: &str) -> Result<(), String> {
        let total = self.used.get().saturating_add(bytes);
        if total > self.max_memory {
            return Err(format!(
                "{what} would need {bytes} bytes, which with the {} already read passes the read's \
                 memory budget of {} bytes ({} raises it)",
                self.used.get(),
                self.max_memory,
                Setting::MaxMemory
            ));
        }
        self.used.set(total);
        Ok(())
    }

    /// The file a `reference` written in a file of folder `anchor` names,
    /// canonical, if it lies inside the scope and is a regular file; else
    /// why not. URIs are percent-decoded as glTF writes them.
    pub fn resolve(&self, anchor: &Path, reference: &str) -> Result<PathBuf, String> {
        let decoded = percent_decode(reference);
        if decoded.contains('\0') {
            return Err("it holds a NUL byte".into());
        }
        if let Some((scheme, _)) = decoded.split_once("://") {
            return Err(format!(
                "it is a `{scheme}://` address; only files beside the file are read"
            ));
        }
        let path = Path::new(&decoded);
        if path.is_absolute() {
            return Err(format!(
                "it is an absolute path; references are read only inside {} \
                 ({} opens another folder)",
                self.describe_roots(),
                Setting::AllowReferences.set("DIR")
            ));
        }
        if path.components().any(|c| matches!(c, Component::Prefix(_))) {
            return Err("it names a drive".into());
        }
        self.check(&anchor.join(path))
    }

    /// `path` canonical if it lies inside the scope (symbolic links
    /// followed) and is a regular file; else why not.
    pub fn check(&self, path: &Path) -> Result<PathBuf, String> {
        let real = fs::canonicalize(path).map_err(|e| format!("it cannot be found ({e})"))?;
        if !self.roots.iter().any(|r| real.starts_with(r)) {
            return Err(format!(
                "it leads outside {} (to {}); {} opens another folder",
                self.describe_roots(),
                real.display(),
                Setting::AllowReferences.set("DIR")
            ));
        }
        let meta = fs::metadata(&real).map_err(|e| format!("it cannot be read ({e})"))?;
        if !meta.is_file() {
            return Err(format!(
                "it is not a regular file ({}), and only files are read",
                kind(&meta)
            ));
        }
        Ok(real)
    }

    /// The bytes of the file `reference` (written in a file of folder
    /// `anchor`) names, checked as [`ReadScope::resolve`] does and charged
    /// to the budget before they are read.
    pub fn read(&self, anchor: &Path, reference: &str) -> Result<Vec<u8>, String> {
        let path = self.resolve(anchor, reference)?;
        self.read_checked(&path)
    }

    /// The bytes of `path`, which [`ReadScope::check`] accepted: opened
    /// without blocking (a FIFO swapped in after the check cannot hang
    /// the read), checked again as opened, and read no further than the
    /// size it had.
    pub fn read_checked(&self, path: &Path) -> Result<Vec<u8>, String> {
        let file = open_nonblocking(path).map_err(|e| format!("it cannot be opened ({e})"))?;
        let meta = file
            .metadata()
            .map_err(|e| format!("it cannot be read ({e})"))?;
        if !meta.is_file() {
            return Err(format!("it is not a regular file ({})", kind(&meta)));
        }
        self.charge(meta.len(), "it")?;
        let mut bytes = Vec::with_capacity(meta.len() as usize);
        file.take(meta.len())
            .read_to_end(&mut bytes)
            .map_err(|e| format!("it cannot be read ({e})"))?;
        Ok(bytes)
    }

    fn describe_roots(&self) -> String {
        let names: Vec<String> = self.roots.iter().map(|r| r.display().to_string()).collect();
        match names.as_slice() {
            [] => "any folder (this read has none)".to_string(),
            [one] => format!("the file's folder {one}"),
            _ => format!("the folders {}", names.join(", ")),
        }
    }
}

/// Opens `path` for reading with `O_NONBLOCK` where there is one, so that
/// opening a FIFO returns at once instead of waiting for a writer.
fn open_nonblocking(path: &Path) -> std::io::Result<fs::File> {
    let mut options = fs::OpenOptions::new();
    options.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        options.custom_flags(rustix::fs::OFlags::NONBLOCK.bits() as i32);
    }
    options.open(path)
}

/// What kind of file system object `meta` is, in words.
fn kind(meta: &fs::Metadata) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        let t = meta.file_type();
        if t.is_fifo() {
            return "a FIFO";
        }
        if t.is_char_device() || t.is_block_device() {
            return "a device";
        }
        if t.is_socket() {
            return "a socket";
        }
    }
    if meta.is_dir() {
        "a folder"
    } else {
        "not a file"
    }
}

/// `%XX` escapes decoded, as a URI reference's path is written; anything
/// that is not a valid escape is kept as written.
fn percent_decode(s: &str) -> String {
    let bytes = s.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        let hex = |b: u8| (b as char).to_digit(16);
        if bytes[i] == b'%'
            && let (Some(h), Some(l)) = (
                bytes.get(i + 1).and_then(|&b| hex(b)),
                bytes.get(i + 2).and_then(|&b| hex(b)),
            )
        {
            out.push((h * 16 + l) as u8);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    String::from_utf8_lossy(&out).into_owned()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tree() -> (PathBuf, PathBuf) {
        let base = std::env::temp_dir().join(format!(
            "leafmagic-confined-{}-{:?}",
            std::process::id(),
            std::thread::current().id()
        ));
        let _ = fs::remove_dir_all(&base);
        let dir = base.join("shared");
        fs::create_dir_all(dir.join("sub")).unwrap();
        fs::write(base.join("secret.txt"), b"canary").unwrap();
        fs::write(dir.join("buf.bin"), b"12345678").unwrap();
        fs::write(dir.join("sub/inner.bin"), b"abc").unwrap();
        (base, dir)
    }

    #[test]
    fn references_stay_in_the_folder() {
        let (base, dir) = tree();
        let scope = ReadScope::of_file(&dir.join("a.gltf")).unwrap();
        assert_eq!(scope.read(&dir, "buf.bin").unwrap(), b"12345678");
        assert_eq!(scope.read(&dir, "sub/../buf.bin").unwrap(), b"12345678");
        assert_eq!(scope.read(&dir, "sub%2Finner.bin").unwrap(), b"abc");
        for bad in ["../secret.txt", "sub/../../secret.txt", "%2E%2E/secret.txt"] {
            let e = scope.read(&dir, bad).unwrap_err();
            assert!(e.contains("leads outside"), "{bad}: {e}");
        }
        let abs = base.join("secret.txt");
        let e = scope.read(&dir, abs.to_str().unwrap()).unwrap_err();
        assert!(e.contains("absolute"), "{e}");
        assert!(
            scope
                .read(&dir, "http://example.org/x.bin")
                .unwrap_err()
                .contains("http")
        );
        // Opened on request, as a search path.
        let wide = ReadScope::of_file(&dir.join("a.gltf"))
            .unwrap()
            .allow(&base)
            .unwrap();
        assert_eq!(wide.read(&dir, "../secret.txt").unwrap(), b"canary");
        let _ = fs::remove_dir_all(&base);
    }

    #[cfg(unix)]
    #[test]
    fn links_fifos_and_devices_are_refused() {
        let (base, dir) = tree();
        std::os::unix::fs::symlink(base.join("secret.txt"), dir.join("link.bin")).unwrap();
        std::os::unix::fs::symlink("/dev/zero", dir.join("zero.bin")).unwrap();
        let made = std::process::Command::new("mkfifo")
            .arg(dir.join("pipe.bin"))
            .status()
            .unwrap();
        assert!(made.success());
        let scope = ReadScope::of_file(&dir.join("a.gltf")).unwrap();
        let e = scope.read(&dir, "link.bin").unwrap_err();
        assert!(e.contains("leads outside"), "{e}");
        let wide = scope.clone().allow(Path::new("/dev")).unwrap();
        let e = wide.read(&dir, "zero.bin").unwrap_err();
        assert!(e.contains("a device"), "{e}");
        let e = scope.read(&dir, "pipe.bin").unwrap_err();
        assert!(e.contains("a FIFO"), "{e}");
        let e = scope.read(&dir, "sub").unwrap_err();
        assert!(e.contains("folder"), "{e}");
        let _ = fs::remove_dir_all(&base);
    }

    #[test]
    fn the_budget_is_charged_before_reading() {
        let (base, dir) = tree();
        let scope = ReadScope::of_file(&dir.join("a.gltf"))
            .unwrap()
            .with_max_memory(10);
        assert!(scope.read(&dir, "buf.bin").is_ok());
        let e = scope.read(&dir, "sub/inner.bin").unwrap_err();
        assert!(e.contains("memory budget of 10 bytes"), "{e}");
        assert!(scope.charge(2, "x").is_ok());
        assert!(scope.charge(1, "x").is_err());
        let _ = fs::remove_dir_all(&base);
    }
}
