//! Breeding across processes and machines: the `shard` command, the
//! `processes` and `slurm` executors. The oracle is always a local run with
//! the same seed: every file but timing.csv must be the same bytes.

use crate::breeding::{contents, same_files};
use leafmagic::breed::shard::{self, Split};
use leafmagic::breed::{BreedSettings, Run};
use leafmagic::motion::classify::MotionClass;
use std::os::unix::fs::MetadataExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

/// The variables the engines set; cleared for every child so that a test
/// run under Slurm (or Kubernetes) does not leak its own index in.
const ENGINE_VARS: [&str; 9] = [
    "SLURM_PROCID",
    "SLURM_NTASKS",
    "SLURM_ARRAY_TASK_ID",
    "SLURM_ARRAY_TASK_COUNT",
    "SLURM_JOB_ID",
    "SLURM_CPUS_PER_TASK",
    "JOB_COMPLETION_INDEX",
    "AWS_BATCH_JOB_ARRAY_INDEX",
    "SLURM_STEP_ID",
];

fn leafmagic() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_leafmagic"));
    for v in ENGINE_VARS {
        c.env_remove(v);
    }
    c
}

fn scratch(name: &str) -> PathBuf {
    super::common::scratch("shards", name)
}

fn assert_same_run(reference: &Path, other: &Path, what: &str) {
    let a = same_files(reference, other, &format!("{what} against the local run"));
    assert!(a.contains_key("checkpoint.json"), "{:?}", a.keys());
}

fn ok(out: &Output, what: &str) -> String {
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "{what} failed: {err}");
    err
}

const SMALL: [&str; 6] = ["--population", "14", "--generations", "3", "--seconds", "2"];

fn breed(args: &[&str], out: &Path) -> Output {
    leafmagic()
        .arg("breed")
        .args(args)
        .arg("--out")
        .arg(out)
        .output()
        .unwrap()
}

/// The local run every sharded one must equal.
fn reference(dir: &Path) -> PathBuf {
    let local = dir.join("local");
    ok(&breed(&SMALL, &local), "local breed");
    local
}

/// A run directory holding only run.toml: what `breed` creates before
/// generation 0 (the settings the CLI derives from SMALL).
fn fresh_run(dir: &Path) -> PathBuf {
    let settings = BreedSettings {
        prototype: "a".into(),
        target: MotionClass::Floater,
        population: 14,
        generations: 3,
        seed: 1991,
        seconds: 2.0,
        elites: 1,
        ..BreedSettings::default_run()
    };
    Run::create(dir, settings).unwrap();
    dir.to_path_buf()
}

fn shard_cmd(run: &Path, generation: usize) -> Command {
    let mut c = leafmagic();
    c.arg("shard")
        .arg(run)
        .args(["--generation", &generation.to_string()]);
    c
}

fn resume(run: &Path, executor: &[&str]) -> Output {
    leafmagic()
        .args(["breed", "--resume"])
        .arg(run)
        .args(executor)
        .output()
        .unwrap()
}

#[test]
fn processes_give_the_local_bytes_with_1_3_and_7_shards() {
    let dir = scratch("processes");
    let local = reference(&dir);
    for n in ["1", "3", "7"] {
        let out = dir.join(format!("p{n}"));
        let r = breed(
            &[&SMALL[..], &["--executor", "processes", "--shards", n]].concat(),
            &out,
        );
        ok(&r, "processes breed");
        // Merged shards are removed: nothing but the run's own files stays.
        assert!(!out.join("shards").exists(), "{n} shards: shards/ left");
        assert_same_run(&local, &out, &format!("{n} shards"));
    }
    // --shards without a sharding executor is refused.
    let r = breed(&[&SMALL[..], &["--shards", "2"]].concat(), &dir.join("x"));
    assert!(!r.status.success());
    assert!(String::from_utf8_lossy(&r.stderr).contains("--shards needs"));
}

/// Environment variables of one case.
type Env<'a> = &'a [(&'a str, &'a str)];

#[test]
fn shard_index_comes_from_each_engines_environment() {
    let dir = scratch("env");
    let run = fresh_run(&dir.join("run"));
    let cases: [(Env, &[&str], Split); 5] = [
        (
            &[("SLURM_PROCID", "1"), ("SLURM_NTASKS", "3")],
            &[],
            Split { index: 1, count: 3 },
        ),
        (
            // An array element's batch step also says SLURM_PROCID=0 of 1.
            &[
                ("SLURM_ARRAY_TASK_ID", "2"),
                ("SLURM_ARRAY_TASK_COUNT", "4"),
                ("SLURM_PROCID", "0"),
                ("SLURM_NTASKS", "1"),
            ],
            &[],
            Split { index: 2, count: 4 },
        ),
        (
            &[("JOB_COMPLETION_INDEX", "4")],
            &["--count", "5"],
            Split { index: 4, count: 5 },
        ),
        (
            &[("AWS_BATCH_JOB_ARRAY_INDEX", "0")],
            &["--count", "2"],
            Split { index: 0, count: 2 },
        ),
        (
            // Flags win over the environment.
            &[("SLURM_PROCID", "1"), ("SLURM_NTASKS", "3")],
            &["--index", "0", "--count", "1"],
            Split { index: 0, count: 1 },
        ),
    ];
    for (env, args, split) in cases {
        let path = shard::shard_path(&run, 0, split);
        assert!(!path.exists());
        let r = shard_cmd(&run, 0)
            .args(args)
            .envs(env.iter().copied())
            .output()
            .unwrap();
        ok(&r, &format!("{env:?}"));
        assert!(path.exists(), "{env:?}: no {}", path.display());
        let stdout = String::from_utf8_lossy(&r.stdout);
        assert!(
            stdout.contains(&format!("shard {} of {}", split.index, split.count)),
            "{stdout}"
        );
    }
    let written = std::fs::read_dir(shard::generation_dir(&run, 0))
        .unwrap()
        .count();
    let errors: [(Env, &[&str], &str); 6] = [
        (&[], &[], "no shard index"),
        (&[("JOB_COMPLETION_INDEX", "1")], &[], "pass --count"),
        (
            &[
                ("SLURM_PROCID", "1"),
                ("SLURM_NTASKS", "2"),
                ("SLURM_ARRAY_TASK_ID", "0"),
                ("SLURM_ARRAY_TASK_COUNT", "2"),
            ],
            &[],
            "contradictory shard index: SLURM_PROCID=1",
        ),
        (
            &[
                ("JOB_COMPLETION_INDEX", "1"),
                ("AWS_BATCH_JOB_ARRAY_INDEX", "2"),
            ],
            &["--count", "3"],
            "contradictory",
        ),
        (
            &[
                ("SLURM_ARRAY_TASK_ID", "4"),
                ("SLURM_ARRAY_TASK_COUNT", "4"),
            ],
            &[],
            "not below the shard count 4",
        ),
        (
            &[("JOB_COMPLETION_INDEX", "one")],
            &["--count", "3"],
            "JOB_COMPLETION_INDEX=\"one\"",
        ),
    ];
    for (env, args, needle) in errors {
        let r = shard_cmd(&run, 0)
            .args(args)
            .envs(env.iter().copied())
            .output()
            .unwrap();
        assert!(!r.status.success(), "{env:?} accepted");
        let err = String::from_utf8_lossy(&r.stderr);
        assert!(err.contains(needle), "{env:?}: {err}");
    }
    // A generation that is not the next one is refused, naming the checkpoint.
    let r = shard_cmd(&run, 1)
        .args(["--index", "0", "--count", "1"])
        .output()
        .unwrap();
    assert!(!r.status.success());
    assert!(String::from_utf8_lossy(&r.stderr).contains("checkpoint.json is absent"));
    let after = std::fs::read_dir(shard::generation_dir(&run, 0))
        .unwrap()
        .count();
    assert_eq!(written, after, "a refused shard wrote a file");

    // A Kubernetes Indexed Job of 5 completions, then the driver merges
    // their files (reusing all 5) into the local run's bytes.
    let k8s = fresh_run(&dir.join("k8s"));
    for i in 0..5 {
        let r = shard_cmd(&k8s, 0)
            .args(["--count", "5"])
            .env("JOB_COMPLETION_INDEX", i.to_string())
            .output()
            .unwrap();
        ok(&r, "k8s shard");
    }
    let r = resume(&k8s, &["--executor", "processes", "--shards", "5"]);
    let err = ok(&r, "resume after k8s shards");
    assert!(err.contains("reusing 5 of 5 shards"), "{err}");
    assert_same_run(&reference(&dir), &k8s, "k8s shards of generation 0");
}

#[test]
fn a_shard_run_twice_writes_the_same_bytes() {
    let dir = scratch("twice");
    let run = fresh_run(&dir.join("run"));
    let split = Split { index: 1, count: 3 };
    let path = shard::shard_path(&run, 0, split);
    let go = |extra: &[&str]| {
        let r = shard_cmd(&run, 0)
            .args(["--index", "1", "--count", "3"])
            .args(extra)
            .output()
            .unwrap();
        ok(&r, "shard");
        String::from_utf8_lossy(&r.stdout).into_owned()
    };
    go(&[]);
    let (first, inode) = (
        std::fs::read(&path).unwrap(),
        std::fs::metadata(&path).unwrap().ino(),
    );
    go(&["--threads", "2"]);
    let (second, inode2) = (
        std::fs::read(&path).unwrap(),
        std::fs::metadata(&path).unwrap().ino(),
    );
    assert_ne!(inode, inode2, "the second run did not rewrite the file");
    assert_eq!(first, second, "a rerun wrote other bytes");
    // 14 children of generation 0: shard 1 of 3 holds ids 1, 4, 7, 10, 13.
    let parsed = shard::decode(&String::from_utf8(first).unwrap()).unwrap();
    let ids: Vec<u64> = parsed.rows.iter().map(|(id, _)| *id).collect();
    assert_eq!(ids, vec![1, 4, 7, 10, 13]);
    // --skip-done keeps a valid file.
    assert!(go(&["--skip-done"]).contains("already done"));
    assert_eq!(std::fs::metadata(&path).unwrap().ino(), inode2);
}

#[test]
fn truncated_or_corrupt_shards_are_re_evaluated_never_merged() {
    let dir = scratch("corrupt");
    let run = fresh_run(&dir.join("run"));
    for i in 0..3 {
        let r = shard_cmd(&run, 0)
            .args(["--index", &i.to_string(), "--count", "3"])
            .output()
            .unwrap();
        ok(&r, "shard");
    }
    let path = |index| shard::shard_path(&run, 0, Split { index, count: 3 });
    // Truncated (a writer that is not leafmagic's, or a broken disk) ...
    let text = std::fs::read_to_string(path(1)).unwrap();
    std::fs::write(path(1), &text[..text.len() / 2]).unwrap();
    // ... and one changed digit in a row that still parses.
    let text = std::fs::read_to_string(path(2)).unwrap();
    let k = text.find("\"score\":").unwrap() + "\"score\":".len();
    let mut bytes = text.into_bytes();
    bytes[k] = if bytes[k] == b'1' { b'2' } else { b'1' };
    std::fs::write(path(2), &bytes).unwrap();
    let r = resume(&run, &["--executor", "processes", "--shards", "3"]);
    let err = ok(&r, "resume over damaged shards");
    assert!(err.contains("reusing 1 of 3 shards"), "{err}");
    assert!(err.contains("shard 1 of 3 is invalid (truncated"), "{err}");
    assert!(
        err.contains("shard 2 of 3 is invalid (corrupt: checksum"),
        "{err}"
    );
    assert_same_run(&reference(&dir), &run, "damaged shards re-evaluated");
}

/// A shard file already on disk is merged as it is, not recomputed: a
/// valid file with a marked row shows up in the generation's CSV.
#[test]
fn finished_shards_are_merged_without_re_evaluation() {
    let dir = scratch("reuse");
    let run = fresh_run(&dir.join("run"));
    let r = shard_cmd(&run, 0)
        .args(["--index", "0", "--count", "3"])
        .output()
        .unwrap();
    ok(&r, "shard");
    let path = shard::shard_path(&run, 0, Split { index: 0, count: 3 });
    let mut file = shard::decode(&std::fs::read_to_string(&path).unwrap()).unwrap();
    // A score no drop gives marks the row as the shard's, not recomputed.
    file.rows[0].1.score = 123.456789;
    std::fs::write(&path, shard::encode(&file).unwrap()).unwrap();
    let r = resume(&run, &["--executor", "processes", "--shards", "3"]);
    let err = ok(&r, "resume");
    assert!(err.contains("reusing 1 of 3 shards"), "{err}");
    let gen0 = std::fs::read_to_string(run.join("gen-000.csv")).unwrap();
    let row0 = gen0.lines().nth(1).unwrap();
    assert!(
        row0.starts_with("0,0,,false,") && row0.contains(",123.456789,"),
        "{row0}"
    );
}

#[test]
fn a_killed_driver_resumes_to_the_local_bytes_with_any_executor() {
    let dir = scratch("killed");
    let args = ["--population", "24", "--generations", "6", "--seconds", "4"];
    let whole = dir.join("whole");
    ok(&breed(&args, &whole), "local breed");
    // (executor that is killed, executor that resumes)
    let pairs: [(&[&str], &[&str]); 2] = [
        (
            &["--executor", "processes", "--shards", "3"],
            &["--executor", "processes", "--shards", "3"],
        ),
        (
            &["--threads", "2"],
            &["--executor", "processes", "--shards", "2"],
        ),
    ];
    for (k, (first, then)) in pairs.iter().enumerate() {
        let killed = dir.join(format!("killed-{k}"));
        let mut child = leafmagic()
            .arg("breed")
            .args(args)
            .args(*first)
            .arg("--out")
            .arg(&killed)
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        let start = Instant::now();
        while !killed.join("gen-001.csv").exists() && start.elapsed() < Duration::from_secs(60) {
            std::thread::sleep(Duration::from_millis(2));
        }
        child.kill().unwrap(); // SIGKILL: shard children run on and finish
        child.wait().unwrap();
        let checkpoint =
            std::fs::read_to_string(killed.join("checkpoint.json")).unwrap_or_default();
        assert!(
            !checkpoint.contains("\"generation\":5"),
            "the run finished before it could be killed; the test did not test resuming"
        );
        ok(&resume(&killed, then), "resume");
        assert_same_run(
            &whole,
            &killed,
            &format!("{first:?} killed, resumed with {then:?}"),
        );
    }
}

#[test]
fn a_shard_that_keeps_failing_stops_the_run_naming_generation_shard_and_log() {
    let dir = scratch("failing");
    let run = fresh_run(&dir.join("run"));
    // A directory where shard 1's file should go: its rename always fails.
    let blocked = shard::shard_path(&run, 0, Split { index: 1, count: 3 });
    std::fs::create_dir_all(&blocked).unwrap();
    let r = resume(&run, &["--executor", "processes", "--shards", "3"]);
    assert!(!r.status.success());
    let err = String::from_utf8_lossy(&r.stderr);
    let log = shard::log_path(&run, 0, Split { index: 1, count: 3 });
    assert!(
        err.contains("generation 0: shard 1 of 3 failed 3 times"),
        "{err}"
    );
    assert!(err.contains(&log.display().to_string()), "{err}");
    let text = std::fs::read_to_string(&log).unwrap();
    assert!(text.contains("== attempt 3"), "{text}");
    assert!(text.contains(&blocked.display().to_string()), "{text}");
    // Nothing of generation 0 was written.
    assert!(!run.join("gen-000.csv").exists() && !run.join("checkpoint.json").exists());
}

/// Whether a Slurm cluster answers here. Without one the test is skipped
/// (saying why), except under CI (`CI=true`), where that is a failure.
fn slurm_available() -> bool {
    let missing: Vec<&str> = ["sbatch", "srun", "salloc", "squeue", "scancel"]
        .into_iter()
        .filter(|p| !which(p))
        .collect();
    if !missing.is_empty() {
        panic_or_skip(&format!("{} not found", missing.join(", ")));
        return false;
    }
    let why = match Command::new("sinfo").args(["-h", "-o", "%T"]).output() {
        Err(e) => format!("no sinfo ({e})"),
        Ok(o) if !o.status.success() => format!(
            "sinfo failed: {}",
            String::from_utf8_lossy(&o.stderr).trim()
        ),
        Ok(o) => {
            let states = String::from_utf8_lossy(&o.stdout).into_owned();
            if ["idle", "mix", "alloc"].iter().any(|s| states.contains(s)) {
                return true;
            }
            format!("no usable node (sinfo: {})", states.trim())
        }
    };
    panic_or_skip(&why);
    false
}

fn which(program: &str) -> bool {
    std::env::var_os("PATH").is_some_and(|path| {
        std::env::split_paths(&path).any(|d| {
            std::fs::metadata(d.join(program)).is_ok_and(|m| m.is_file() && m.mode() & 0o111 != 0)
        })
    })
}

fn panic_or_skip(why: &str) {
    if std::env::var("CI").is_ok_and(|v| v == "true") {
        panic!("CI=true but no Slurm cluster: {why}; run deploy/slurm/up.sh first");
    }
    eprintln!("skipped the Slurm test: {why} (deploy/slurm/up.sh brings one up)");
}

/// Polls `squeue` (with `args`) until a line names `name`; returns its id.
fn wait_for_in_queue(args: &[&str], name: &str, timeout: Duration) -> Option<String> {
    let start = Instant::now();
    while start.elapsed() < timeout {
        let out = Command::new("squeue").args(args).output().ok()?;
        for line in String::from_utf8_lossy(&out.stdout).lines() {
            let mut f = line.split_whitespace();
            if let (Some(id), Some(n)) = (f.next(), f.next())
                && n == name
            {
                return Some(id.to_string());
            }
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    None
}

/// Cancels, one after another, the first queue entry named after each of
/// generations 1..=`last` as it shows (`squeue ARGS` lists "id name"), and
/// returns what was cancelled. A step can end between `squeue` showing it
/// and `scancel` reaching it (a loaded machine, a short generation), so one
/// cancellation is not sure to kill anything; several in successive
/// generations make it all but sure that one lands in flight.
fn cancel_in_flight(args: &[&str], last: usize, target: impl Fn(&str) -> String) -> Vec<String> {
    let mut cancelled = Vec::new();
    for g in 1..=last {
        let Some(id) = wait_for_in_queue(
            args,
            &format!("leafmagic-g{g:03}"),
            Duration::from_secs(120),
        ) else {
            continue;
        };
        let id = target(&id);
        // A failed scancel is an entry that ended first: the next
        // generation gets its turn.
        if Command::new("scancel").arg(&id).status().unwrap().success() {
            cancelled.push(id);
        }
    }
    cancelled
}

/// Breeding through a real Slurm: inside an allocation (one srun step per
/// generation) and as arrays; in each, steps or array elements cancelled in
/// flight are rerun and the run still equals the local one.
#[test]
fn slurm_executor_gives_the_local_bytes_and_reruns_what_scancel_killed() {
    if !slurm_available() {
        return;
    }
    let dir = scratch("slurm");
    // Generations long enough (a few seconds) to cancel one in flight.
    let args = [
        "--population",
        "60",
        "--generations",
        "4",
        "--seconds",
        "40",
    ];
    let local = dir.join("local");
    ok(&breed(&args, &local), "local breed");

    // 1. The driver inside an allocation of 2 tasks; scancel the steps of
    //    generations 1 to 3 as they show.
    let steps = dir.join("steps");
    let driver = Command::new("salloc")
        .args(["--ntasks=2", "--job-name=leafmagic-test-driver"])
        .arg(env!("CARGO_BIN_EXE_leafmagic"))
        .arg("breed")
        .args(args)
        .args(["--executor", "slurm", "--out"])
        .arg(&steps)
        .env_remove("SLURM_JOB_ID")
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let cancelled = cancel_in_flight(&["-h", "-s", "-o", "%i %j"], 3, |id| id.to_string());
    let out = driver.wait_with_output().unwrap();
    let err = ok(&out, "breed --executor slurm in salloc");
    assert!(
        !cancelled.is_empty() && err.contains(": shards") && err.contains("rerunning"),
        "of the cancelled steps {cancelled:?} none was rerun: {err}"
    );
    assert_same_run(&local, &steps, "slurm steps with cancelled ones");

    // 2. No allocation: an array per generation; scancel one element (the
    //    last, still pending or running) of generations 1 to 3.
    let arrays = dir.join("arrays");
    let driver = leafmagic()
        .arg("breed")
        .args(args)
        .args(["--executor", "slurm", "--shards", "3", "--out"])
        .arg(&arrays)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let cancelled = cancel_in_flight(&["-h", "-r", "-o", "%i %j"], 3, |element| {
        format!("{}_2", element.split('_').next().unwrap())
    });
    let out = driver.wait_with_output().unwrap();
    let err = ok(&out, "breed --executor slurm (arrays)");
    assert!(
        !cancelled.is_empty()
            && err.contains("shards [2] of 3 missing")
            && err.contains("rerunning"),
        "of the cancelled elements {cancelled:?} none was rerun: {err}"
    );
    assert_same_run(&local, &arrays, "slurm arrays with cancelled elements");
}

/// How a run goes on Kubernetes (deploy/k8s): per generation, an Indexed
/// Job of N pods (JOB_COMPLETION_INDEX, --count N), then `merge`. A merge
/// with a shard missing is refused, naming it, and changes nothing.
#[test]
fn indexed_jobs_and_merge_give_the_local_bytes() {
    let dir = scratch("k8s-loop");
    let run = dir.join("run");
    let r = breed(&[&SMALL[..], &["--create-only"]].concat(), &run);
    ok(&r, "breed --create-only");
    let files: Vec<_> = std::fs::read_dir(&run)
        .unwrap()
        .flatten()
        .map(|e| e.file_name())
        .collect();
    assert_eq!(
        files,
        ["run.toml"],
        "--create-only wrote more than run.toml"
    );
    let merge = |g: usize| {
        leafmagic()
            .arg("merge")
            .arg(&run)
            .args(["--generation", &g.to_string(), "--count", "4"])
            .output()
            .unwrap()
    };
    // Nothing to merge yet: refused, and not even a directory is made.
    let r = merge(0);
    assert!(!r.status.success());
    let files: Vec<_> = std::fs::read_dir(&run)
        .unwrap()
        .flatten()
        .map(|e| e.file_name())
        .collect();
    assert_eq!(files, ["run.toml"], "a refused merge wrote into the run");
    for g in 0..3 {
        for i in [3, 0, 2] {
            let r = shard_cmd(&run, g)
                .args(["--count", "4"])
                .env("JOB_COMPLETION_INDEX", i.to_string())
                .output()
                .unwrap();
            ok(&r, "indexed shard");
        }
        let before = contents(&run);
        let r = merge(g);
        assert!(!r.status.success(), "merged with shard 1 missing");
        let err = String::from_utf8_lossy(&r.stderr);
        let missing = shard::shard_path(&run, g, Split { index: 1, count: 4 });
        assert!(err.contains("shards [1] of 4 are missing"), "{err}");
        assert!(err.contains(&missing.display().to_string()), "{err}");
        assert_eq!(before, contents(&run), "a refused merge changed the run");

        let r = shard_cmd(&run, g)
            .args(["--count", "4"])
            .env("JOB_COMPLETION_INDEX", "1")
            .output()
            .unwrap();
        ok(&r, "indexed shard");
        let r = merge(g);
        ok(&r, "merge");
        // Merging again (a retried pod) is harmless.
        let again = merge(g);
        ok(&again, "second merge");
        assert!(String::from_utf8_lossy(&again.stdout).contains("already merged"));
    }
    assert_same_run(&reference(&dir), &run, "indexed jobs and merge");
}
