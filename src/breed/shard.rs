//! Shards: the unit of distribution of a breeding run. Evaluating one
//! generation is embarrassingly parallel, so a generation's children are
//! split into `count` shards and each shard can be evaluated by any process
//! that can read the run directory (`leafmagic shard RUN_DIR --generation G`),
//! on this machine or another one sharing the directory. leafmagic has no
//! cluster protocol of its own: the run directory is the protocol.
//!
//! The split, by position in id order: the k-th child of generation G (its
//! children are numbered consecutively, so k = id − first id) belongs to
//! shard k mod count. Round-robin rather than blocks, so that the shards of
//! a generation whose cost drifts with the id still finish together.
//!
//! A shard file, `RUN_DIR/shards/gen-GGG/shard-III-of-NNN.jsonl`, is JSON
//! lines: a header (format version, generation, index, count, and a hash of
//! the shard's planned children, so a file computed from another checkpoint
//! is never taken for this one), one row per child in id order
//! (`{"id":…,"eval":{…}}`, floats in shortest round-trip form, so the merge
//! gets the very bits a local evaluation would have), and a footer with the
//! row count and the FNV-1a 64 checksum of every byte before the footer.
//! A truncated or corrupt file fails one of these checks and is re-evaluated,
//! never merged. The bytes depend only on the run directory, the generation
//! and the split, so running a shard twice writes the same file.

use super::population::{Child, Evaluation, Plan};
use crate::util::hash::fnv1a64_hex;
use crate::util::setting::Setting;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The directory of the run directory that holds shard files.
pub const SHARDS_DIR: &str = "shards";

/// Version of the shard file format (the header's `leafmagic_shard`).
pub const FORMAT: u32 = 1;

/// Which part of a generation one process evaluates: shard `index` of
/// `count` (0 ≤ index < count).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Split {
    /// This shard, from 0.
    pub index: usize,
    /// Shards in the generation.
    pub count: usize,
}

impl Split {
    /// The children of `children` (in id order) that this shard evaluates:
    /// positions index, index + count, index + 2·count, …
    pub fn members<'a>(&self, children: &'a [Child]) -> Vec<&'a Child> {
        children
            .iter()
            .skip(self.index)
            .step_by(self.count)
            .collect()
    }
}

/// `RUN_DIR/shards/gen-GGG`: the shard files and logs of one generation.
pub fn generation_dir(run_dir: &Path, generation: usize) -> PathBuf {
    run_dir
        .join(SHARDS_DIR)
        .join(format!("gen-{generation:03}"))
}

/// `RUN_DIR/shards/gen-GGG/shard-III-of-NNN.jsonl`.
pub fn shard_path(run_dir: &Path, generation: usize, split: Split) -> PathBuf {
    generation_dir(run_dir, generation).join(format!(
        "shard-{:03}-of-{:03}.jsonl",
        split.index, split.count
    ))
}

/// `RUN_DIR/shards/gen-GGG/shard-III-of-NNN.log`: where an executor sends a
/// shard process's output (appended to by every attempt).
pub fn log_path(run_dir: &Path, generation: usize, split: Split) -> PathBuf {
    generation_dir(run_dir, generation).join(format!(
        "shard-{:03}-of-{:03}.log",
        split.index, split.count
    ))
}

/// Removes the shard files of generations up to `merged` (their results are
/// in the checkpoint), and `shards/` itself once it is empty, so that a run
/// directory ends the same whichever executor filled it. Shards of later
/// generations (a driver killed mid-generation) are kept: they are reused.
/// Failures are ignored: leftovers are removed by the next run, never read.
pub fn remove_merged(run_dir: &Path, merged: Option<usize>) {
    let root = run_dir.join(SHARDS_DIR);
    let Ok(entries) = std::fs::read_dir(&root) else {
        return;
    };
    for e in entries.flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        let done = name
            .strip_prefix("gen-")
            .and_then(|g| g.parse::<usize>().ok())
            .is_some_and(|g| merged.is_some_and(|m| g <= m));
        if done {
            let _ = std::fs::remove_dir_all(e.path());
        }
    }
    // Only succeeds when empty.
    let _ = std::fs::remove_dir(&root);
}

/// Hash of what a shard evaluates (ids, parents, genomes), hex: ties a
/// shard file to the checkpoint it was planned from.
pub fn plan_hash(members: &[&Child]) -> String {
    #[derive(Serialize)]
    struct Planned<'a> {
        id: u64,
        parent: Option<u64>,
        genome: &'a crate::leaf::genome::Genome,
    }
    let planned: Vec<Planned> = members
        .iter()
        .map(|c| Planned {
            id: c.id,
            parent: c.parent,
            genome: &c.genome,
        })
        .collect();
    let json = serde_json::to_string(&planned).expect("genomes serialise");
    fnv1a64_hex(json.as_bytes())
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct Header {
    leafmagic_shard: u32,
    generation: usize,
    index: usize,
    count: usize,
    plan: String,
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct Row {
    id: u64,
    eval: Evaluation,
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct Footer {
    rows: usize,
    fnv1a64: String,
}

/// The content of one shard file.
#[derive(Clone, Debug, PartialEq)]
pub struct ShardFile {
    /// The generation.
    pub generation: usize,
    /// Which shard.
    pub split: Split,
    /// [`plan_hash`] of its members.
    pub plan: String,
    /// (id, evaluation) per member, in id order.
    pub rows: Vec<(u64, Evaluation)>,
}

/// The file's bytes. Fails, naming the individual, if an evaluation would
/// not read back bit for bit (a non-finite float, which JSON cannot carry:
/// checkpoint.json could not hold it either).
pub fn encode(shard: &ShardFile) -> Result<String, ShardFileError> {
    let mut out = serde_json::to_string(&Header {
        leafmagic_shard: FORMAT,
        generation: shard.generation,
        index: shard.split.index,
        count: shard.split.count,
        plan: shard.plan.clone(),
    })
    .map_err(|e| e.to_string())?;
    out.push('\n');
    for (id, eval) in &shard.rows {
        let line = serde_json::to_string(&Row {
            id: *id,
            eval: eval.clone(),
        })
        .map_err(|e| format!("individual {id}: {e}"))?;
        let back: Row = serde_json::from_str(&line)
            .map_err(|e| format!("individual {id}: its evaluation does not read back: {e}"))?;
        if back.eval != *eval {
            return Err(ShardFileError(format!(
                "individual {id}: its evaluation does not read back exactly (a non-finite number?)"
            )));
        }
        out.push_str(&line);
        out.push('\n');
    }
    let footer = Footer {
        rows: shard.rows.len(),
        fnv1a64: fnv1a64_hex(out.as_bytes()),
    };
    out.push_str(&serde_json::to_string(&footer).map_err(|e| e.to_string())?);
    out.push('\n');
    Ok(out)
}

/// Parses and checks a shard file's bytes: header, one JSON row per line,
/// footer present (else: truncated), row count and checksum as the footer
/// says. The reason names the line.
pub fn decode(text: &str) -> Result<ShardFile, ShardFileError> {
    if !text.ends_with('\n') {
        return Err(ShardFileError(
            "truncated: the last line is incomplete".to_string(),
        ));
    }
    let body = &text[..text.len() - 1];
    let (before, footer_line) = match body.rfind('\n') {
        Some(k) => (&text[..k + 1], &body[k + 1..]),
        None => return Err(ShardFileError("truncated: no footer line".to_string())),
    };
    let footer: Footer = serde_json::from_str(footer_line)
        .map_err(|e| format!("truncated or corrupt: the last line is not the footer ({e})"))?;
    let sum = fnv1a64_hex(before.as_bytes());
    if sum != footer.fnv1a64 {
        return Err(ShardFileError(format!(
            "corrupt: checksum {sum} differs from the footer's {}",
            footer.fnv1a64
        )));
    }
    let mut lines = before.lines();
    let header: Header = serde_json::from_str(lines.next().unwrap_or_default())
        .map_err(|e| format!("line 1: not a shard header ({e})"))?;
    if header.leafmagic_shard != FORMAT {
        return Err(ShardFileError(format!(
            "line 1: shard format {} (this leafmagic reads {FORMAT})",
            header.leafmagic_shard
        )));
    }
    let mut rows = Vec::new();
    for (k, line) in lines.enumerate() {
        let row: Row =
            serde_json::from_str(line).map_err(|e| format!("line {}: bad row ({e})", k + 2))?;
        rows.push((row.id, row.eval));
    }
    if rows.len() != footer.rows {
        return Err(ShardFileError(format!(
            "{} rows, the footer says {}",
            rows.len(),
            footer.rows
        )));
    }
    Ok(ShardFile {
        generation: header.generation,
        split: Split {
            index: header.index,
            count: header.count,
        },
        plan: header.plan,
        rows,
    })
}

/// A shard file that cannot be written or read back: the reason, naming
/// the line or the individual.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct ShardFileError(pub String);

impl From<String> for ShardFileError {
    fn from(reason: String) -> ShardFileError {
        ShardFileError(reason)
    }
}

/// A shard index or count that the flags and the environment do not give:
/// names the flag or variable.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct SplitError(pub String);

impl From<String> for SplitError {
    fn from(reason: String) -> SplitError {
        SplitError(reason)
    }
}

/// Why a shard's results cannot be merged.
#[derive(Clone, Debug, PartialEq)]
pub enum Problem {
    /// No shard file (not run yet, or the task died before writing it).
    Missing,
    /// A file that fails a check: truncated, corrupt, or of another plan.
    Invalid(String),
}

impl std::fmt::Display for Problem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Problem::Missing => write!(f, "no shard file"),
            Problem::Invalid(reason) => write!(f, "{reason}"),
        }
    }
}

/// The evaluations of shard `split` of `plan`'s generation, in member
/// order, if its file is whole and belongs to this plan.
pub fn read_valid(run_dir: &Path, plan: &Plan, split: Split) -> Result<Vec<Evaluation>, Problem> {
    let path = shard_path(run_dir, plan.generation, split);
    let bytes = match std::fs::read(&path) {
        Ok(b) => b,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Err(Problem::Missing),
        Err(e) => return Err(Problem::Invalid(format!("unreadable: {e}"))),
    };
    let text =
        String::from_utf8(bytes).map_err(|_| Problem::Invalid("corrupt: not UTF-8".to_string()))?;
    let shard = decode(&text).map_err(|e| Problem::Invalid(e.0))?;
    let members = split.members(&plan.children);
    if shard.generation != plan.generation || shard.split != split {
        return Err(Problem::Invalid(format!(
            "the header says generation {} shard {} of {}",
            shard.generation, shard.split.index, shard.split.count
        )));
    }
    if shard.plan != plan_hash(&members) {
        return Err(Problem::Invalid(
            "planned from another checkpoint (plan hash differs)".to_string(),
        ));
    }
    let ids: Vec<u64> = members.iter().map(|c| c.id).collect();
    let got: Vec<u64> = shard.rows.iter().map(|(id, _)| *id).collect();
    if ids != got {
        return Err(Problem::Invalid(format!(
            "ids {got:?}, the split gives {ids:?}"
        )));
    }
    Ok(shard.rows.into_iter().map(|(_, e)| e).collect())
}

/// Where a shard's index and count come from: the `--index`/`--count`
/// flags, else the environment of the common array-job engines.
///
/// | engine | index | count |
/// |---|---|---|
/// | `srun` step | `SLURM_PROCID` | `SLURM_NTASKS` |
/// | Slurm job array (`--array=0-(N-1)`) | `SLURM_ARRAY_TASK_ID` | `SLURM_ARRAY_TASK_COUNT` |
/// | Kubernetes Indexed Job | `JOB_COMPLETION_INDEX` | `--count` |
/// | AWS Batch array job | `AWS_BATCH_JOB_ARRAY_INDEX` | `--count` |
///
/// `--index` (which needs `--count`) overrides the environment. `--count`
/// given alone overrides any count from the environment (so an array of a
/// subset, `--array=3,5 … --count 7`, reruns shards 3 and 5 of 7). Several
/// engines' variables may be set at once (a batch script of an array sets
/// `SLURM_PROCID=0`); they must agree on the index, except that a one-task
/// `srun` step (`SLURM_NTASKS=1`) is no split and yields to the others. No
/// index, disagreeing indices, a missing count or an index not below the
/// count are errors naming the variables.
pub fn resolve_split(
    index: Option<usize>,
    count: Option<usize>,
    var: impl Fn(&str) -> Option<String>,
) -> Result<Split, SplitError> {
    let check = |index: usize, count: usize, from: &str| -> Result<Split, SplitError> {
        if count == 0 {
            Err(SplitError(format!(
                "{from}: the shard count must be at least 1"
            )))
        } else if index >= count {
            Err(SplitError(format!(
                "{from}: shard index {index} is not below the shard count {count} (indices run from 0)"
            )))
        } else {
            Ok(Split { index, count })
        }
    };
    if let Some(index) = index {
        let count = count
            .ok_or_else(|| SplitError(format!("{} needs {}", Setting::Index, Setting::Count)))?;
        return check(
            index,
            count,
            &format!("{}/{}", Setting::Index, Setting::Count),
        );
    }
    let num = |name: &str| -> Result<Option<usize>, SplitError> {
        match var(name) {
            None => Ok(None),
            Some(v) if v.trim().is_empty() => Ok(None),
            Some(v) => v
                .trim()
                .parse::<usize>()
                .map(Some)
                .map_err(|_| SplitError(format!("{name}={v:?} is not a non-negative integer"))),
        }
    };
    struct Found {
        what: String,
        index: usize,
        count: Option<usize>,
        single_step: bool,
    }
    let mut found = Vec::new();
    if let (Some(p), Some(n)) = (num("SLURM_PROCID")?, num("SLURM_NTASKS")?) {
        found.push(Found {
            what: format!("SLURM_PROCID={p} (of SLURM_NTASKS={n})"),
            index: p,
            count: Some(n),
            single_step: n == 1,
        });
    }
    if let Some(a) = num("SLURM_ARRAY_TASK_ID")? {
        let c = num("SLURM_ARRAY_TASK_COUNT")?;
        found.push(Found {
            what: match c {
                Some(c) => format!("SLURM_ARRAY_TASK_ID={a} (of SLURM_ARRAY_TASK_COUNT={c})"),
                None => format!("SLURM_ARRAY_TASK_ID={a}"),
            },
            index: a,
            count: c,
            single_step: false,
        });
    }
    for name in ["JOB_COMPLETION_INDEX", "AWS_BATCH_JOB_ARRAY_INDEX"] {
        if let Some(k) = num(name)? {
            found.push(Found {
                what: format!("{name}={k}"),
                index: k,
                count: None,
                single_step: false,
            });
        }
    }
    if found.len() > 1 {
        found.retain(|f| !f.single_step);
    }
    let Some(first) = found.first() else {
        let (index, count) = (Setting::Index, Setting::Count);
        return Err(SplitError(format!(
            "no shard index: pass {index} and {count}, or run under srun \
             (SLURM_PROCID, SLURM_NTASKS), in a Slurm job array (SLURM_ARRAY_TASK_ID), \
             a Kubernetes Indexed Job (JOB_COMPLETION_INDEX, with {count}) or an AWS \
             Batch array job (AWS_BATCH_JOB_ARRAY_INDEX, with {count})"
        )));
    };
    let names = found
        .iter()
        .map(|f| f.what.as_str())
        .collect::<Vec<_>>()
        .join(", ");
    if found.iter().any(|f| f.index != first.index) {
        return Err(SplitError(format!(
            "contradictory shard index: {names}; pass {} and {}",
            Setting::Index,
            Setting::Count
        )));
    }
    let count = match count {
        Some(c) => c,
        None => {
            let counts: Vec<usize> = found.iter().filter_map(|f| f.count).collect();
            match counts.first() {
                None => {
                    return Err(SplitError(format!(
                        "{names} gives the shard index but not the count: pass {}",
                        Setting::Count
                    )));
                }
                Some(&c) if counts.iter().any(|&d| d != c) => {
                    return Err(SplitError(format!(
                        "contradictory shard count: {names}; pass {}",
                        Setting::Count
                    )));
                }
                Some(&c) => c,
            }
        }
    };
    check(first.index, count, &names)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::breed::population::{Fall, Outcome};
    use crate::motion::classify::{MotionClass, Regime};
    use std::collections::HashMap;

    fn env(pairs: &[(&str, &str)]) -> impl Fn(&str) -> Option<String> {
        let m: HashMap<String, String> = pairs
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect();
        move |k| m.get(k).cloned()
    }

    fn split(index: usize, count: usize) -> Split {
        Split { index, count }
    }

    #[test]
    fn every_engine_convention_gives_its_index() {
        let r = |i, c, e: &[(&str, &str)]| resolve_split(i, c, env(e));
        assert_eq!(
            r(None, None, &[("SLURM_PROCID", "2"), ("SLURM_NTASKS", "3")]),
            Ok(split(2, 3))
        );
        let array = [
            ("SLURM_ARRAY_TASK_ID", "4"),
            ("SLURM_ARRAY_TASK_COUNT", "8"),
        ];
        assert_eq!(r(None, None, &array), Ok(split(4, 8)));
        // The batch step of an array element: SLURM_PROCID=0, one task.
        let batch = [
            ("SLURM_ARRAY_TASK_ID", "4"),
            ("SLURM_ARRAY_TASK_COUNT", "8"),
            ("SLURM_PROCID", "0"),
            ("SLURM_NTASKS", "1"),
        ];
        assert_eq!(r(None, None, &batch), Ok(split(4, 8)));
        // A rerun of a subset array names the split's size.
        assert_eq!(r(None, Some(7), &array), Ok(split(4, 7)));
        assert_eq!(
            r(None, Some(5), &[("JOB_COMPLETION_INDEX", "1")]),
            Ok(split(1, 5))
        );
        assert_eq!(
            r(None, Some(5), &[("AWS_BATCH_JOB_ARRAY_INDEX", "0")]),
            Ok(split(0, 5))
        );
        // Flags win over the environment.
        assert_eq!(r(Some(1), Some(2), &array), Ok(split(1, 2)));
    }

    #[test]
    fn missing_or_contradictory_indices_are_errors_that_say_why() {
        let r = |i, c, e: &[(&str, &str)]| resolve_split(i, c, env(e)).unwrap_err().0;
        assert!(r(None, None, &[]).contains("no shard index"));
        assert!(r(None, Some(3), &[]).contains("no shard index"));
        assert!(r(None, None, &[("JOB_COMPLETION_INDEX", "1")]).contains("count"));
        let e = r(
            None,
            None,
            &[
                ("SLURM_PROCID", "1"),
                ("SLURM_NTASKS", "2"),
                ("SLURM_ARRAY_TASK_ID", "3"),
                ("SLURM_ARRAY_TASK_COUNT", "4"),
            ],
        );
        assert!(
            e.contains("contradictory") && e.contains("SLURM_PROCID=1"),
            "{e}"
        );
        let e = r(
            None,
            Some(4),
            &[
                ("JOB_COMPLETION_INDEX", "1"),
                ("AWS_BATCH_JOB_ARRAY_INDEX", "2"),
            ],
        );
        assert!(e.contains("contradictory"), "{e}");
        let e = r(
            None,
            None,
            &[
                ("SLURM_ARRAY_TASK_ID", "8"),
                ("SLURM_ARRAY_TASK_COUNT", "8"),
            ],
        );
        assert!(e.contains("not below"), "{e}");
        assert!(
            r(None, Some(2), &[("JOB_COMPLETION_INDEX", "x")]).contains("JOB_COMPLETION_INDEX")
        );
        assert!(r(Some(0), Some(0), &[]).contains("at least 1"));
        assert!(r(Some(0), None, &[]).contains("count"));
    }

    fn eval(score: f64) -> Evaluation {
        Evaluation {
            outcome: Outcome::Fell(Fall {
                class: MotionClass::Floater,
                regime: Regime::Glide,
                margin: 0.1 + 0.2,
                descent_m_s: 1e-300,
                drift_ratio: -0.0,
                net_turns: std::f64::consts::PI,
                yaw_turns: 1.0 / 3.0,
                spin_rad_s: 5e-324,
                reversals: 3,
                flips: 0,
                tilt_deg: 12.5,
                dt: 1.3889e-3,
            }),
            score,
            distance: Some(0.1 + 0.7),
            releases: 4,
            kept: 3,
            release_deg: [-17.25, 0.1 + 0.2],
            residuals: vec![0.1 + 0.2, -1e-300, 5e-324, -0.0],
            spread: [0.1 + 0.2, 1e-300, 5e-324],
        }
    }

    /// A diverged drop whose error needs JSON escaping.
    fn diverged() -> Evaluation {
        Evaluation {
            outcome: Outcome::Diverged("diverged at step 3, \"quoted\"\nnewline".into()),
            score: -1.0,
            distance: None,
            releases: 4,
            kept: 0,
            release_deg: [2.0, -29.9],
            residuals: Vec::new(),
            spread: [0.0; 3],
        }
    }

    fn fall_mut(e: &mut Evaluation) -> &mut Fall {
        match &mut e.outcome {
            Outcome::Fell(f) => f,
            Outcome::Diverged(_) => unreachable!(),
        }
    }

    fn sample() -> ShardFile {
        ShardFile {
            generation: 2,
            split: split(1, 3),
            plan: "0123456789abcdef".into(),
            rows: vec![(7, eval(1.25)), (10, eval(-1.0)), (12, diverged())],
        }
    }

    #[test]
    fn shard_files_round_trip_bit_for_bit() {
        let text = encode(&sample()).unwrap();
        let back = decode(&text).unwrap();
        assert_eq!(back, sample());
        assert_eq!(
            back.rows[0].1.fall().unwrap().drift_ratio.to_bits(),
            (-0.0f64).to_bits()
        );
        assert_eq!(encode(&back).unwrap(), text);
    }

    #[test]
    fn truncation_and_corruption_are_detected() {
        let text = encode(&sample()).unwrap();
        for cut in [1, 10, text.len() / 2, text.len() - 1] {
            assert!(decode(&text[..cut]).is_err(), "truncated at {cut} accepted");
        }
        // Drop a whole row but keep the footer: the checksum catches it.
        let lines: Vec<&str> = text.lines().collect();
        let dropped = format!("{}\n{}\n{}\n{}\n", lines[0], lines[2], lines[3], lines[4]);
        assert!(decode(&dropped).unwrap_err().0.contains("checksum"));
        // One changed digit.
        let flipped = text.replacen("1.25", "1.26", 1);
        assert!(decode(&flipped).unwrap_err().0.contains("checksum"));
        // Not a number that reads back: refused at write time.
        let mut bad = sample();
        fall_mut(&mut bad.rows[0].1).margin = f64::NAN;
        assert!(encode(&bad).unwrap_err().0.contains("individual 7"));
    }

    #[test]
    fn round_robin_split_covers_every_child_once() {
        let children: Vec<Child> = (10..23)
            .map(|id| Child {
                id,
                parent: None,
                genome: crate::leaf::genome::Genome::of_prototype(
                    &crate::leaf::LeafSpec::load("a").unwrap(),
                ),
                parent_score: f64::NAN,
            })
            .collect();
        for count in [1, 3, 7, 20] {
            let mut ids: Vec<u64> = (0..count)
                .flat_map(|i| split(i, count).members(&children))
                .map(|c| c.id)
                .collect();
            ids.sort();
            assert_eq!(ids, (10..23).collect::<Vec<_>>(), "count {count}");
        }
        let ids: Vec<u64> = split(1, 3)
            .members(&children)
            .iter()
            .map(|c| c.id)
            .collect();
        assert_eq!(ids, vec![11, 14, 17, 20]);
    }
}
