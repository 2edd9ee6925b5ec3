//! What a search leaves on disk: the solved scene (a plain scene file
//! `leafmagic scene` runs and exports), the history of every run, and the
//! checkpoint a killed search resumes from, each written atomically, the
//! same bytes for the same input and seed.

use super::problem::Problem;
use super::search::{Outcome, Settings, State};
use crate::util::bad_input::BadInput;
use crate::util::io::write_atomic;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The checkpoint's name in the output directory.
pub const CHECKPOINT_FILE: &str = "checkpoint.json";

/// What a search was started on and where it stands after its last whole
/// batch: rewritten after every batch, kept when the search ends.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Checkpoint {
    /// The scene file as named when the search began.
    pub scene: String,
    /// The hash of its bytes ([`crate::breed::verify::content_hash`]): an
    /// edited file is a different problem.
    pub scene_hash: String,
    /// [`Settings::budget`].
    pub budget: usize,
    /// [`Settings::seed`] (the thread count is free: it changes no byte).
    pub seed: u64,
    /// Where the search stands.
    pub state: State,
}

/// Writes `checkpoint` as `out/checkpoint.json` (made if missing),
/// atomically: a kill leaves the previous batch's or this one's.
///
/// # Errors
/// A file that cannot be written.
pub fn write_checkpoint(out: &Path, checkpoint: &Checkpoint) -> std::io::Result<()> {
    std::fs::create_dir_all(out)?;
    let json = serde_json::to_vec(checkpoint).map_err(std::io::Error::other)?;
    write_atomic(&out.join(CHECKPOINT_FILE), &json)
}

/// Reads `dir/checkpoint.json`.
///
/// # Errors
/// A file that is missing, unreadable or not a checkpoint, named.
pub fn read_checkpoint(dir: &Path) -> Result<Checkpoint, BadInput> {
    let path = dir.join(CHECKPOINT_FILE);
    let refuse = |reason: String| BadInput {
        file: path.display().to_string(),
        line: None,
        field: "checkpoint".into(),
        reason,
    };
    let text = std::fs::read_to_string(&path).map_err(|e| {
        refuse(format!(
            "cannot be read ({e}): is this the output directory of a search?"
        ))
    })?;
    serde_json::from_str(&text).map_err(|e| BadInput {
        file: path.display().to_string(),
        line: Some(e.line()),
        field: "checkpoint".into(),
        reason: format!("not a search's checkpoint: {e}"),
    })
}

/// The solved scene's text: the best values in place, `[[free]]` removed,
/// a header saying how it was found and how well it meets each goal.
pub fn solved(problem: &Problem, settings: &Settings, outcome: &Outcome) -> String {
    let best = outcome.best();
    let mut header = vec![
        format!(
            "Solved from {} by CMA-ES: {} scene runs, seed {}.",
            problem.file,
            outcome.history.len() / 2,
            settings.seed
        ),
        "The free values found (their bounds):".to_string(),
    ];
    for (f, v) in problem.free.iter().zip(&best.values) {
        header.push(format!(
            "  {} = {v} ({} to {}; the file had {})",
            f.parameter, f.min, f.max, f.written
        ));
    }
    header.push("The goals (kept below; `leafmagic scene` ignores them):".to_string());
    for (g, r) in problem.goals.iter().zip(&best.evaluation.goals) {
        header.push(format!(
            "  {}: {:.0} % of {} leaves met it, mean distance {:.4} m",
            g.name,
            100.0 * r.met_fraction,
            g.leaves.len(),
            r.mean_distance
        ));
    }
    problem.solved_toml(&best.values, &header)
}

/// The history as CSV: one row per run, `evaluation,search,generation`,
/// the free values, the objective, each goal's met fraction and mean
/// distance, and why a run failed.
pub fn history(problem: &Problem, outcome: &Outcome) -> Vec<u8> {
    let mut w = csv::Writer::from_writer(Vec::new());
    let mut head: Vec<String> = vec!["evaluation".into(), "search".into(), "generation".into()];
    head.extend(problem.free.iter().map(|f| f.parameter.clone()));
    head.push("objective".into());
    for g in &problem.goals {
        head.push(format!("met:{}", g.name));
        head.push(format!("distance:{}", g.name));
    }
    head.push("failed".into());
    w.write_record(&head).expect("writing to memory");
    for (k, r) in outcome.history.iter().enumerate() {
        let mut row: Vec<String> = vec![
            k.to_string(),
            r.method.name().into(),
            r.generation.to_string(),
        ];
        row.extend(r.values.iter().map(|v| v.to_string()));
        row.push(r.evaluation.objective.to_string());
        for g in &r.evaluation.goals {
            row.push(g.met_fraction.to_string());
            row.push(g.mean_distance.to_string());
        }
        row.push(r.evaluation.failed.clone().unwrap_or_default());
        w.write_record(&row).expect("writing to memory");
    }
    w.into_inner().expect("writing to memory")
}

/// Writes `solved.toml` and `history.csv` into `out` (made if missing);
/// returns their paths.
///
/// # Errors
/// A file that cannot be written.
pub fn write(
    out: &Path,
    problem: &Problem,
    settings: &Settings,
    outcome: &Outcome,
) -> std::io::Result<Vec<PathBuf>> {
    std::fs::create_dir_all(out)?;
    let solved_path = out.join("solved.toml");
    write_atomic(&solved_path, solved(problem, settings, outcome).as_bytes())?;
    let history_path = out.join("history.csv");
    write_atomic(&history_path, &history(problem, outcome))?;
    Ok(vec![solved_path, history_path])
}
