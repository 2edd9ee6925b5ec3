//! `leafmagic studio`: opens or creates a session and serves it.

use super::args::StudioArgs;
use anyhow::{Context, Result};
use leafmagic::leaf::LeafSpec;
use leafmagic::studio::{Server, Session, StudioSettings};
use std::io::Write;
use std::path::{Path, PathBuf};

/// Runs the studio until the process is stopped.
pub fn studio(args: StudioArgs) -> Result<()> {
    let session = match &args.resume {
        Some(dir) => Session::open(dir)?,
        None => {
            let proto = LeafSpec::load(&args.prototype)
                .with_context(|| format!("--prototype {}", args.prototype))?;
            let proto = match args.law {
                Some(law) => proto.under_law(law.law()),
                None => proto,
            };
            let settings = StudioSettings {
                grid: args.grid,
                seconds: args.seconds,
                ..StudioSettings::new(&args.prototype, args.target, args.seed)
            };
            settings.validate()?;
            // The example is read (and checked) before anything is bred.
            let example = match &args.like {
                Some(path) => Some((
                    path.display().to_string(),
                    super::input::read_record(
                        path,
                        super::input::CsvUnits::default(),
                        super::input::Pick::default(),
                    )
                    .with_context(|| format!("--like {}", path.display()))?,
                )),
                None => None,
            };
            let new_session = |dir: &Path| -> Result<Session> {
                let mut session = create(dir, settings.clone(), proto.clone())?;
                if let Some((name, record)) = &example {
                    session
                        .set_example(name, &record.trajectory)
                        .with_context(|| format!("--like {name}"))?;
                }
                Ok(session)
            };
            match &args.out {
                Some(dir) => new_session(dir)?,
                // The default folder is named by prototype and seed: running
                // `studio` again with the same settings reopens it where it
                // was, as an animator coming back expects.
                None => {
                    let dir = default_dir(
                        &args.prototype,
                        args.law.map(|l| super::args::law_word(l.law())),
                        args.seed,
                    );
                    if dir.join(leafmagic::studio::session::SESSION_FILE).exists() {
                        let session = Session::open(&dir)?;
                        if session.file().settings != settings
                            || session.prototype().aero.law != proto.aero.law
                            || args.like.is_some()
                        {
                            anyhow::bail!(
                                "{} holds a session with other settings; reopen it with --resume {}, or start another with --out DIR",
                                dir.display(),
                                dir.display()
                            );
                        }
                        eprintln!(
                            "studio: reopening {} where it was (--out DIR starts another session)",
                            dir.display()
                        );
                        session
                    } else {
                        new_session(&dir)?
                    }
                }
            }
        }
    };
    let server = Server::bind(args.port).context("could not listen on 127.0.0.1")?;
    let url = server.url();
    // The URL on stdout, alone on its line and last, for a person or a
    // script (which may stop reading after it).
    let mut out = std::io::stdout().lock();
    writeln!(out, "session: {}", session.dir().display())?;
    writeln!(out, "studio: {url}")?;
    out.flush()?;
    drop(out);
    if args.open {
        // Best effort: without a desktop the URL above is the way in.
        let _ = std::process::Command::new("xdg-open").arg(&url).spawn();
    }
    server.serve(session).context("the studio's server stopped")
}

/// A new session in `dir`, generation 0 bred.
fn create(dir: &Path, settings: StudioSettings, proto: LeafSpec) -> Result<Session> {
    eprintln!(
        "studio: breeding generation 0 ({} candidates) in {}",
        settings.grid,
        dir.display()
    );
    Ok(Session::create(dir, settings, proto)?)
}

/// `runs/studio-<prototype>-s<seed>`, a file prototype by its stem, with
/// `-<law>` after it when `--law` is given (`studio-a-real-s1991`).
fn default_dir(prototype: &str, law: Option<&str>, seed: u64) -> PathBuf {
    let stem = Path::new(prototype)
        .file_stem()
        .map_or("leaf".into(), |s| s.to_string_lossy());
    let name: String = stem
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' {
                c
            } else {
                '_'
            }
        })
        .collect();
    let law = law.map(|l| format!("-{l}")).unwrap_or_default();
    PathBuf::from("runs").join(format!("studio-{name}{law}-s{seed}"))
}
