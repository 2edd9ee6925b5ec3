//! The Kubernetes recipe (deploy/k8s): the manifests, rendered as breed.sh
//! renders them, pass the API schemas of Kubernetes 1.28 and of the newest
//! version PyPI's `kubernetes-validate` knows (installed into a venv under
//! target/tmp; the test skips with a message where it cannot be), and the
//! checks of the "restricted" Pod Security Standard; and breed.sh, driven
//! against a stand-in kubectl, completes a run byte-identical to a local one
//! and stops at once on a failed index, with that index's log.

use super::breeding::{leafmagic, same_files};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn scratch(name: &str) -> PathBuf {
    super::common::scratch("k8s", name)
}

fn have(tool: &str) -> bool {
    Command::new("sh")
        .arg("-c")
        .arg(format!("command -v {tool}"))
        .output()
        .is_ok_and(|o| o.status.success())
}

/// Renders one manifest with deploy/k8s/render.sh.
fn render(what: &str, env: &[(&str, &str)], extra: &[&str]) -> String {
    let out = Command::new("bash")
        .arg(repo().join("deploy/k8s/render.sh"))
        .arg(what)
        .args(extra)
        .envs(env.iter().copied())
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "render.sh {what}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

/// The checks of the "restricted" Pod Security Standard that apply to these
/// manifests (kubernetes.io/docs/concepts/security/pod-security-standards),
/// plus a read-only root file system, for every pod template: run as
/// non-root (and not as uid 0), no privilege escalation, every capability
/// dropped, seccomp RuntimeDefault, no host namespaces or host paths, no
/// privileged container. Prints one line per violation.
const RESTRICTED: &str = r#"
import sys, yaml
bad = []
for path in sys.argv[1:]:
    for doc in yaml.safe_load_all(open(path)):
        if not doc or doc["kind"] not in ("Pod", "Job"):
            continue
        spec = doc["spec"] if doc["kind"] == "Pod" else doc["spec"]["template"]["spec"]
        name = doc["kind"] + "/" + doc["metadata"]["name"]
        psc = spec.get("securityContext", {})
        for key in ("hostNetwork", "hostPID", "hostIPC"):
            if spec.get(key):
                bad.append(f"{name}: {key}")
        for v in spec.get("volumes", []):
            if "hostPath" in v:
                bad.append(f"{name}: hostPath volume {v['name']}")
        if psc.get("runAsUser") == 0:
            bad.append(f"{name}: pod runs as uid 0")
        for c in spec.get("containers", []) + spec.get("initContainers", []):
            csc = c.get("securityContext", {})
            where = f"{name} container {c['name']}"
            if not (csc.get("runAsNonRoot", psc.get("runAsNonRoot")) is True):
                bad.append(f"{where}: runAsNonRoot is not true")
            if csc.get("runAsUser", psc.get("runAsUser")) == 0:
                bad.append(f"{where}: runs as uid 0")
            if csc.get("allowPrivilegeEscalation") is not False:
                bad.append(f"{where}: allowPrivilegeEscalation is not false")
            if csc.get("privileged"):
                bad.append(f"{where}: privileged")
            if "ALL" not in csc.get("capabilities", {}).get("drop", []):
                bad.append(f"{where}: capabilities do not drop ALL")
            if csc.get("capabilities", {}).get("add"):
                bad.append(f"{where}: adds capabilities")
            seccomp = csc.get("seccompProfile", psc.get("seccompProfile", {})).get("type")
            if seccomp not in ("RuntimeDefault", "Localhost"):
                bad.append(f"{where}: seccompProfile is {seccomp}, not RuntimeDefault")
            if csc.get("readOnlyRootFilesystem") is not True:
                bad.append(f"{where}: root file system is writable")
            mounts = {m["mountPath"] for m in c.get("volumeMounts", [])}
            if "/tmp" not in mounts:
                bad.append(f"{where}: no writable /tmp volume")
for b in bad:
    print(b)
sys.exit(1 if bad else 0)
"#;

/// A venv under target/tmp with kubernetes-validate, or why not.
fn validator() -> Result<PathBuf, String> {
    let venv = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("k8s-validate-venv");
    let bin = venv.join("bin");
    if bin.join("kubernetes-validate").exists() {
        return Ok(bin);
    }
    if !have("python3") {
        return Err("no python3".into());
    }
    let made = Command::new("python3")
        .arg("-m")
        .arg("venv")
        .arg(&venv)
        .output()
        .map_err(|e| e.to_string())?;
    if !made.status.success() {
        return Err(format!(
            "python3 -m venv failed: {}",
            String::from_utf8_lossy(&made.stderr)
        ));
    }
    let pip = Command::new(bin.join("pip"))
        .args(["install", "--quiet", "kubernetes-validate"])
        .output()
        .map_err(|e| e.to_string())?;
    if !pip.status.success() {
        let _ = std::fs::remove_dir_all(&venv);
        return Err(format!(
            "pip install kubernetes-validate failed: {}",
            String::from_utf8_lossy(&pip.stderr)
        ));
    }
    Ok(bin)
}

#[test]
fn manifests_pass_the_kubernetes_schemas_and_the_restricted_level() {
    if !have("envsubst") {
        crate::common::missing_tool(
            "k8s manifests",
            "no envsubst (Debian: gettext-base) to render the manifests",
        );
        return;
    }
    let dir = scratch("manifests");
    let env = [
        ("RUN", "Floaters_2026"),
        ("SHARDS", "64"),
        ("IMAGE", "registry.example/leafmagic:0.1"),
        ("GENERATION", "7"),
        ("STORAGE_CLASS", "nfs-client"),
    ];
    let settings = ["--", "--population", "10000", "--seconds", "10"];
    let mut files = Vec::new();
    for what in ["job", "volume", "rbac", "driver"] {
        let text = render(what, &env, &settings);
        assert!(!text.contains("${"), "{what}: unsubstituted: {text}");
        let path = dir.join(format!("{what}.yaml"));
        std::fs::write(&path, &text).unwrap();
        files.push(path);
    }
    // The names carry the run's, as a DNS label; the claim names its class.
    let name = render("name", &env, &[]).trim().to_string();
    assert!(name.starts_with("floaters-2026-"), "{name}");
    let job = std::fs::read_to_string(&files[0]).unwrap();
    assert!(
        job.contains(&format!("name: leafmagic-{name}-gen-7")),
        "{job}"
    );
    assert!(
        job.contains(&format!("claimName: leafmagic-{name}")),
        "{job}"
    );
    let volume = std::fs::read_to_string(&files[1]).unwrap();
    assert!(volume.contains("storageClassName: nfs-client"), "{volume}");
    let default_class = render("volume", &[("RUN", "x")], &[]);
    assert!(
        !default_class.contains("storageClassName"),
        "{default_class}"
    );
    // A claim for another run has another name.
    assert_ne!(render("volume", &[("RUN", "spinners")], &[]), default_class);

    let bin = match validator() {
        Ok(bin) => bin,
        Err(why) => {
            crate::common::missing_tool("k8s schema checks", &why);
            return;
        }
    };
    let restricted = dir.join("restricted.py");
    std::fs::write(&restricted, RESTRICTED).unwrap();
    let pss = Command::new(bin.join("python"))
        .arg(&restricted)
        .args(&files)
        .output()
        .unwrap();
    assert!(
        pss.status.success(),
        "restricted Pod Security violations:\n{}",
        String::from_utf8_lossy(&pss.stdout)
    );
    let newest = Command::new(bin.join("python"))
        .args([
            "-c",
            "import kubernetes_validate.utils as u; print(u.latest_version())",
        ])
        .output()
        .unwrap();
    let newest = String::from_utf8(newest.stdout).unwrap().trim().to_string();
    assert!(newest.starts_with("1."), "{newest}");
    let validate = |version: &str, files: &[PathBuf]| {
        Command::new(bin.join("kubernetes-validate"))
            .args(["--strict", "--no-warn", "-k", version])
            .args(files)
            .output()
            .unwrap()
    };
    for version in ["1.28.0", newest.as_str()] {
        let out = validate(version, &files);
        assert!(
            out.status.success(),
            "Kubernetes {version}:\n{}{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
        // Every resource was checked: 1 Job, 1 claim, 3 RBAC objects, 1 pod.
        let passed = String::from_utf8_lossy(&out.stdout)
            .matches("passed")
            .count();
        assert_eq!(passed, 6, "{}", String::from_utf8_lossy(&out.stdout));
    }
    // The validator does reject what is wrong (a control for the above):
    // a string where the Job wants a number, and a field that does not exist.
    let broken = dir.join("broken.yaml");
    std::fs::write(
        &broken,
        job.replace("completions: 64", "completions: many")
            .replace("backoffLimit: 100", "backoffLimit: 100\n  retries: 3"),
    )
    .unwrap();
    assert!(!validate("1.28.0", &[broken]).status.success());
}

/// A stand-in for kubectl: records every call, and plays a cluster whose
/// Indexed Jobs either run their shards (`leafmagic shard`, one process per
/// index, as the pods would) and complete, or (FAKE_FAIL_INDEX=k) run all
/// but index k, which fails with a log line.
const FAKE_KUBECTL: &str = r#"#!/usr/bin/env bash
set -u
echo "kubectl $*" >>"$FAKE_STATE/calls"
case "$1" in
  delete) exit 0 ;;
  apply)
    cat >"$FAKE_STATE/applied-$GENERATION.yaml"
    for ((i = 0; i < SHARDS; i++)); do
      if [ "${FAKE_FAIL_INDEX:-}" = "$i" ]; then continue; fi
      leafmagic shard "$RUNS_ROOT/$RUN" --generation "$GENERATION" --index "$i" --count "$SHARDS" --threads 1 >/dev/null || exit 1
    done
    exit 0 ;;
  get)
    if [ "$2" = job ]; then
      case "$*" in
        *failedIndexes*) [ -n "${FAKE_FAIL_INDEX:-}" ] && echo "$FAKE_FAIL_INDEX"; exit 0 ;;
        *conditions*)
          # Not finished at the first poll; then Complete or Failed.
          n=$(grep -c "conditions" "$FAKE_STATE/calls")
          [ "$n" -le 1 ] && exit 0
          if [ -n "${FAKE_FAIL_INDEX:-}" ]; then printf 'FailureTarget\nFailed\n'; else printf 'Complete\n'; fi
          exit 0 ;;
      esac
    fi
    if [ "$2" = pods ]; then
      echo "leafmagic-pod-$FAKE_FAIL_INDEX-a Failed"
      exit 0
    fi ;;
  logs) echo "shard $FAKE_FAIL_INDEX: simulated failure: the node ran out of memory (exit 137)"; exit 0 ;;
esac
echo "fake kubectl: unexpected call: $*" >&2
exit 3
"#;

/// Runs deploy/k8s/breed.sh with the stand-in kubectl first on PATH.
fn drive(dir: &Path, fail_index: Option<usize>) -> (std::process::Output, Duration) {
    let bin = dir.join("bin");
    std::fs::create_dir_all(&bin).unwrap();
    let kubectl = bin.join("kubectl");
    std::fs::write(&kubectl, FAKE_KUBECTL).unwrap();
    Command::new("chmod")
        .arg("+x")
        .arg(&kubectl)
        .status()
        .unwrap();
    let link = bin.join("leafmagic");
    let _ = std::fs::remove_file(&link);
    std::os::unix::fs::symlink(env!("CARGO_BIN_EXE_leafmagic"), &link).unwrap();
    let state = dir.join("state");
    std::fs::create_dir_all(&state).unwrap();
    let runs = dir.join("runs");
    std::fs::create_dir_all(&runs).unwrap();
    let path = format!("{}:{}", bin.display(), std::env::var("PATH").unwrap());
    let mut cmd = Command::new("bash");
    cmd.arg(repo().join("deploy/k8s/breed.sh"))
        .args(["demo", "2", "registry.example/leafmagic:0.1", "--"])
        .args(["--population", "8", "--generations", "2", "--seconds", "1"])
        .env("PATH", path)
        .env("RUNS_ROOT", &runs)
        .env("FAKE_STATE", &state)
        .env("POLL_SECONDS", "0.05");
    if let Some(k) = fail_index {
        cmd.env("FAKE_FAIL_INDEX", k.to_string());
    }
    let start = Instant::now();
    let out = cmd.output().unwrap();
    (out, start.elapsed())
}

#[test]
fn breed_sh_completes_a_run_and_stops_on_a_failed_index_with_its_log() {
    if !have("envsubst") {
        crate::common::missing_tool(
            "k8s jobs",
            "no envsubst (Debian: gettext-base) to render the Jobs",
        );
        return;
    }
    // A run driven to the end: the same bytes as a local run.
    let dir = scratch("driver-ok");
    let (out, _) = drive(&dir, None);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(stderr.contains("run complete"), "{stderr}");
    let applied = std::fs::read_to_string(dir.join("state/applied-1.yaml")).unwrap();
    assert!(applied.contains("name: leafmagic-demo-gen-1"), "{applied}");
    let local = dir.join("local");
    let l = leafmagic()
        .args(["breed", "--population", "8", "--generations", "2"])
        .args(["--seconds", "1", "--out"])
        .arg(&local)
        .output()
        .unwrap();
    assert!(l.status.success());
    same_files(
        &dir.join("runs/demo"),
        &local,
        "the Kubernetes run against the local run",
    );

    // Index 1 of generation 0 fails: the driver stops at once (not after a
    // 24 h wait), non-zero, with the index and its log.
    let dir = scratch("driver-failed");
    let (out, took) = drive(&dir, Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{stderr}");
    assert!(took < Duration::from_secs(20), "took {took:?}");
    assert!(
        stderr.contains("Job leafmagic-demo-gen-0 failed")
            && stderr.contains("shard 1 of 2 ran out of retries")
            && stderr.contains("simulated failure: the node ran out of memory"),
        "{stderr}"
    );
    // Nothing was merged: generation 0 is not in a checkpoint.
    assert!(!dir.join("runs/demo/checkpoint.json").exists());
    let calls = std::fs::read_to_string(dir.join("state/calls")).unwrap();
    assert!(!calls.contains("merge"), "{calls}");
}
