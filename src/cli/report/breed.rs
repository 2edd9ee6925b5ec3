//! The human reports of `breed`, `shard` and `merge`: the table of
//! generations, the best leaf beside its target, and where a run and its
//! shards stand.

use super::text;
use leafmagic::breed::GenerationSummary;
use leafmagic::breed::population::OutcomeKind;
use leafmagic::breed::worker::Outcome;
use leafmagic::motion::describe::{self, Descriptors};
use std::fmt::Write as _;
use std::path::Path;

/// A line per generation: the count of each class, best and mean score,
/// the best's robustness (how many of its releases kept the class) and the
/// mutation scale; toward a class, how many leaves of it, kept by every
/// release, fall pairwise apart (`apart`: what improves once the class is
/// held); with `like`, the best individual's distance to the target
/// instead.
pub fn generations(history: &[GenerationSummary], like: bool) -> String {
    text(|out| {
        write!(
            out,
            "{:>3}  {:>7} {:>7} {:>6} {:>6} {:>6}  {:>10} {:>5} {:>10} {:>6}",
            "gen",
            "floater",
            "spinner",
            "lilter",
            "undet.",
            "diverg",
            "best",
            "kept",
            "mean",
            "scale"
        )?;
        writeln!(out, "{}", if like { "  best dist." } else { "  apart" })?;
        for h in history {
            let c = h.counts;
            let kept = format!("{}/{}", h.best_kept, h.releases);
            write!(
                out,
                "{:>3}  {:>7} {:>7} {:>6} {:>6} {:>6}  {:>10.4} {:>5} {:>10.4} {:>6.3}",
                h.generation,
                c[OutcomeKind::Floater],
                c[OutcomeKind::Spinner],
                c[OutcomeKind::Lilter],
                c[OutcomeKind::Undetermined],
                c[OutcomeKind::Diverged],
                h.best_score,
                kept,
                h.mean_score,
                h.scale
            )?;
            if like {
                write!(
                    out,
                    "  {:>11}",
                    h.best_distance
                        .map_or("∞".to_string(), |d| format!("{d:.4}"))
                )?;
            } else {
                write!(out, "  {:>5}", h.distinct)?;
            }
            writeln!(out)?;
        }
        Ok(())
    })
}

/// The best leaf (`id`) of a `--like` or `--target-features` run has no
/// descriptors: its fall is undetermined (one line, without its newline).
pub fn undescribed_best(id: u64) -> String {
    format!("best leaf {id}: undetermined, no descriptors")
}

/// The descriptors of the run's `reference` (`example` or `target`) beside
/// the best leaf's, and its distance to the target (`None`: not of the
/// target's class).
pub fn like(
    (reference, wanted): (&str, &Descriptors),
    (id, best): (u64, &Descriptors),
    distance: Option<f64>,
) -> String {
    let label = format!("leaf {id}");
    text(|out| {
        out.push_str(&describe::table(&[
            (reference, wanted),
            (label.as_str(), best),
        ]));
        match distance {
            Some(d) => writeln!(out, "distance    {d:.4}"),
            None => writeln!(out, "distance    ∞ (the best is not of the target's class)"),
        }
    })
}

/// Where the run is (one line, without its newline).
pub fn run_directory(dir: &Path) -> String {
    format!("run directory: {}", dir.display())
}

/// Where the run is after `merge` of `generation`, and whether it is
/// complete (one line, without its newline).
pub fn merged(dir: &Path, generation: usize, complete: bool) -> String {
    format!(
        "run directory: {} ({})",
        dir.display(),
        if complete {
            "complete".to_string()
        } else {
            format!("next: generation {}", generation + 1)
        }
    )
}

/// `merge` of a generation the checkpoint already holds (one line, without
/// its newline).
pub fn already_merged(generation: usize, checkpoint: usize) -> String {
    format!(
        "generation {generation} is already merged (checkpoint.json holds generation {checkpoint}): nothing to do"
    )
}

/// What `shard` did with shard `index` of `count` of `generation`, in
/// `elapsed_s` (one line, without its newline).
pub fn shard(
    generation: usize,
    (index, count): (usize, usize),
    outcome: &Outcome,
    elapsed_s: f64,
) -> String {
    let (g, i, n) = (generation, index, count);
    match outcome {
        Outcome::Evaluated(k, path) => format!(
            "generation {g}, shard {i} of {n}: {k} individuals in {elapsed_s:.3} s -> {}",
            path.display()
        ),
        Outcome::AlreadyDone(path) => format!(
            "generation {g}, shard {i} of {n}: already done ({})",
            path.display()
        ),
    }
}
