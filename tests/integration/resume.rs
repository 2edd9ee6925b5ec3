//! A run directory is verified before it is resumed: a damaged checkpoint
//! or generation file is recomputed (the run comes out byte-identical to an
//! uninterrupted one), a changed run.toml is refused naming the file, and
//! what does not repair (a shard process, `export`) refuses the damage
//! instead of trusting it. The damages are the ones issue 22 found by hand.

use super::breeding::{breed, contents, leafmagic, scratch};
use serde_json::Value;
use std::path::Path;

const SMALL: [&str; 6] = ["--population", "12", "--generations", "3", "--seconds", "2"];

fn copy_dir(from: &Path, to: &Path) {
    let _ = std::fs::remove_dir_all(to);
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        let target = to.join(e.file_name());
        if e.path().is_dir() {
            copy_dir(&e.path(), &target);
        } else {
            std::fs::copy(e.path(), target).unwrap();
        }
    }
}

/// What becomes of the checkpoint's digest when it is edited.
#[derive(Clone, Copy)]
enum Digest {
    /// Kept as it was, so now wrong.
    Kept,
    /// Recomputed for the edited content: what only leafmagic's own checks
    /// of every field can catch.
    Resealed,
    /// Removed.
    Removed,
}

/// The checkpoint as JSON, edited by `edit`, written back compactly with
/// its digest as `digest` says.
fn edit_checkpoint(dir: &Path, digest: Digest, edit: impl FnOnce(&mut Value)) {
    let path = dir.join("checkpoint.json");
    let mut v: Value = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    edit(&mut v);
    let map = v.as_object_mut().unwrap();
    match digest {
        Digest::Kept => {}
        Digest::Removed => {
            map.remove("digest");
        }
        Digest::Resealed => {
            map.remove("digest");
            let sealed = leafmagic::breed::verify::checkpoint_digest(&v);
            v["digest"] = sealed.into();
        }
    }
    std::fs::write(&path, serde_json::to_string(&v).unwrap()).unwrap();
}

#[test]
fn damaged_runs_are_recomputed_to_the_bytes_of_an_uninterrupted_run() {
    let dir = scratch("verify");
    let whole = dir.join("whole");
    let out = breed(&SMALL, &whole);
    crate::common::assert_succeeded(&out);
    let reference = contents(&whole);
    let cp: Value =
        serde_json::from_str(&std::fs::read_to_string(whole.join("checkpoint.json")).unwrap())
            .unwrap();
    assert!(cp["digest"].as_str().is_some_and(|d| d.len() == 16), "{cp}");
    assert_eq!(cp["fnv1a64"].as_object().unwrap().len(), 4, "{cp}");
    // The default strategy (hybrid) found its class and keeps CMA-ES's
    // state in the checkpoint.
    assert!(cp["cmaes"]["covariance"].is_array(), "{cp}");

    type Damage = (&'static str, &'static str, Box<dyn Fn(&Path)>);
    let damages: Vec<Damage> = vec![
        (
            "population []",
            "digest",
            Box::new(|d| {
                edit_checkpoint(d, Digest::Kept, |v| v["population"] = Value::Array(vec![]))
            }),
        ),
        (
            "scale 1e308",
            "digest",
            Box::new(|d| edit_checkpoint(d, Digest::Kept, |v| v["scale"] = 1e308.into())),
        ),
        (
            "generation 9",
            "digest",
            Box::new(|d| edit_checkpoint(d, Digest::Kept, |v| v["generation"] = 9.into())),
        ),
        (
            "size_factor 1e300, resealed",
            "population[0].genome.size_factor",
            Box::new(|d| {
                edit_checkpoint(d, Digest::Resealed, |v| {
                    v["population"][0]["genome"]["size_factor"] = 1e300.into()
                })
            }),
        ),
        (
            "mass_factor -1, resealed",
            "population[2].genome.mass_factor[1]",
            Box::new(|d| {
                edit_checkpoint(d, Digest::Resealed, |v| {
                    v["population"][2]["genome"]["mass_factor"][1] = (-1.0).into()
                })
            }),
        ),
        (
            "population [], resealed",
            "population",
            Box::new(|d| {
                edit_checkpoint(d, Digest::Resealed, |v| {
                    v["population"] = Value::Array(vec![])
                })
            }),
        ),
        (
            "generation 9, resealed",
            "generation",
            Box::new(|d| edit_checkpoint(d, Digest::Resealed, |v| v["generation"] = 9.into())),
        ),
        (
            "cmaes sigma 0, resealed",
            "cmaes.sigma",
            Box::new(|d| {
                edit_checkpoint(d, Digest::Resealed, |v| v["cmaes"]["sigma"] = 0.0.into())
            }),
        ),
        (
            "cmaes covariance asymmetric, resealed",
            "cmaes.covariance",
            Box::new(|d| {
                edit_checkpoint(d, Digest::Resealed, |v| {
                    let c = &mut v["cmaes"]["covariance"][1];
                    *c = (c.as_f64().unwrap() + 0.25).into();
                })
            }),
        ),
        (
            "re-saved with spaces, a score edited",
            "digest",
            Box::new(|d| {
                let p = d.join("checkpoint.json");
                let mut v: Value =
                    serde_json::from_str(&std::fs::read_to_string(&p).unwrap()).unwrap();
                v["population"][0]["eval"]["score"] = 1000.0.into();
                let text = serde_json::to_string_pretty(&v).unwrap();
                assert!(text.contains("\"digest\": \""), "{text}");
                std::fs::write(&p, text).unwrap();
            }),
        ),
        (
            "re-saved with spaces, nothing edited",
            "content is intact",
            Box::new(|d| {
                let p = d.join("checkpoint.json");
                let v: Value = serde_json::from_str(&std::fs::read_to_string(&p).unwrap()).unwrap();
                std::fs::write(&p, serde_json::to_string_pretty(&v).unwrap()).unwrap();
            }),
        ),
        (
            "digest removed",
            "digest: missing",
            Box::new(|d| edit_checkpoint(d, Digest::Removed, |_| {})),
        ),
        (
            "gen-001.csv's hash removed, resealed",
            "fnv1a64.\"gen-001.csv\": missing",
            Box::new(|d| {
                edit_checkpoint(d, Digest::Resealed, |v| {
                    v["fnv1a64"].as_object_mut().unwrap().remove("gen-001.csv");
                })
            }),
        ),
        (
            "gen-002.csv's hash removed, resealed",
            "fnv1a64.\"gen-002.csv\": missing",
            Box::new(|d| {
                edit_checkpoint(d, Digest::Resealed, |v| {
                    v["fnv1a64"].as_object_mut().unwrap().remove("gen-002.csv");
                })
            }),
        ),
        (
            "run.toml's hash removed, resealed",
            "fnv1a64.\"run.toml\": missing",
            Box::new(|d| {
                edit_checkpoint(d, Digest::Resealed, |v| {
                    v["fnv1a64"].as_object_mut().unwrap().remove("run.toml");
                })
            }),
        ),
        // The checkpoint's own generation: its file is rewritten, and the
        // hash recorded is the file's true one again (the comparison with
        // the uninterrupted run's checkpoint.json below says so).
        (
            "gen-002.csv's hash zeroed, resealed",
            "rewriting it from checkpoint.json",
            Box::new(|d| {
                edit_checkpoint(d, Digest::Resealed, |v| {
                    v["fnv1a64"]["gen-002.csv"] = "0000000000000000".into();
                })
            }),
        ),
        (
            "gen-000.csv's hash zeroed, resealed",
            "gen-000.csv",
            Box::new(|d| {
                edit_checkpoint(d, Digest::Resealed, |v| {
                    v["fnv1a64"]["gen-000.csv"] = "0000000000000000".into();
                })
            }),
        ),
        (
            "checkpoint truncated",
            "line",
            Box::new(|d| {
                let p = d.join("checkpoint.json");
                let t = std::fs::read(&p).unwrap();
                std::fs::write(&p, &t[..t.len() / 3]).unwrap();
            }),
        ),
        (
            "gen-001.csv truncated",
            "gen-001.csv",
            Box::new(|d| {
                let p = d.join("gen-001.csv");
                let t = std::fs::read(&p).unwrap();
                std::fs::write(&p, &t[..t.len() - 40]).unwrap();
            }),
        ),
        (
            "gen-000.csv edited",
            "gen-000.csv",
            Box::new(|d| {
                let p = d.join("gen-000.csv");
                let t = std::fs::read_to_string(&p).unwrap();
                std::fs::write(&p, t.replacen("floater", "spinner", 1)).unwrap();
            }),
        ),
        (
            "gen-001.csv deleted",
            "gen-001.csv",
            Box::new(|d| std::fs::remove_file(d.join("gen-001.csv")).unwrap()),
        ),
        (
            "gen-002.csv (the checkpoint's own) deleted",
            "rewriting it from checkpoint.json",
            Box::new(|d| std::fs::remove_file(d.join("gen-002.csv")).unwrap()),
        ),
        (
            "generations.csv edited",
            "generations.csv",
            Box::new(|d| std::fs::write(d.join("generations.csv"), "generation\n").unwrap()),
        ),
    ];
    for (what, said, damage) in &damages {
        let run = dir.join("damaged");
        copy_dir(&whole, &run);
        damage(&run);
        let out = leafmagic()
            .arg("breed")
            .arg("--resume")
            .arg(&run)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{what}: {stderr}");
        assert!(
            stderr.contains(said),
            "{what}: the note does not say {said:?}: {stderr}"
        );
        let repaired = contents(&run);
        assert_eq!(
            repaired.keys().collect::<Vec<_>>(),
            reference.keys().collect::<Vec<_>>(),
            "{what}"
        );
        for (k, v) in &reference {
            assert!(
                repaired[k] == *v,
                "{what}: {k} differs from the uninterrupted run's"
            );
        }
    }
}

#[test]
fn what_cannot_be_recomputed_or_is_not_a_driver_refuses_the_damage() {
    let dir = scratch("refuse");
    let whole = dir.join("whole");
    assert!(breed(&SMALL, &whole).status.success());

    // run.toml changed under the checkpoint: refused, nothing touched.
    let run = dir.join("edited-run-toml");
    copy_dir(&whole, &run);
    let path = run.join("run.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    std::fs::write(&path, text.replacen("seconds = 2.0", "seconds = 3.0", 1)).unwrap();
    let before = contents(&run);
    let out = leafmagic()
        .arg("breed")
        .arg("--resume")
        .arg(&run)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        stderr.contains("run.toml") && stderr.contains("changed"),
        "{stderr}"
    );
    assert_eq!(contents(&run), before, "a refused resume changed files");

    // A damaged checkpoint: `export` and a shard process refuse it, naming
    // the file and field, and say what repairs it.
    let run = dir.join("bad-genome");
    copy_dir(&whole, &run);
    edit_checkpoint(&run, Digest::Resealed, |v| {
        v["population"][0]["genome"]["mass_factor"][0] = (-1.0).into();
        v["generation"] = 1.into();
        v["history"].as_array_mut().unwrap().pop();
    });
    let export = leafmagic()
        .arg("export")
        .arg(&run)
        .args(["--top", "2", "--out"])
        .arg(dir.join("exported"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&export.stderr);
    assert!(!export.status.success());
    assert!(
        stderr.contains("checkpoint.json")
            && stderr.contains("population[0].genome.mass_factor[0]")
            && stderr.contains("--resume"),
        "{stderr}"
    );
    assert!(!dir.join("exported").exists());
    let shard = leafmagic()
        .arg("shard")
        .arg(&run)
        .args(["--generation", "2", "--index", "0", "--count", "1"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&shard.stderr);
    assert!(!shard.status.success());
    assert!(stderr.contains("mass_factor[0]"), "{stderr}");
    assert!(!run.join("shards").exists());
}
