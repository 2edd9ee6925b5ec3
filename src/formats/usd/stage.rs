//! A USD stage that the text reader ([`super::layer`]) does not read
//! alone: a binary crate file (`.usdc`, or a `.usd` holding one), a USDZ
//! package, or layers that need composing (sublayers, references,
//! payloads, inherits, specializes, variant sets). The openusd crate opens
//! and composes it (LIVRPS strength order, layer offsets on references
//! and sublayers, variant selections); this module reads the composed
//! prims back as one flat [`Layer`], as Pixar's `usdcat --flatten` would
//! write it, so that the meshes, transforms and skins are read by the same
//! code as a text layer's.
//!
//! What is kept of each prim: its name, type, attributes (type, default,
//! time samples, `interpolation` and `elementSize`) and relationships
//! (their composed targets). Prims that are not defined (`over` alone),
//! abstract (`class`) or inactive are left out, as USD's default traversal
//! does. Stage metadata (`upAxis`, `metersPerUnit`, `timeCodesPerSecond`,
//! `framesPerSecond`) is the root layer's, as in USD.
//!
//! Single-precision values are read as the shortest decimal that gives
//! them back, which is what USD writes for them in text: a `.usdc` and the
//! `.usda` that `usdcat` writes of it then read to the same bits.
//!
//! openusd 0.6 trusts the counts and offsets a crate file gives: a damaged
//! one made it index out of bounds, or ask for an allocation of exabytes,
//! which aborts the process (24 of 400 crate files of the test data with
//! bytes flipped, cut or overwritten at random). So it runs in a child
//! process, the leafmagic
//! executable's hidden `compose-usd` command ([`compose_usd_stage`]), which
//! hands the flat layer back as JSON; whatever becomes of the child, the
//! reader ends with an error that names the file.
//! (openusd 0.8 bounds those counts, but needs Rust 1.96.)

use super::layer::{Attribute, IdListOp, Layer, Prim, StageMetadata, Value, edit_id_list};
use crate::util::confined::ReadScope;
use openusd::ar::{self, Resolver};
use openusd::{gf, sdf, usd};
use std::cell::RefCell;
use std::collections::HashMap;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::rc::Rc;
use std::time::{Duration, Instant};

/// How long reading one USD file may take by default, seconds, wall
/// clock: the child stops itself past it and the parent stops the child.
/// The largest point cache of the test data composes in 3 s.
pub const DEFAULT_USD_TIMEOUT_S: u64 = 120;

/// The environment variable that sets that bound (seconds), for tests and
/// for stages larger than any seen.
pub const USD_TIMEOUT_VAR: &str = "LEAFMAGIC_USD_TIMEOUT_S";

/// The wall-clock bound on reading one USD file: [`USD_TIMEOUT_VAR`] if
/// it holds a positive number of seconds, else [`DEFAULT_USD_TIMEOUT_S`].
pub fn usd_timeout() -> Duration {
    std::env::var(USD_TIMEOUT_VAR)
        .ok()
        .and_then(|v| v.trim().parse::<f64>().ok())
        .filter(|s| s.is_finite() && *s > 0.0 && *s < 1e9)
        .map_or(
            Duration::from_secs(DEFAULT_USD_TIMEOUT_S),
            Duration::from_secs_f64,
        )
}

/// The composed stage at `path` as one flat layer, read in a child process
/// (the module docs say why) whose layers may come only from inside
/// `scope`'s folders, or why it cannot be read.
pub(super) fn flatten(path: &Path, scope: &ReadScope) -> Result<Layer, String> {
    let program = std::env::current_exe()
        .map_err(|e| format!("cannot find the leafmagic executable to read USD with: {e}"))?;
    let timeout = usd_timeout();
    let child = reader(&program, path, scope.roots(), timeout)
        .env("RUST_BACKTRACE", "0")
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| format!("cannot start {} to read USD: {e}", program.display()))?;
    let out = wait_bounded(child, timeout)?;
    let stderr = String::from_utf8_lossy(&out.stderr);
    let said = stderr.trim();
    match out.status.code() {
        Some(0) => serde_json::from_slice(&out.stdout)
            .map_err(|e| format!("the USD reader's answer did not read back: {e}")),
        Some(1) if !said.is_empty() => Err(said.to_string()),
        _ if said.contains("has overflowed its stack") => Err(format!(
            "the USD library (openusd) ran out of stack composing it: its composition arcs \
             (inherits, specializes, references) form a cycle or nest too deeply ({})",
            out.status
        )),
        _ => Err(format!(
            "the USD library (openusd) stopped on it ({}{}): it is probably damaged; \
             Pixar's `usdcat --flatten IN -o OUT.usda` (pip install usd-core) says what is \
             wrong with it, and leafmagic reads what that writes",
            out.status,
            // What the runtime says when a count read from the file asked
            // for more memory than there is.
            said.lines()
                .find(|l| l.starts_with("memory allocation of"))
                .map_or(String::new(), |l| format!(": {l}"))
        )),
    }
}

/// What a child said and how it ended.
struct Finished {
    status: std::process::ExitStatus,
    stdout: Vec<u8>,
    stderr: Vec<u8>,
}

/// Waits for `child` at most `timeout`, reading its stdout and stderr on
/// threads meanwhile (a child that fills one pipe while the other is read
/// would wait for ever); past it, stops the child and says so.
fn wait_bounded(mut child: std::process::Child, timeout: Duration) -> Result<Finished, String> {
    let drain = |pipe: Option<Box<dyn Read + Send>>| {
        std::thread::spawn(move || {
            let mut bytes = Vec::new();
            if let Some(mut pipe) = pipe {
                let _ = pipe.read_to_end(&mut bytes);
            }
            bytes
        })
    };
    let stdout = drain(
        child
            .stdout
            .take()
            .map(|p| Box::new(p) as Box<dyn Read + Send>),
    );
    let stderr = drain(
        child
            .stderr
            .take()
            .map(|p| Box::new(p) as Box<dyn Read + Send>),
    );
    let start = Instant::now();
    let mut pause = Duration::from_millis(1);
    let status = loop {
        match child.try_wait() {
            Ok(Some(status)) => break status,
            Ok(None) if start.elapsed() < timeout => {
                std::thread::sleep(pause);
                pause = (pause * 2).min(Duration::from_millis(50));
            }
            Ok(None) => {
                let _ = child.kill();
                let _ = child.wait();
                return Err(format!(
                    "reading it took longer than {} s, so it was stopped \
                     ({USD_TIMEOUT_VAR}=SECONDS sets the bound)",
                    timeout.as_secs_f64()
                ));
            }
            Err(e) => {
                let _ = child.kill();
                return Err(format!("lost the USD reader process: {e}"));
            }
        }
    };
    // The child has ended, so its pipes close and the threads finish
    // (unless it left a process of its own holding them; it starts none).
    let stdout = stdout.join().unwrap_or_default();
    let stderr = stderr.join().unwrap_or_default();
    Ok(Finished {
        status,
        stdout,
        stderr,
    })
}

/// Address space the child may take: [`MEMORY_BASE`] and
/// [`MEMORY_PER_BYTE`] times the file's size. A damaged crate file of
/// 1 kB otherwise had openusd fill gigabytes before failing (25 s); with
/// the cap the allocation fails at once and the file is refused. A 30 MB
/// point cache needs 0.6 GB.
const MEMORY_BASE: u64 = 2 << 30;

/// See [`MEMORY_BASE`]: the most a crate file's LZ4 and integer coding
/// expand by, with room for openusd's own structures.
const MEMORY_PER_BYTE: u64 = 400;

/// The command that reads `path` in a child process: `program compose-usd
/// PATH --root DIR… --parent PID --timeout-s S`, under a cap on its address
/// space where a POSIX shell can set one (`ulimit -v`).
fn reader(program: &Path, path: &Path, roots: &[PathBuf], timeout: Duration) -> Command {
    let mut args: Vec<std::ffi::OsString> = vec!["compose-usd".into(), path.into()];
    for root in roots {
        args.push("--root".into());
        args.push(root.into());
    }
    args.push("--parent".into());
    args.push(std::process::id().to_string().into());
    args.push("--timeout-s".into());
    args.push(timeout.as_secs_f64().to_string().into());
    let shell = Path::new("/bin/sh");
    if cfg!(unix) && shell.exists() {
        let size = std::fs::metadata(path).map_or(0, |m| m.len());
        let cap_kib = MEMORY_BASE.saturating_add(size.saturating_mul(MEMORY_PER_BYTE)) / 1024;
        let mut cmd = Command::new(shell);
        // `exec`: the reader replaces the shell, so its parent is this
        // process, as its watchdog expects.
        cmd.arg("-c")
            .arg(r#"ulimit -v "$1" 2>/dev/null; shift; exec "$@""#)
            .arg("sh")
            .arg(cap_kib.to_string())
            .arg(program)
            .args(args);
        cmd
    } else {
        let mut cmd = Command::new(program);
        cmd.args(args);
        cmd
    }
}

/// What the hidden `compose-usd` child is told: the file, the folders its
/// layers may come from, who started it and for how long it may run.
#[derive(Clone, Debug, Default)]
pub struct ComposeRequest {
    /// The USD file.
    pub file: PathBuf,
    /// Folders its layers may come from besides its own (the parent's
    /// [`ReadScope::roots`]).
    pub roots: Vec<PathBuf>,
    /// The process that started it: when that is gone, the child ends.
    pub parent: Option<u32>,
    /// Wall-clock bound on the child.
    pub timeout: Option<Duration>,
}

/// Ends this process, with a word on stderr, when the process `parent`
/// is no longer its parent (it ended, even by `kill -9`: the child is
/// given to another) or when `timeout` has passed: a child blocked in
/// openusd would otherwise outlive the reader that wanted its answer.
pub fn watch_parent(parent: Option<u32>, timeout: Option<Duration>) {
    let start = Instant::now();
    std::thread::spawn(move || {
        loop {
            #[cfg(unix)]
            if let Some(pid) = parent
                && std::os::unix::process::parent_id() != pid
            {
                eprintln!("the leafmagic process that asked for this USD file is gone");
                std::process::exit(3);
            }
            if let Some(limit) = timeout
                && start.elapsed() > limit
            {
                eprintln!(
                    "reading it took longer than {} s, so it was stopped \
                     ({USD_TIMEOUT_VAR}=SECONDS sets the bound)",
                    limit.as_secs_f64()
                );
                std::process::exit(1);
            }
            std::thread::sleep(Duration::from_millis(100));
        }
    });
}

/// The composed stage of `request.file` as one flat layer, in JSON: what
/// the hidden `leafmagic compose-usd FILE` prints, in the child process
/// that reads a binary, packaged or composed USD file (the module docs say
/// why). Its layers come only from the file's folder and `request.roots`.
/// Errors are openusd's own words for a file it cannot open or compose, or
/// ours for a layer refused.
pub fn compose_usd_stage(request: &ComposeRequest) -> Result<String, String> {
    let mut scope = ReadScope::of_file(&request.file)?;
    for root in &request.roots {
        scope = scope.allow(root)?;
    }
    // The child's address space is capped (`ulimit -v`); a budget here
    // would count each re-read of one layer by openusd again.
    let layer = compose(&request.file, scope.with_max_memory(u64::MAX))?;
    serde_json::to_string(&layer).map_err(|e| e.to_string())
}

/// An asset openusd asked for and we did not give it, and why.
#[derive(Clone, Debug)]
struct Refusal {
    /// The asset path as written in the layer that names it.
    written: String,
    /// That layer, where known.
    anchor: Option<String>,
    /// Why it was refused.
    reason: String,
}

impl std::fmt::Display for Refusal {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        match &self.anchor {
            Some(anchor) => write!(
                f,
                "`{}`, named in {anchor}, is refused: {}",
                self.written, self.reason
            ),
            None => write!(f, "`{}` is refused: {}", self.written, self.reason),
        }
    }
}

/// openusd's filesystem resolver, confined to a [`ReadScope`]: every
/// layer of a sublayer, reference or payload (and every asset openusd
/// resolves) must be a regular file inside the scope's folders, and a path
/// inside a `.usdz` package must stay inside it. What it refuses it
/// records, for [`compose`] to report instead of openusd's bare
/// "unresolved".
struct ConfinedResolver {
    inner: ar::DefaultResolver,
    scope: ReadScope,
    /// Each identifier openusd made, with the asset path and anchor it was
    /// made from, to name a refusal as the file wrote it.
    written: RefCell<HashMap<String, (String, Option<String>)>>,
    refusals: Rc<RefCell<Vec<Refusal>>>,
}

impl ConfinedResolver {
    /// The resolved location of `identifier` if the scope allows it.
    fn confine(&self, identifier: &str) -> Result<ar::ResolvedPath, String> {
        if let Some((package, inner)) = package_relative(identifier) {
            let real = self.scope.check(Path::new(&package))?;
            check_packaged_path(&inner)?;
            let real = real
                .to_str()
                .ok_or("its package's path is not UTF-8, which the USD reader needs")?;
            return self
                .inner
                .resolve(&ar::join_package_relative_path(real, &inner))
                .ok_or_else(|| format!("the package {real} holds no `{inner}`"));
        }
        if !Path::new(identifier).is_absolute() {
            return Err("it is not anchored to a layer's folder".to_string());
        }
        self.scope
            .check(Path::new(identifier))
            .map(ar::ResolvedPath::new)
    }

    fn refuse(&self, identifier: &str, reason: String) {
        let (written, anchor) = self
            .written
            .borrow()
            .get(identifier)
            .cloned()
            .unwrap_or_else(|| (identifier.to_string(), None));
        let mut refusals = self.refusals.borrow_mut();
        // openusd asks again on each composition pass.
        if !refusals
            .iter()
            .any(|r| r.written == written && r.anchor == anchor)
        {
            refusals.push(Refusal {
                written,
                anchor,
                reason,
            });
        }
    }
}

/// `pkg.usdz[inner]` split into its package and the path inside it.
fn package_relative(identifier: &str) -> Option<(String, String)> {
    if ar::is_package_relative_path(identifier) {
        ar::split_package_relative_path_outer(identifier)
    } else {
        None
    }
}

/// `Err` unless `inner`, a path inside a package, stays inside it: no
/// absolute path, no `..`, no package inside the package.
fn check_packaged_path(inner: &str) -> Result<(), String> {
    if inner.starts_with(['/', '\\']) || inner.contains(':') {
        return Err(format!("`{inner}` inside its package is an absolute path"));
    }
    if inner.split(['/', '\\']).any(|part| part == "..") {
        return Err(format!("`{inner}` climbs out of its package with `..`"));
    }
    if inner.contains('[') {
        return Err(format!(
            "`{inner}` is a package inside a package, which is not read"
        ));
    }
    Ok(())
}

impl ar::Resolver for ConfinedResolver {
    fn create_identifier(&self, asset_path: &str, anchor: Option<&ar::ResolvedPath>) -> String {
        let identifier = self.inner.create_identifier(asset_path, anchor);
        self.written
            .borrow_mut()
            .entry(identifier.clone())
            .or_insert_with(|| (asset_path.to_string(), anchor.map(|a| a.to_string())));
        identifier
    }

    fn resolve(&self, asset_path: &str) -> Option<ar::ResolvedPath> {
        self.confine(asset_path)
            .map_err(|reason| self.refuse(asset_path, reason))
            .ok()
    }

    fn resolve_for_new_asset(&self, _asset_path: &str) -> Option<ar::ResolvedPath> {
        // This reader writes nothing.
        None
    }

    fn open_asset(&self, resolved_path: &ar::ResolvedPath) -> std::io::Result<Box<dyn ar::Asset>> {
        let text = resolved_path.to_string_lossy().into_owned();
        let refused = |reason: String| {
            self.refuse(&text, reason.clone());
            std::io::Error::other(reason)
        };
        if let Some((package, inner)) = package_relative(&text) {
            // Checked again as opened: a file swapped after resolving.
            self.scope.check(Path::new(&package)).map_err(refused)?;
            check_packaged_path(&inner).map_err(refused)?;
            return self.inner.open_asset(resolved_path);
        }
        let real = self.scope.check(resolved_path).map_err(refused)?;
        // Opened without blocking and read no further than its size: a
        // FIFO swapped in after the check cannot hang the read.
        let bytes = self.scope.read_checked(&real).map_err(refused)?;
        Ok(Box::new(std::io::Cursor::new(bytes)))
    }

    fn identity(&self) -> String {
        format!("leafmagic-confined{:?}", self.scope.roots())
    }
}

/// The deepest prim nesting the child hands back: the parent reads its
/// JSON with serde_json, which refuses more than 128 levels of arrays and
/// objects (two a prim, up to eight for an attribute's value).
const MAX_COMPOSED_DEPTH: usize = 50;

/// The composed stage at `path` as one flat layer, in this process, its
/// layers read only inside `scope`.
fn compose(path: &Path, scope: ReadScope) -> Result<Layer, String> {
    let file = path
        .to_str()
        .ok_or_else(|| "its path is not UTF-8, which the USD reader needs".to_string())?;
    let refusals = Rc::new(RefCell::new(Vec::new()));
    let resolver = ConfinedResolver {
        inner: ar::DefaultResolver::new(),
        scope,
        written: RefCell::new(HashMap::new()),
        refusals: Rc::clone(&refusals),
    };
    // A refused layer is why composing failed, in our words; openusd's
    // own ("unresolved sublayer @x@") where nothing was refused but
    // missing files, which it names well.
    let refused = |fallback: String| -> String {
        let refusals: Vec<Refusal> = refusals
            .borrow()
            .iter()
            .filter(|r| !r.reason.starts_with(NOT_FOUND))
            .cloned()
            .collect();
        match refusals.as_slice() {
            [] => fallback,
            [one] => format!("a layer it names is not read: {one}"),
            [first, rest @ ..] => format!(
                "a layer it names is not read: {first} (and {} more refused)",
                rest.len()
            ),
        }
    };
    let stage = usd::Stage::builder()
        .resolver(resolver)
        .open(file)
        .map_err(|e| refused(format!("{e:#}")))?;
    if let Some(e) = stage.composition_errors().first() {
        return Err(refused(format!("it does not compose: {e}")));
    }
    if let Some(cycle) = arc_cycle(&stage) {
        return Err(format!("its composition arcs form a cycle: {cycle}"));
    }
    let layer = flat_layer(&stage);
    // References and payloads resolve as the prims are composed, so what
    // was refused is known only now. A layer left out would change what
    // is read, so any refusal fails the read; only an asset that is
    // merely missing (a texture) without a composition error does not.
    if let Some(e) = stage.composition_errors().first() {
        return Err(refused(format!("it does not compose: {e}")));
    }
    if refusals
        .borrow()
        .iter()
        .any(|r| !r.reason.starts_with(NOT_FOUND))
    {
        return Err(refused(String::new()));
    }
    layer
}

/// How [`ReadScope::check`] begins its reason for a path that does not
/// exist.
const NOT_FOUND: &str = "it cannot be found";

/// The composed `stage` as one flat layer.
fn flat_layer(stage: &usd::Stage) -> Result<Layer, String> {
    let meta = {
        let root = stage.root_layer();
        let data = root.data();
        let field = |key: &str| {
            data.try_field(&sdf::Path::abs_root(), key)
                .ok()
                .flatten()
                .and_then(|v| value(&v))
        };
        let number = |key: &str| match field(key) {
            Some(Value::Number(x)) => Some(x),
            _ => None,
        };
        StageMetadata {
            up_axis: match field("upAxis") {
                Some(Value::Str(a)) => Some(a),
                _ => None,
            },
            meters_per_unit: number("metersPerUnit"),
            time_codes_per_second: number("timeCodesPerSecond"),
            frames_per_second: number("framesPerSecond"),
        }
    };
    meta.layer(children(&stage.prim(sdf::Path::abs_root()), 1)?)
}

/// The items a list op adds, whatever its edits (deletions are left out:
/// a cycle that a deletion breaks in one layer may close in another).
fn list_items<T: Default + Clone + PartialEq>(op: &sdf::ListOp<T>) -> impl Iterator<Item = &T> {
    op.explicit_items
        .iter()
        .chain(&op.added_items)
        .chain(&op.prepended_items)
        .chain(&op.appended_items)
}

/// A cycle of inherits, specializes or internal references among the prims
/// of one of `stage`'s layer stacks, in words (`</A> inherits </B>, which
/// inherits </A>`), found before composing those prims: openusd 0.6
/// follows an inherit cycle until its stack overflows. A prim also takes
/// the arcs of its ancestors (`/A` inheriting `/B` makes `/A/c` take
/// `/B/c`), and an arc to a prim's own ancestor or descendant is a cycle.
fn arc_cycle(stage: &usd::Stage) -> Option<String> {
    let stack = stage.layer_stack();
    let mut groups = vec![stack.clone()];
    for id in stage.layer_identifiers() {
        if !stack.contains(&id) {
            groups.push(vec![id]);
        }
    }
    for group in groups {
        // Each prim spec's own arcs: (verb, target).
        let mut arcs: HashMap<String, Vec<Arc>> = HashMap::new();
        for id in &group {
            let Some(layer) = stage.layer(id) else {
                continue;
            };
            let data = layer.data();
            for path in data.spec_paths() {
                if data.spec_type(&path) != Some(sdf::SpecType::Prim) {
                    continue;
                }
                let mut found = Vec::new();
                for (field, verb) in [("inheritPaths", "inherits"), ("specializes", "specializes")]
                {
                    if let Ok(Some(v)) = data.try_field(&path, field)
                        && let sdf::Value::PathListOp(op) = &*v
                    {
                        found.extend(list_items(op).map(|t| (verb, t.as_str().to_string())));
                    }
                }
                if let Ok(Some(v)) = data.try_field(&path, "references")
                    && let sdf::Value::ReferenceListOp(op) = &*v
                {
                    found.extend(
                        list_items(op)
                            .filter(|r| r.asset_path.is_empty() && !r.prim_path.is_empty())
                            .map(|r| ("references", r.prim_path.as_str().to_string())),
                    );
                }
                arcs.entry(path.as_str().to_string())
                    .or_default()
                    .extend(found);
            }
        }
        if let Some(cycle) = find_cycle(&arcs) {
            return Some(cycle);
        }
    }
    None
}

/// Whether `path` is `prefix` or lies below it.
fn is_within(path: &str, prefix: &str) -> bool {
    path == prefix
        || (path.starts_with(prefix)
            && (prefix.ends_with('/') || path[prefix.len()..].starts_with('/')))
}

/// A composition arc: its verb (`inherits`) and the prim it reaches.
type Arc = (&'static str, String);

/// A cycle among `arcs` (prim path → its own arcs), followed with an
/// explicit stack (a file's cycle may be as long as it likes), in words.
fn find_cycle(arcs: &HashMap<String, Vec<Arc>>) -> Option<String> {
    // The arcs `path` takes: its own, and each ancestor's carried down to
    // it; only to prims that have specs (others add no arcs of their own).
    let edges = |path: &str| -> Vec<Arc> {
        let mut out = Vec::new();
        let mut at = path.to_string();
        loop {
            if let Some(own) = arcs.get(&at) {
                let rest = &path[at.len()..];
                for (verb, target) in own {
                    out.push((*verb, format!("{target}{rest}")));
                }
            }
            match at.rfind('/') {
                Some(0) | None => break,
                Some(k) => at.truncate(k),
            }
        }
        out
    };
    // 0 unvisited, 1 on the path being followed, 2 done.
    let mut state: HashMap<String, u8> = HashMap::new();
    let mut starts: Vec<&String> = arcs.keys().collect();
    starts.sort();
    for start in starts {
        if state.get(start.as_str()).copied().unwrap_or(0) != 0 {
            continue;
        }
        // The path followed: each prim with its arcs and the next to try.
        let mut trail: Vec<(String, Vec<Arc>, usize)> = vec![(start.clone(), edges(start), 0)];
        state.insert(start.clone(), 1);
        while let Some((node, out, next)) = trail.last_mut() {
            let Some((verb, target)) = out.get(*next).cloned() else {
                state.insert(node.clone(), 2);
                trail.pop();
                continue;
            };
            *next += 1;
            // An arc within a prim's own namespace: a cycle by itself.
            if target == *node {
                return Some(format!("<{node}> {verb} itself"));
            }
            let side = if is_within(&target, node) {
                Some("below")
            } else if is_within(node, &target) {
                Some("above")
            } else {
                None
            };
            if let Some(side) = side {
                return Some(format!("<{node}> {verb} <{target}>, which lies {side} it"));
            }
            if !arcs.contains_key(&target) {
                continue;
            }
            match state.get(&target).copied().unwrap_or(0) {
                1 => {
                    let from = trail.iter().position(|(n, _, _)| *n == target)?;
                    let cycle = &trail[from..];
                    // A long cycle by its first arcs and the one that
                    // closes it: the message stays a line.
                    const SHOWN: usize = 6;
                    let mut words = format!("<{}>", cycle[0].0);
                    for (k, (_, out, next)) in cycle.iter().enumerate() {
                        let (verb, to) = &out[*next - 1];
                        let which = if k == 0 { "" } else { ", which" };
                        if k < SHOWN || k + 1 == cycle.len() {
                            words.push_str(&format!("{which} {verb} <{to}>"));
                        } else if k == SHOWN {
                            words.push_str(", …");
                        }
                    }
                    if cycle.len() > SHOWN + 1 {
                        words.push_str(&format!(" ({} arcs in all)", cycle.len()));
                    }
                    return Some(words);
                }
                2 => {}
                _ => {
                    state.insert(target.clone(), 1);
                    let out = edges(&target);
                    trail.push((target, out, 0));
                }
            }
        }
    }
    None
}

/// An openusd call's error in our words.
fn failed(e: anyhow::Error) -> String {
    format!("{e:#}")
}

/// The composed children of `prim`, at nesting `depth`, that a default
/// traversal visits.
fn children(prim: &usd::Prim, depth: usize) -> Result<Vec<Prim>, String> {
    let mut out = Vec::new();
    for child in prim.children().map_err(failed)? {
        let shown = child.is_defined().map_err(failed)?
            && child.is_active().map_err(failed)?
            && !child.is_abstract().map_err(failed)?;
        if shown {
            if depth > MAX_COMPOSED_DEPTH {
                return Err(format!(
                    "prim `{}`: prims nest deeper than {MAX_COMPOSED_DEPTH} levels",
                    child.path()
                ));
            }
            out.push(flat_prim(&child, depth)?);
        }
    }
    Ok(out)
}

/// A PointInstancer's composed `inactiveIds`: each layer's list op of
/// its prim stack applied over the weaker ones' (openusd 0.6 composes
/// only the metadata it knows of).
fn inactive_ids(prim: &usd::Prim) -> Result<Vec<i64>, String> {
    let stage = prim.stage();
    let mut ids = Vec::new();
    for (layer, path) in prim.prim_stack().map_err(failed)?.iter().rev() {
        let Some(layer) = stage.layer(layer) else {
            continue;
        };
        let field = layer
            .data()
            .try_field(path, "inactiveIds")
            .map_err(|e| format!("its `inactiveIds` in {}: {e}", layer.identifier()))?;
        match field.as_deref() {
            None => {}
            Some(sdf::Value::Int64ListOp(op)) => {
                let op = IdListOp {
                    explicit: op.explicit.then(|| op.explicit_items.clone()),
                    deleted: op.deleted_items.clone(),
                    added: op
                        .added_items
                        .iter()
                        .chain(&op.prepended_items)
                        .chain(&op.appended_items)
                        .copied()
                        .collect(),
                };
                ids = edit_id_list(&ids, &op);
            }
            Some(v) => {
                return Err(format!(
                    "its `inactiveIds` in {} is not a list of ids ({v:?})",
                    layer.identifier()
                ));
            }
        }
    }
    Ok(ids)
}

/// One composed prim, at nesting `depth`, and those below it.
fn flat_prim(prim: &usd::Prim, depth: usize) -> Result<Prim, String> {
    let path = prim.path();
    let mut flat = Prim {
        name: path.name().unwrap_or_default().to_string(),
        type_name: prim
            .type_name()
            .map_err(failed)?
            .map(|t| t.as_str().to_string())
            .unwrap_or_default(),
        attributes: Vec::new(),
        children: Vec::new(),
        inactive_ids: Vec::new(),
    };
    let at = |e: String| format!("prim `{path}`: {e}");
    if flat.type_name == "PointInstancer" {
        flat.inactive_ids = inactive_ids(prim).map_err(at)?;
    }
    for a in prim.attributes().map_err(|e| at(failed(e)))? {
        let name = property_name(a.path());
        let read = || -> Result<Attribute, String> {
            let default = a.get::<sdf::Value>().map_err(failed)?;
            let samples = a.time_samples().map_err(failed)?.unwrap_or_default();
            if let Some((t, _)) = samples.iter().find(|(t, _)| !t.is_finite()) {
                return Err(format!("a time sample at time code {t}"));
            }
            let mut metadata = Vec::new();
            for key in ["interpolation", "elementSize"] {
                if let Some(v) = a.get_metadata::<sdf::Value>(key).map_err(failed)? {
                    metadata.extend(value(&v).map(|v| (key.to_string(), v)));
                }
            }
            Ok(Attribute {
                type_name: a
                    .type_name()
                    .map_err(failed)?
                    .map(|t| t.as_str().to_string())
                    .unwrap_or_default(),
                default: default.as_ref().and_then(value),
                // A blocked sample (`None` in text) has no value to hold.
                samples: samples
                    .iter()
                    .filter_map(|(t, v)| value(v).map(|v| (*t, v)))
                    .collect(),
                metadata,
            })
        };
        let attribute = read().map_err(|e| at(format!("`{name}`: {e}")))?;
        flat.attributes.push((name, attribute));
    }
    for r in prim.relationships().map_err(|e| at(failed(e)))? {
        let name = property_name(r.path());
        let targets = r
            .targets()
            .map_err(|e| at(format!("`{name}`: {}", failed(e))))?;
        let default = Value::List(
            targets
                .iter()
                .map(|p| Value::Path(p.as_str().to_string()))
                .collect(),
        );
        flat.attributes.push((
            name,
            Attribute {
                type_name: "rel".to_string(),
                default: Some(default),
                ..Attribute::default()
            },
        ));
    }
    flat.children = children(prim, depth + 1)?;
    Ok(flat)
}

/// The name of the property at `path` (`xformOp:translate`).
fn property_name(path: &sdf::Path) -> String {
    path.split_property()
        .map_or_else(|| path.as_str().to_string(), |(_, name)| name.to_string())
}

/// An f32 as the shortest decimal that gives it back, in f64: what USD
/// writes for it in text, so that text and crate files read the same.
/// Where the f32 lies exactly halfway between two such decimals (-16.7578125
/// between -16.757812 and -16.757813), USD writes the even one and Rust's
/// formatter the other (505 of the 7.2 million numbers of a point cache
/// of 10,000 vertices and 240 frames): the even one is taken.
fn single(x: f32) -> f64 {
    if !x.is_finite() || x == 0.0 {
        return f64::from(x);
    }
    let text = format!("{:e}", x.abs());
    let Some((mantissa, exp)) = text.split_once('e') else {
        return f64::from(x);
    };
    let digits = mantissa.replace('.', "");
    let (Ok(n), Ok(exp)) = (digits.parse::<u64>(), exp.parse::<i32>()) else {
        return f64::from(x);
    };
    let len = digits.len() as i32;
    // n × 10^(exp − len + 1), or with one more digit.
    let at =
        |n: u64, len: i32| -> f64 { format!("{n}e{}", exp - len + 1).parse().unwrap_or(f64::NAN) };
    let mut value = at(n, len);
    let exact = f64::from(x.abs());
    if n % 2 == 1 {
        let (other, middle) = if exact > value {
            (n + 1, 10 * n + 5)
        } else {
            (n - 1, 10 * n - 5)
        };
        let other_value = at(other, len);
        if at(middle, len + 1) == exact && other_value as f32 == x.abs() {
            value = other_value;
        }
    }
    if value.is_finite() {
        value.copysign(f64::from(x))
    } else {
        f64::from(x)
    }
}

/// Numbers as a tuple, the text reader's shape for a vector.
fn tuple(xs: impl IntoIterator<Item = f64>) -> Value {
    Value::List(xs.into_iter().map(Value::Number).collect())
}

/// An array of `T`, each as `f` gives it.
fn array<T>(xs: &[T], f: impl Fn(&T) -> Value) -> Value {
    Value::List(xs.iter().map(f).collect())
}

fn vec2f(v: &gf::Vec2f) -> Value {
    tuple([single(v.x), single(v.y)])
}
fn vec3f(v: &gf::Vec3f) -> Value {
    tuple([single(v.x), single(v.y), single(v.z)])
}
fn vec4f(v: &gf::Vec4f) -> Value {
    tuple([single(v.x), single(v.y), single(v.z), single(v.w)])
}
fn vec2d(v: &gf::Vec2d) -> Value {
    tuple([v.x, v.y])
}
fn vec3d(v: &gf::Vec3d) -> Value {
    tuple([v.x, v.y, v.z])
}
fn vec4d(v: &gf::Vec4d) -> Value {
    tuple([v.x, v.y, v.z, v.w])
}
/// A half-precision number (openusd's `f16`) as USD text writes it: to
/// six significant digits, C++'s default for a stream (`0.818848` for
/// 0.81884765625), not its shortest decimal. So a crate file's quaths
/// (Houdini writes orientations so) read as its text's.
fn half<T: Copy + Into<f32>>(x: &T) -> f64 {
    let x = f64::from((*x).into());
    if !x.is_finite() || x == 0.0 {
        return x;
    }
    format!("{x:.5e}").parse().unwrap_or(x)
}
fn vec3h(v: &gf::Vec3h) -> Value {
    tuple([half(&v.x), half(&v.y), half(&v.z)])
}
/// Quaternions as USD text writes them: (real, i, j, k).
fn quatf(q: &gf::Quatf) -> Value {
    tuple([single(q.w), single(q.x), single(q.y), single(q.z)])
}
fn quatd(q: &gf::Quatd) -> Value {
    tuple([q.w, q.x, q.y, q.z])
}
fn quath(q: &gf::Quath) -> Value {
    tuple([half(&q.w), half(&q.x), half(&q.y), half(&q.z)])
}
/// A matrix as its rows, as USD text writes it.
fn matrix(m: &[f64], size: usize) -> Value {
    Value::List(
        m.chunks(size)
            .map(|row| tuple(row.iter().copied()))
            .collect(),
    )
}

/// A composed value in the text reader's shapes ([`Value`]): numbers,
/// tuples, arrays, strings and tokens, paths; `None` for what no reader of
/// ours reads (dictionaries, list edits, blocks).
fn value(v: &sdf::Value) -> Option<Value> {
    use sdf::Value as S;
    let n = |x: f64| Value::Number(x);
    Some(match v {
        S::Bool(b) => n(f64::from(u8::from(*b))),
        S::Uchar(x) => n(f64::from(*x)),
        S::Int(x) => n(f64::from(*x)),
        S::Uint(x) => n(f64::from(*x)),
        S::Int64(x) => n(*x as f64),
        S::Uint64(x) => n(*x as f64),
        S::Half(x) => n(half(x)),
        S::Float(x) => n(single(*x)),
        S::Double(x) => n(*x),
        S::BoolVec(xs) => array(xs, |b| n(f64::from(u8::from(*b)))),
        S::UcharVec(xs) => array(xs, |x| n(f64::from(*x))),
        S::IntVec(xs) => array(xs, |x| n(f64::from(*x))),
        S::UintVec(xs) => array(xs, |x| n(f64::from(*x))),
        S::Int64Vec(xs) => array(xs, |x| n(*x as f64)),
        S::Uint64Vec(xs) => array(xs, |x| n(*x as f64)),
        S::HalfVec(xs) => array(xs, |x| n(half(x))),
        S::FloatVec(xs) => array(xs, |x| n(single(*x))),
        S::DoubleVec(xs) => array(xs, |x| n(*x)),
        S::String(s) => Value::Str(s.clone()),
        S::Token(t) => Value::Str(t.as_str().to_string()),
        S::StringVec(xs) => array(xs, |s| Value::Str(s.clone())),
        S::TokenVec(xs) => array(xs, |t| Value::Str(t.as_str().to_string())),
        S::AssetPath(a) => Value::Str(a.authored_path.clone()),
        S::Quath(q) => quath(q),
        S::Quatf(q) => quatf(q),
        S::Quatd(q) => quatd(q),
        S::QuathVec(qs) => array(qs, quath),
        S::QuatfVec(qs) => array(qs, quatf),
        S::QuatdVec(qs) => array(qs, quatd),
        S::Vec2f(v) => vec2f(v),
        S::Vec2d(v) => vec2d(v),
        S::Vec3h(v) => vec3h(v),
        S::Vec3f(v) => vec3f(v),
        S::Vec3d(v) => vec3d(v),
        S::Vec4f(v) => vec4f(v),
        S::Vec4d(v) => vec4d(v),
        S::Vec2fVec(vs) => array(vs, vec2f),
        S::Vec2dVec(vs) => array(vs, vec2d),
        S::Vec3hVec(vs) => array(vs, vec3h),
        S::Vec3fVec(vs) => array(vs, vec3f),
        S::Vec3dVec(vs) => array(vs, vec3d),
        S::Vec4fVec(vs) => array(vs, vec4f),
        S::Vec4dVec(vs) => array(vs, vec4d),
        S::Matrix2d(m) => matrix(&m.0, 2),
        S::Matrix3d(m) => matrix(&m.0, 3),
        S::Matrix4d(m) => matrix(&m.0, 4),
        S::Matrix2dVec(ms) => array(ms, |m| matrix(&m.0, 2)),
        S::Matrix3dVec(ms) => array(ms, |m| matrix(&m.0, 3)),
        S::Matrix4dVec(ms) => array(ms, |m| matrix(&m.0, 4)),
        S::PathVec(ps) => array(ps, |p| Value::Path(p.as_str().to_string())),
        _ => return None,
    })
}

/// A [`Value`] in JSON, compact where a point cache is large: a number as
/// itself, a string as itself, a list as an array; the rest one-key
/// objects: `{"i": …}` an identifier, `{"p": …}` a path, `{"d": [[k, v],
/// …]}` a dictionary, `{"n": "inf"}` a number JSON has none for (`inf`,
/// `-inf`, `NaN`). Serde's derived form tags every number (`{"Number":
/// 0.1}`), which made a 10,000-vertex cache of 240 frames 186 MB.
impl serde::Serialize for Value {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            Value::Number(x) if x.is_finite() => s.serialize_f64(*x),
            Value::Number(x) => one_key(s, "n", &x.to_string()),
            Value::Str(text) => s.serialize_str(text),
            Value::Ident(text) => one_key(s, "i", text),
            Value::Path(text) => one_key(s, "p", text),
            Value::List(items) => s.collect_seq(items),
            Value::Dict(entries) => one_key(s, "d", entries),
        }
    }
}

/// `{key: value}`.
fn one_key<S: serde::Serializer, T: serde::Serialize + ?Sized>(
    s: S,
    key: &str,
    value: &T,
) -> Result<S::Ok, S::Error> {
    use serde::ser::SerializeMap;
    let mut map = s.serialize_map(Some(1))?;
    map.serialize_entry(key, value)?;
    map.end()
}

impl<'de> serde::Deserialize<'de> for Value {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_any(ValueVisitor)
    }
}

/// Reads what [`Value`]'s `Serialize` writes.
struct ValueVisitor;

impl<'de> serde::de::Visitor<'de> for ValueVisitor {
    type Value = Value;

    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str("a USD value: a number, a string, an array or a one-key object")
    }
    fn visit_f64<E>(self, x: f64) -> Result<Value, E> {
        Ok(Value::Number(x))
    }
    fn visit_i64<E>(self, x: i64) -> Result<Value, E> {
        Ok(Value::Number(x as f64))
    }
    fn visit_u64<E>(self, x: u64) -> Result<Value, E> {
        Ok(Value::Number(x as f64))
    }
    fn visit_str<E>(self, text: &str) -> Result<Value, E> {
        Ok(Value::Str(text.to_string()))
    }
    fn visit_string<E>(self, text: String) -> Result<Value, E> {
        Ok(Value::Str(text))
    }
    fn visit_seq<A: serde::de::SeqAccess<'de>>(self, mut seq: A) -> Result<Value, A::Error> {
        let mut items = Vec::with_capacity(seq.size_hint().unwrap_or(0).min(1 << 16));
        while let Some(v) = seq.next_element()? {
            items.push(v);
        }
        Ok(Value::List(items))
    }
    fn visit_map<A: serde::de::MapAccess<'de>>(self, mut map: A) -> Result<Value, A::Error> {
        use serde::de::Error;
        let key: String = map
            .next_key()?
            .ok_or_else(|| A::Error::custom("an empty object is no USD value"))?;
        let value = match key.as_str() {
            "n" => {
                let word: String = map.next_value()?;
                Value::Number(word.parse().map_err(A::Error::custom)?)
            }
            "i" => Value::Ident(map.next_value()?),
            "p" => Value::Path(map.next_value()?),
            "d" => Value::Dict(map.next_value()?),
            other => return Err(A::Error::custom(format!("no USD value is keyed `{other}`"))),
        };
        Ok(value)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arc_cycles_are_found_and_named_without_recursing() {
        let arcs = |list: &[(&str, &[(&'static str, &str)])]| {
            list.iter()
                .map(|(p, out)| {
                    let out = out.iter().map(|(v, t)| (*v, t.to_string())).collect();
                    (p.to_string(), out)
                })
                .collect::<HashMap<_, _>>()
        };
        let two = arcs(&[("/A", &[("inherits", "/B")]), ("/B", &[("inherits", "/A")])]);
        assert_eq!(
            find_cycle(&two).unwrap(),
            "</A> inherits </B>, which inherits </A>"
        );
        let none = arcs(&[
            ("/A", &[("inherits", "/B")]),
            ("/B", &[("specializes", "/C")]),
            ("/C", &[]),
            ("/A/c", &[("references", "/C")]),
        ]);
        assert_eq!(find_cycle(&none), None);
        // A chain of 100,000 prims closing on itself: followed without
        // recursion, named from where it was entered.
        let n = 100_000;
        let mut long = HashMap::new();
        for k in 0..n {
            long.insert(
                format!("/P{k}"),
                vec![("inherits", format!("/P{}", (k + 1) % n))],
            );
        }
        let found = find_cycle(&long).unwrap();
        assert_eq!(
            found,
            "</P0> inherits </P1>, which inherits </P2>, which inherits </P3>, which inherits \
             </P4>, which inherits </P5>, which inherits </P6>, …, which inherits </P0> \
             (100000 arcs in all)"
        );
        let below = arcs(&[("/A", &[("references", "/A/x")]), ("/A/x", &[])]);
        assert_eq!(
            find_cycle(&below).unwrap(),
            "</A> references </A/x>, which lies below it"
        );
    }

    #[test]
    fn paths_inside_a_package_stay_inside_it() {
        assert!(check_packaged_path("geo/leaf.usda").is_ok());
        for bad in [
            "../x.usda",
            "a/../../x.usda",
            "/etc/x.usda",
            "C:/x.usda",
            "in.usdz[x.usda]",
        ] {
            assert!(check_packaged_path(bad).is_err(), "{bad}");
        }
    }

    #[cfg(unix)]
    #[test]
    fn a_child_past_its_time_is_stopped() {
        let child = Command::new("sleep")
            .arg("30")
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let start = Instant::now();
        let Err(e) = wait_bounded(child, Duration::from_millis(300)) else {
            panic!("sleep 30 ended within 0.3 s");
        };
        assert!(start.elapsed() < Duration::from_secs(5));
        assert!(e.contains("longer than 0.3 s"), "{e}");
        let child = Command::new("echo")
            .arg("hi")
            .stdout(Stdio::piped())
            .spawn()
            .unwrap();
        let out = wait_bounded(child, Duration::from_secs(30)).unwrap();
        assert_eq!(out.stdout, b"hi\n");
    }

    #[test]
    fn values_take_the_text_reader_s_shapes() {
        // f32 as the decimal USD text writes for it, not its binary value.
        assert_eq!(single(0.1), 0.1);
        assert_ne!(f64::from(0.1f32), 0.1);
        // Halfway between two shortest decimals, the even one, as USD
        // writes it (Rust's formatter gives -16.757813).
        let tie = 16.0 + 97.0 / 128.0; // 16.7578125, an f32 exactly
        assert_eq!(single(-tie), -16.757812);
        assert_eq!(single(tie), 16.757812);
        assert_eq!(single(-2.5), -2.5);
        assert_eq!(single(0.0).to_bits(), 0.0f64.to_bits());
        assert_eq!(single(-0.0).to_bits(), (-0.0f64).to_bits());
        assert_eq!(single(1e-40), 1e-40);
        assert_eq!(single(f32::MAX), 3.4028235e38);
        // A half as USD text writes it, to six significant digits (the
        // values of a Houdini quath in tests/data/usd/instanced).
        assert_eq!(half(&(1677.0f32 / 2048.0)), 0.818848);
        assert_eq!(half(&(-1175.0f32 / 2048.0)), -0.57373);
        assert_eq!(half(&(1874.0f32 / 131_072.0)), 0.0142975);
        assert_eq!(half(&-0.0f32).to_bits(), (-0.0f64).to_bits());
        // Every one reads back as the f32 it came from.
        for bits in (0..u32::MAX).step_by(9_973) {
            let x = f32::from_bits(bits);
            if x.is_finite() {
                assert_eq!(single(x) as f32, x, "{x:e}");
            }
        }
        // Quaternions real part first, as `(w, x, y, z)` in text.
        let q = sdf::Value::Quatf(gf::Quatf {
            w: 0.5,
            x: 1.0,
            y: 2.0,
            z: 3.0,
        });
        assert_eq!(value(&q).unwrap().numbers().unwrap(), [0.5, 1.0, 2.0, 3.0]);
        // Matrices as their rows.
        let mut m = [0.0; 16];
        m.iter_mut().enumerate().for_each(|(k, x)| *x = k as f64);
        let Some(Value::List(rows)) = value(&sdf::Value::Matrix4d(gf::Matrix4d(m))) else {
            panic!("a matrix is a list of rows");
        };
        assert_eq!(rows.len(), 4);
        assert_eq!(rows[1].numbers().unwrap(), [4.0, 5.0, 6.0, 7.0]);
        // Tokens are strings; dictionaries are not read.
        let t = sdf::Value::TokenVec(vec!["xformOp:translate".into()]);
        assert_eq!(value(&t).unwrap().strings().unwrap(), ["xformOp:translate"]);
        assert_eq!(value(&sdf::Value::Dictionary(Default::default())), None);
    }

    #[test]
    fn a_layer_comes_back_from_json_as_it_went_with_numbers_json_lacks() {
        let layer = Layer {
            up_y: false,
            meters_per_unit: 1.0,
            time_codes_per_second: 24.0,
            roots: vec![Prim {
                name: "card".into(),
                type_name: "Mesh".into(),
                attributes: vec![(
                    "points".into(),
                    Attribute {
                        type_name: "point3f[]".into(),
                        default: Some(Value::List(
                            [0.1, f64::INFINITY, f64::NEG_INFINITY, -0.0]
                                .map(Value::Number)
                                .into(),
                        )),
                        samples: vec![(1.5, Value::Number(f64::NAN))],
                        metadata: vec![("interpolation".into(), Value::Str("vertex".into()))],
                    },
                )],
                children: Vec::new(),
                inactive_ids: vec![-3, 5],
            }],
        };
        let json = serde_json::to_string(&layer).unwrap();
        let back: Layer = serde_json::from_str(&json).unwrap();
        let a = back.roots[0].attribute("points").unwrap();
        let p = a.default.as_ref().unwrap().numbers().unwrap();
        assert_eq!(p[..3], [0.1, f64::INFINITY, f64::NEG_INFINITY]);
        assert!(p[3] == 0.0 && p[3].is_sign_negative());
        assert!(matches!(a.samples[0], (1.5, Value::Number(x)) if x.is_nan()));
        assert_eq!(a.meta("interpolation"), Some(&Value::Str("vertex".into())));
        assert!(!back.up_y);
        assert_eq!(back.roots[0].inactive_ids, [-3, 5]);
        // A prim without deactivated ids carries no field for them.
        let mut plain = layer;
        plain.roots[0].inactive_ids.clear();
        assert!(!serde_json::to_string(&plain).unwrap().contains("inactive"));
    }
}
