//! The files of a run directory that are tables: `generations.csv`,
//! `gen-NNN.csv`, leaf files with their `index.csv`; and the clean-up of
//! temporaries a killed writer left.

use super::population::{BreedError, GenerationSummary, Individual, OutcomeKind, io_err};
use crate::leaf::LeafSpec;
use crate::util::io::write_atomic;
use std::fmt::Write as _;
use std::path::Path;

/// generations.csv: one row per completed generation.
pub fn generations_csv(history: &[GenerationSummary]) -> String {
    let mut out = String::from("generation");
    for kind in OutcomeKind::ALL {
        out.push(',');
        out.push_str(kind.name());
    }
    out.push_str(
        ",best_score,mean_score,best_id,scale,success_rate,best_distance,best_kept,releases,distinct\n",
    );
    for h in history {
        let _ = write!(out, "{}", h.generation);
        for (_, count) in h.counts.iter() {
            let _ = write!(out, ",{count}");
        }
        let _ = writeln!(
            out,
            ",{},{},{},{},{},{},{},{},{}",
            h.best_score,
            h.mean_score,
            h.best_id,
            h.scale,
            h.success_rate,
            h.best_distance.map_or(String::new(), |d| d.to_string()),
            h.best_kept,
            h.releases,
            h.distinct
        );
    }
    out
}

/// gen-NNN.csv: one row per individual, in id order.
pub fn population_csv(generation: usize, population: &[Individual]) -> String {
    let mut out = String::from("generation,id,parent,elite");
    if let Some(first) = population.first() {
        for (name, _) in first.genome.values() {
            let _ = write!(out, ",{name}");
        }
    }
    out.push_str(
        ",class,regime,score,margin,descent_m_s,drift_ratio,net_turns,yaw_turns,reversals,flips,tilt_deg,dt,distance,releases,kept,release_x_deg,release_y_deg,spread_descent_m_s,spread_drift_ratio,spread_spin_rad_s,error\n",
    );
    for i in population {
        let parent = i.parent.map_or(String::new(), |p| p.to_string());
        let _ = write!(out, "{generation},{},{parent},{}", i.id, i.elite);
        for (_, v) in i.genome.values() {
            let _ = write!(out, ",{v}");
        }
        let e = &i.eval.record();
        // Errors may contain commas: quote them for CSV.
        let error = if e.error.is_empty() {
            String::new()
        } else {
            format!("\"{}\"", e.error.replace('"', "\"\""))
        };
        let _ = writeln!(
            out,
            ",{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
            e.class,
            e.regime,
            e.score,
            e.margin,
            e.descent_m_s,
            e.drift_ratio,
            e.net_turns,
            e.yaw_turns,
            e.reversals,
            e.flips,
            e.tilt_deg,
            e.dt,
            e.distance.map_or(String::new(), |d| d.to_string()),
            e.releases,
            e.kept,
            e.release_deg[0],
            e.release_deg[1],
            e.spread[0],
            e.spread[1],
            e.spread[2],
            error
        );
    }
    out
}

/// Writes each individual as `leaf-<id>.toml` plus `index.csv` into `dir`.
pub fn export_leaves(
    proto: &LeafSpec,
    chosen: &[&Individual],
    dir: &Path,
) -> Result<(), BreedError> {
    let mut index = String::from(
        "rank,id,file,class,regime,score,descent_m_s,kept,releases,release_x_deg,release_y_deg\n",
    );
    for (rank, ind) in chosen.iter().enumerate() {
        let e = ind.eval.record();
        // Never an invalid leaf file: the genome within its bounds, the
        // leaf a valid model (a resumed run checks genomes already).
        let invalid = |message: String| BreedError::Leaf {
            id: ind.id,
            message,
        };
        ind.genome
            .check(proto)
            .map_err(|e| invalid(format!("genome: {e}")))?;
        let mut leaf = ind.genome.to_leaf(proto);
        leaf.model()
            .map_err(|e| invalid(format!("not a valid leaf: {e}")))?;
        leaf.name = format!("{}-{}", proto.name, ind.id);
        let file = format!("leaf-{}.toml", ind.id);
        let text = format!(
            "# Bred by leafmagic from {}: individual {} ({} / {}, score {}).\n\
             # Robustness: {} of {} release attitudes kept the class; the class and score are \
             those of the lower-median drop, released at ({}°, {}°).\n{}",
            proto.name,
            ind.id,
            e.class,
            e.regime,
            e.score,
            e.kept,
            e.releases,
            e.release_deg[0],
            e.release_deg[1],
            leaf.to_toml()
        );
        let path = dir.join(&file);
        write_atomic(&path, text.as_bytes()).map_err(|e| io_err(&path, e))?;
        let _ = writeln!(
            index,
            "{},{},{},{},{},{},{},{},{},{},{}",
            rank + 1,
            ind.id,
            file,
            e.class,
            e.regime,
            e.score,
            e.descent_m_s,
            e.kept,
            e.releases,
            e.release_deg[0],
            e.release_deg[1]
        );
    }
    let path = dir.join("index.csv");
    write_atomic(&path, index.as_bytes()).map_err(|e| io_err(&path, e))
}

/// Removes `.<name>.<pid>.tmp` files (see [`crate::util::io::write_atomic`]).
pub(crate) fn remove_stale_temporaries(dir: &Path) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        if name.starts_with('.') && name.ends_with(".tmp") {
            let _ = std::fs::remove_file(e.path());
        }
    }
}
