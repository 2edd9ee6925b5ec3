//! What a run directory is checked for before anything is taken from it:
//! the checkpoint's own digest and every field against `run.toml` (counts,
//! ids, the scale, every genome against the prototype's bounds, every number
//! finite), and each generation file against the content hash the
//! checkpoint recorded when it was written. A damage is named by its file,
//! its field and the reason; [`super::run::Run::resume`] repairs what can be
//! recomputed, everything else refuses the directory.
//!
//! The checkpoint's text ends with `,"digest":"<16 hex digits>"}`: the
//! FNV-1a 64 hash ([`super::shard::fnv1a64`]) of the same text without that
//! field. Checked on the raw bytes, so no re-serialisation is trusted.

use super::population::{Checkpoint, Individual};
use super::selection::{MAX_SCALE, MIN_SCALE};
use super::settings::BreedSettings;
use super::shard::fnv1a64;
use crate::leaf::LeafSpec;
use crate::util::number::shown;
use std::path::{Path, PathBuf};

/// What is wrong with a file of a run directory: the file, the field (or
/// line) and the reason.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{}: {field}: {reason}", .file.display())]
pub struct Damage {
    /// The file.
    pub file: PathBuf,
    /// The field or part of it (`population[3].genome.size_factor`).
    pub field: String,
    /// Why it cannot be used.
    pub reason: String,
}

impl Damage {
    pub(crate) fn new(file: &Path, field: impl Into<String>, reason: impl Into<String>) -> Damage {
        Damage {
            file: file.to_path_buf(),
            field: field.into(),
            reason: reason.into(),
        }
    }
}

const DIGEST_KEY: &str = ",\"digest\":\"";
/// The run's settings and prototype, which every checkpoint names.
pub(crate) const RUN_FILE: &str = "run.toml";

/// A content hash as the run directory records it: 16 hex digits of FNV-1a 64.
pub fn content_hash(bytes: &[u8]) -> String {
    format!("{:016x}", fnv1a64(bytes))
}

/// The checkpoint's file text: its JSON with the digest of that JSON as a
/// last field.
pub(crate) fn encode_checkpoint(cp: &Checkpoint) -> Result<String, serde_json::Error> {
    let body = serde_json::to_string(cp)?;
    let digest = content_hash(body.as_bytes());
    // `body` is an object: it ends with '}'.
    Ok(format!(
        "{}{DIGEST_KEY}{digest}\"}}",
        &body[..body.len() - 1]
    ))
}

/// Parses checkpoint text and checks its digest (a checkpoint written
/// before digests existed has none, and is checked field by field only).
pub(crate) fn decode_checkpoint(text: &str, file: &Path) -> Result<Checkpoint, Damage> {
    let body = match text.rfind(DIGEST_KEY) {
        Some(k) if text.ends_with("\"}") => {
            let recorded = &text[k + DIGEST_KEY.len()..text.len() - 2];
            let body = format!("{}}}", &text[..k]);
            let actual = content_hash(body.as_bytes());
            if recorded != actual {
                return Err(Damage::new(
                    file,
                    "digest",
                    format!(
                        "the content hash of the file is {actual}, not the {recorded} recorded \
                         when it was written: it was edited or damaged"
                    ),
                ));
            }
            body
        }
        // The key cannot occur inside a JSON string (its quotes would be
        // escaped there): the file was rewritten by something else.
        Some(_) => {
            return Err(Damage::new(
                file,
                "digest",
                "is not the last field, where leafmagic writes it: the file was rewritten by \
                 another program, so its content hash cannot vouch for it",
            ));
        }
        None => text.to_string(),
    };
    serde_json::from_str(&body).map_err(|e| {
        Damage::new(
            file,
            format!("line {} column {}", e.line(), e.column()),
            format!("not a checkpoint: {e}"),
        )
    })
}

/// Checks every field of a checkpoint against the run's settings and
/// prototype: what a run writes always satisfies, so anything else is
/// damage. `run_toml` is run.toml's bytes, which the checkpoint's hashes
/// name.
pub(crate) fn check_checkpoint(
    cp: &Checkpoint,
    settings: &BreedSettings,
    proto: &LeafSpec,
    run_toml: &[u8],
    file: &Path,
) -> Result<(), Damage> {
    let bad = |field: String, reason: String| Err(Damage::new(file, field, reason));
    // run.toml first: a checkpoint cannot repair the run's definition, so a
    // run.toml that changed under it is refused (a damage of run.toml).
    if let Some(recorded) = cp.fnv1a64.get(RUN_FILE) {
        let actual = content_hash(run_toml);
        if *recorded != actual {
            return Err(Damage::new(
                &file.with_file_name(RUN_FILE),
                "(file)",
                format!(
                    "changed since checkpoint.json was written (content hash {actual}, recorded \
                     {recorded}): a run's settings and prototype cannot change while it runs; \
                     restore it, or start a new run"
                ),
            ));
        }
    }
    if cp.settings != *settings {
        return Err(Damage::new(
            &file.with_file_name(RUN_FILE),
            "settings",
            "differ from those checkpoint.json was written with: the checkpoint belongs to \
             another run, or run.toml was edited; restore it, or start a new run",
        ));
    }
    if cp.generation >= settings.generations {
        return bad(
            "generation".into(),
            format!(
                "{} is not below the run's {} generations",
                cp.generation, settings.generations
            ),
        );
    }
    if cp.history.len() != cp.generation + 1 {
        return bad(
            "history".into(),
            format!(
                "{} summaries for generations 0 to {}",
                cp.history.len(),
                cp.generation
            ),
        );
    }
    for (g, h) in cp.history.iter().enumerate() {
        if h.generation != g {
            return bad(
                format!("history[{g}].generation"),
                format!("is {}, expected {g}", h.generation),
            );
        }
        for (name, v) in [
            ("best_score", h.best_score),
            ("mean_score", h.mean_score),
            ("scale", h.scale),
            ("success_rate", h.success_rate),
        ] {
            if !v.is_finite() {
                return bad(
                    format!("history[{g}].{name}"),
                    format!("{} is not finite", shown(v)),
                );
            }
        }
    }
    if cp.population.len() != settings.population {
        return bad(
            "population".into(),
            format!(
                "{} members, the run's population is {}",
                cp.population.len(),
                settings.population
            ),
        );
    }
    let scale_ok = cp.scale.is_finite()
        && ((MIN_SCALE..=MAX_SCALE).contains(&cp.scale)
            || (cp.generation == 0 && cp.scale == settings.initial_scale));
    if !scale_ok {
        return bad(
            "scale".into(),
            format!(
                "{} is outside the variation scale's range [{MIN_SCALE}, {MAX_SCALE}]",
                shown(cp.scale)
            ),
        );
    }
    let mut previous: Option<u64> = None;
    for (k, i) in cp.population.iter().enumerate() {
        if previous.is_some_and(|p| i.id <= p) {
            return bad(
                format!("population[{k}].id"),
                format!(
                    "{} does not follow {} (ids are in increasing order)",
                    i.id,
                    previous.unwrap_or(0)
                ),
            );
        }
        previous = Some(i.id);
        check_member(i, proto, &format!("population[{k}]"), file)?;
    }
    if previous.is_some_and(|p| cp.next_id <= p) {
        return bad(
            "next_id".into(),
            format!(
                "{} is not above the largest id, {}",
                cp.next_id,
                previous.unwrap_or(0)
            ),
        );
    }
    // The strategy's state: only where the strategy keeps one, and one
    // that can go on (its dimension the genome's, its numbers sane).
    if let Some(state) = &cp.cmaes {
        if matches!(
            settings.strategy,
            super::settings::Strategy::Ga | super::settings::Strategy::Random
        ) {
            return bad(
                "cmaes".into(),
                format!(
                    "a CMA-ES state in a run whose strategy is {}",
                    settings.strategy
                ),
            );
        }
        let n = crate::leaf::genome::Genome::of_prototype(proto)
            .values()
            .len();
        state
            .check(n)
            .map_err(|e| Damage::new(file, format!("cmaes.{}", e.field), e.reason))?;
    } else if settings.strategy == super::settings::Strategy::Cmaes {
        return bad(
            "cmaes".into(),
            "missing: a cmaes run holds its CMA-ES state from generation 0 on".to_string(),
        );
    }
    let cells = super::archive::ARCHIVE_DESCENT_EDGES.len();
    for (k, e) in cp.archive.iter().enumerate() {
        if e.descent_bin >= cells || e.spin_bin >= super::archive::ARCHIVE_SPIN_EDGES.len() {
            return bad(
                format!("archive[{k}]"),
                format!("cell ({}, {}) does not exist", e.descent_bin, e.spin_bin),
            );
        }
        if e.generation > cp.generation {
            return bad(
                format!("archive[{k}].generation"),
                format!(
                    "{} is after the checkpoint's {}",
                    e.generation, cp.generation
                ),
            );
        }
        check_member(
            &e.individual,
            proto,
            &format!("archive[{k}].individual"),
            file,
        )?;
    }
    Ok(())
}

/// One member: its genome within the prototype's bounds, its numbers finite.
fn check_member(i: &Individual, proto: &LeafSpec, at: &str, file: &Path) -> Result<(), Damage> {
    i.genome
        .check(proto)
        .map_err(|e| Damage::new(file, format!("{at}.genome.{}", e.field), e.reason))?;
    let r = i.eval.record();
    let numbers = [
        ("score", r.score),
        ("margin", r.margin),
        ("descent_m_s", r.descent_m_s),
        ("drift_ratio", r.drift_ratio),
        ("net_turns", r.net_turns),
        ("yaw_turns", r.yaw_turns),
        ("spin_rad_s", r.spin_rad_s),
        ("tilt_deg", r.tilt_deg),
        ("dt", r.dt),
        ("distance", r.distance.unwrap_or(0.0)),
        ("release_deg[0]", r.release_deg[0]),
        ("release_deg[1]", r.release_deg[1]),
    ];
    if r.releases == 0 || r.kept > r.releases {
        return Err(Damage::new(
            file,
            format!("{at}.eval.kept"),
            format!(
                "{} of {} releases kept the class: at least one release, and no more kept than dropped",
                r.kept, r.releases
            ),
        ));
    }
    let finite = |name: &str, v: f64| {
        if v.is_finite() {
            Ok(())
        } else {
            Err(Damage::new(
                file,
                format!("{at}.eval.{name}"),
                format!("{} is not finite", shown(v)),
            ))
        }
    };
    for (name, v) in numbers {
        finite(name, v)?;
    }
    for (k, &v) in r.residuals.iter().enumerate() {
        finite(&format!("residuals[{k}]"), v)?;
    }
    Ok(())
}

/// Checks a generation file against the hash its checkpoint recorded.
pub(crate) fn check_generation_file(path: &Path, recorded: &str) -> Result<(), Damage> {
    let bytes = std::fs::read(path)
        .map_err(|e| Damage::new(path, "(file)", format!("cannot be read: {e}")))?;
    let actual = content_hash(&bytes);
    if actual != recorded {
        return Err(Damage::new(
            path,
            "(file)",
            format!(
                "its content hash is {actual}, not the {recorded} that checkpoint.json recorded \
                 when it was written ({} bytes now): truncated, edited or replaced",
                bytes.len()
            ),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_digest_catches_any_edit_and_old_checkpoints_still_read() {
        let proto = LeafSpec::load("a").unwrap();
        let settings = BreedSettings::default_run();
        let plan = super::super::selection::plan(&settings, &proto, None);
        let cp = Checkpoint {
            settings,
            generation: 0,
            population: Vec::new(),
            scale: 1.0,
            next_id: plan.next_id,
            history: Vec::new(),
            archive: Vec::new(),
            cmaes: None,
            fnv1a64: Default::default(),
        };
        let text = encode_checkpoint(&cp).unwrap();
        let file = Path::new("checkpoint.json");
        assert_eq!(decode_checkpoint(&text, file).unwrap(), cp);
        let edited = text.replacen("\"scale\":1.0", "\"scale\":1e308", 1);
        assert_ne!(edited, text);
        assert_eq!(
            decode_checkpoint(&edited, file).unwrap_err().field,
            "digest"
        );
        // Without a digest (a run written before digests): parsed as it is.
        let old = serde_json::to_string(&cp).unwrap();
        assert_eq!(decode_checkpoint(&old, file).unwrap(), cp);
        let cut = &text[..text.len() / 2];
        assert!(
            decode_checkpoint(cut, file)
                .unwrap_err()
                .field
                .starts_with("line")
        );
    }
}
