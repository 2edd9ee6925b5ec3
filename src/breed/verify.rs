//! What a run directory is checked for before anything is taken from it:
//! the checkpoint's own digest and every field against `run.toml` (counts,
//! ids, the scale, every genome against the prototype's bounds, every number
//! finite), and each generation file against the content hash the
//! checkpoint recorded when it was written. A damage is named by its file,
//! its field and the reason; [`super::run::Run::resume`] repairs what can be
//! recomputed, everything else refuses the directory.
//!
//! The checkpoint's text ends with `,"digest":"<16 hex digits>"}`: the
//! FNV-1a 64 hash ([`crate::util::hash::fnv1a64`]) of the checkpoint's other
//! fields in a canonical form ([`checkpoint_digest`]: keys sorted, no
//! spaces). A checkpoint re-saved by another JSON writer (spaces, key
//! order) is checked all the same, and one without a digest is refused.

use super::population::{Checkpoint, Individual};
use super::selection::{MAX_SCALE, MIN_SCALE};
use super::settings::BreedSettings;
use crate::leaf::LeafSpec;
use crate::util::hash::fnv1a64_hex;
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

/// How leafmagic writes the digest (a checkpoint written before the
/// canonical digest hashed its own text up to this key).
const DIGEST_KEY: &str = ",\"digest\":\"";
const DIGEST_FIELD: &str = "digest";
/// The run's settings and prototype, which every checkpoint names.
pub(crate) const RUN_FILE: &str = "run.toml";

/// A content hash as the run directory records it: 16 hex digits of FNV-1a 64.
pub fn content_hash(bytes: &[u8]) -> String {
    fnv1a64_hex(bytes)
}

/// The digest of a checkpoint's JSON (its `digest` field, if any, left
/// out): the content hash of its canonical text, so that how a writer
/// spaced or ordered it does not matter but every value does.
pub fn checkpoint_digest(json: &serde_json::Value) -> String {
    let mut text = String::new();
    canonical(json, true, &mut text);
    content_hash(text.as_bytes())
}

/// Compact JSON with the keys of every object sorted (whatever order the
/// map type keeps); the top level's digest field skipped.
fn canonical(v: &serde_json::Value, top: bool, out: &mut String) {
    use serde_json::Value;
    match v {
        Value::Array(items) => {
            out.push('[');
            for (k, item) in items.iter().enumerate() {
                if k > 0 {
                    out.push(',');
                }
                canonical(item, false, out);
            }
            out.push(']');
        }
        Value::Object(map) => {
            let mut keys: Vec<&String> = map
                .keys()
                .filter(|k| !(top && k.as_str() == DIGEST_FIELD))
                .collect();
            keys.sort();
            out.push('{');
            for (k, key) in keys.into_iter().enumerate() {
                if k > 0 {
                    out.push(',');
                }
                out.push_str(&Value::String(key.clone()).to_string());
                out.push(':');
                canonical(&map[key], false, out);
            }
            out.push('}');
        }
        // Scalars print one way (numbers in their shortest round-trip form).
        other => out.push_str(&other.to_string()),
    }
}

/// The checkpoint's file text: its JSON with the digest of that JSON as a
/// last field.
pub(crate) fn encode_checkpoint(cp: &Checkpoint) -> Result<String, serde_json::Error> {
    let body = serde_json::to_string(cp)?;
    let digest = checkpoint_digest(&serde_json::to_value(cp)?);
    // `body` is an object: it ends with '}'.
    Ok(format!(
        "{}{DIGEST_KEY}{digest}\"}}",
        &body[..body.len() - 1]
    ))
}

/// Parses checkpoint text and checks its digest, which must be there.
pub(crate) fn decode_checkpoint(text: &str, file: &Path) -> Result<Checkpoint, Damage> {
    let json: serde_json::Value = serde_json::from_str(text).map_err(|e| {
        Damage::new(
            file,
            format!("line {} column {}", e.line(), e.column()),
            format!("not a checkpoint: {e}"),
        )
    })?;
    let recorded = match json.get(DIGEST_FIELD) {
        Some(serde_json::Value::String(d)) => d.clone(),
        Some(_) => {
            return Err(Damage::new(
                file,
                DIGEST_FIELD,
                "is not a string of 16 hex digits: the file was edited or damaged",
            ));
        }
        None if !json.is_object() => {
            return Err(Damage::new(
                file,
                "(file)",
                "not a checkpoint: not a JSON object",
            ));
        }
        None => {
            return Err(Damage::new(
                file,
                DIGEST_FIELD,
                "missing: leafmagic writes the content hash of the checkpoint's other fields                  there, and without it an edited checkpoint cannot be told from the one written",
            ));
        }
    };
    let actual = checkpoint_digest(&json);
    if recorded != actual && !legacy_digest_matches(text, &recorded) {
        return Err(Damage::new(
            file,
            DIGEST_FIELD,
            format!(
                "the content hash of the checkpoint's fields is {actual}, not the {recorded}                  recorded when it was written: it was edited or damaged"
            ),
        ));
    }
    serde_json::from_value(json)
        .map_err(|e| Damage::new(file, "(content)", format!("not a checkpoint: {e}")))
}

/// Whether the digest is the one an earlier leafmagic wrote: the hash of
/// the file's own text before `,"digest":…`, exactly as written.
fn legacy_digest_matches(text: &str, recorded: &str) -> bool {
    let suffix = format!("{DIGEST_KEY}{recorded}\"}}");
    text.strip_suffix(&suffix)
        .is_some_and(|body| content_hash(format!("{body}}}").as_bytes()) == recorded)
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
    check_run_file(cp, settings, run_toml, file)?;
    check_history(cp, settings, file)?;
    check_population(cp, settings, proto, file)?;
    check_strategy_state(cp, settings, proto, file)?;
    check_archive(cp, proto, file)
}

/// The run.toml a checkpoint names: its content hash and its settings.
fn check_run_file(
    cp: &Checkpoint,
    settings: &BreedSettings,
    run_toml: &[u8],
    file: &Path,
) -> Result<(), Damage> {
    let bad = |field: String, reason: String| Err(Damage::new(file, field, reason));
    // run.toml first: a checkpoint cannot repair the run's definition, so a
    // run.toml that changed under it is refused (a damage of run.toml).
    let Some(recorded) = cp.fnv1a64.get(RUN_FILE) else {
        return bad(
            format!("fnv1a64.\"{RUN_FILE}\""),
            format!(
                "missing: every checkpoint records the content hash of {RUN_FILE}, which the \
                 run's files are checked against"
            ),
        );
    };
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
    if cp.settings != *settings {
        return Err(Damage::new(
            &file.with_file_name(RUN_FILE),
            "settings",
            "differ from those checkpoint.json was written with: the checkpoint belongs to \
             another run, or run.toml was edited; restore it, or start a new run",
        ));
    }
    Ok(())
}

/// The generation and one finite summary for each generation up to it.
fn check_history(cp: &Checkpoint, settings: &BreedSettings, file: &Path) -> Result<(), Damage> {
    let bad = |field: String, reason: String| Err(Damage::new(file, field, reason));
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
    Ok(())
}

/// The population: its size, variation scale, increasing ids and members.
fn check_population(
    cp: &Checkpoint,
    settings: &BreedSettings,
    proto: &LeafSpec,
    file: &Path,
) -> Result<(), Damage> {
    let bad = |field: String, reason: String| Err(Damage::new(file, field, reason));
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
    Ok(())
}

/// The strategy's state: only where the strategy keeps one, and one that
/// can go on.
fn check_strategy_state(
    cp: &Checkpoint,
    settings: &BreedSettings,
    proto: &LeafSpec,
    file: &Path,
) -> Result<(), Damage> {
    let bad = |field: String, reason: String| Err(Damage::new(file, field, reason));
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
    Ok(())
}

/// The archive: cells that exist, generations up to the checkpoint's, sane
/// members.
fn check_archive(cp: &Checkpoint, proto: &LeafSpec, file: &Path) -> Result<(), Damage> {
    let bad = |field: String, reason: String| Err(Damage::new(file, field, reason));
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
        ("spread[0]", r.spread[0]),
        ("spread[1]", r.spread[1]),
        ("spread[2]", r.spread[2]),
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
    fn the_digest_catches_any_edit_however_the_file_is_spaced_and_is_required() {
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
            fnv1a64: [(RUN_FILE.to_string(), "0123456789abcdef".to_string())].into(),
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
        // Re-saved by another writer (spaces, newlines): still checked.
        let v: serde_json::Value = serde_json::from_str(&text).unwrap();
        let pretty = serde_json::to_string_pretty(&v).unwrap();
        assert!(pretty.contains("\"digest\": \""));
        assert_eq!(decode_checkpoint(&pretty, file).unwrap(), cp);
        let edited = pretty.replacen("\"scale\": 1.0", "\"scale\": 2.0", 1);
        assert_ne!(edited, pretty);
        assert_eq!(
            decode_checkpoint(&edited, file).unwrap_err().field,
            "digest"
        );
        // The hash written before the canonical form (the text as written).
        let body = serde_json::to_string(&cp).unwrap();
        let old = format!(
            "{}{DIGEST_KEY}{}\"}}",
            &body[..body.len() - 1],
            content_hash(body.as_bytes())
        );
        assert_eq!(decode_checkpoint(&old, file).unwrap(), cp);
        // Without a digest: refused, not read as it is.
        let damage = decode_checkpoint(&body, file).unwrap_err();
        assert_eq!(damage.field, "digest");
        assert!(damage.reason.starts_with("missing"), "{damage}");
        let cut = &text[..text.len() / 2];
        assert!(
            decode_checkpoint(cut, file)
                .unwrap_err()
                .field
                .starts_with("line")
        );
    }
}
