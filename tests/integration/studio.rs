//! `leafmagic studio`: its server refuses what it must (no token, a foreign
//! Host or Origin, a large or malformed body) and keeps running; breeding
//! runs in the background with its progress and each candidate shown as it
//! finishes, one at a time (409 while one runs); breeding from picks
//! records the picks and parents, going back and branching makes a tree, a
//! session reopens where it was, and the same seed and picks write the same
//! bytes; kept leaves export under the session as the falls shown.
//! Requests are plain HTTP over a TcpStream.

use serde_json::Value;
use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::Duration;

/// A running studio, stopped when dropped.
struct Studio {
    child: Child,
    /// Its standard output, held open: a closed pipe would fail its writes.
    _stdout: std::io::Lines<BufReader<std::process::ChildStdout>>,
    port: u16,
    token: String,
    dir: PathBuf,
}

/// Small and short, so that a generation takes seconds: 4 candidates, 2 s
/// drops.
const SMALL: [&str; 4] = ["--grid", "4", "--seconds", "2"];

impl Studio {
    /// Starts `leafmagic studio ARGS` and waits for its URL.
    fn start(args: &[&str], dir: &Path) -> Studio {
        let mut child = Command::new(env!("CARGO_BIN_EXE_leafmagic"))
            .arg("studio")
            .args(args)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let mut lines = BufReader::new(child.stdout.take().unwrap()).lines();
        let url = loop {
            match lines.next() {
                Some(Ok(line)) => {
                    if let Some(url) = line.strip_prefix("studio: ") {
                        break url.to_string();
                    }
                }
                _ => {
                    let mut err = String::new();
                    child
                        .stderr
                        .take()
                        .unwrap()
                        .read_to_string(&mut err)
                        .unwrap();
                    panic!("the studio did not start: {err}");
                }
            }
        };
        // The URL names the loopback address, a port and the token.
        let rest = url.strip_prefix("http://127.0.0.1:").expect(&url);
        let (port, token) = rest.split_once("/?token=").expect(&url);
        assert_eq!(token.len(), 32, "128 bits as hex: {url}");
        assert!(token.bytes().all(|b| b.is_ascii_hexdigit()), "{url}");
        Studio {
            child,
            _stdout: lines,
            port: port.parse().unwrap(),
            token: token.to_string(),
            dir: dir.to_path_buf(),
        }
    }

    fn host(&self) -> String {
        format!("127.0.0.1:{}", self.port)
    }

    /// Sends one request (head lines, then `body`) and returns the status
    /// and body of the answer.
    fn raw(&self, method: &str, target: &str, headers: &[String], body: &[u8]) -> (u16, String) {
        let mut s = TcpStream::connect(("127.0.0.1", self.port)).unwrap();
        s.set_read_timeout(Some(Duration::from_secs(600))).unwrap();
        let mut head = format!("{method} {target} HTTP/1.1\r\n");
        for h in headers {
            head.push_str(h);
            head.push_str("\r\n");
        }
        head.push_str(&format!(
            "Content-Length: {}\r\nConnection: close\r\n\r\n",
            body.len()
        ));
        // A refused body may not be read: the answer is what counts.
        let _ = s.write_all(head.as_bytes());
        let _ = s.write_all(body);
        let mut answer = Vec::new();
        let _ = s.read_to_end(&mut answer);
        let text = String::from_utf8_lossy(&answer).into_owned();
        let status = text
            .split(' ')
            .nth(1)
            .and_then(|c| c.parse().ok())
            .unwrap_or_else(|| panic!("no HTTP answer: {text:?}"));
        let body = text
            .split_once("\r\n\r\n")
            .map_or("", |(_, b)| b)
            .to_string();
        (status, body)
    }

    /// A request as the page makes it: the right Host, the token.
    fn call(&self, method: &str, path: &str, body: &str) -> (u16, String) {
        self.raw(
            method,
            &format!("{path}?token={}", self.token),
            &[format!("Host: {}", self.host())],
            body.as_bytes(),
        )
    }

    /// A successful API call's state.
    fn api(&self, path: &str, body: &str) -> Value {
        let method = if path == "/api/state" { "GET" } else { "POST" };
        let (status, text) = self.call(method, path, body);
        assert_eq!(status, 200, "{path} {body}: {text}");
        serde_json::from_str(&text).unwrap()
    }

    /// A GET with the token in the header, so `target` may carry its own
    /// query.
    fn get(&self, target: &str) -> Value {
        let (status, text) = self.raw(
            "GET",
            target,
            &[
                format!("Host: {}", self.host()),
                format!("X-Leafmagic-Token: {}", self.token),
            ],
            b"",
        );
        assert_eq!(status, 200, "{target}: {text}");
        serde_json::from_str(&text).unwrap()
    }

    /// Starts breeding from `body` (202 at once, the breeding announced).
    fn start_breed(&self, body: &str) -> Value {
        let (status, text) = self.call("POST", "/api/breed", body);
        assert_eq!(status, 202, "{body}: {text}");
        let started: Value = serde_json::from_str(&text).unwrap();
        assert!(started["breeding"].is_object(), "{started}");
        started
    }

    /// Follows the breeding under way to its end as the page does, from
    /// its progress: every candidate arrives once, in some order, with its
    /// fall, and the count of drops done only grows. Returns the state
    /// then, whose grid must hold what arrived, slot by slot.
    fn finish_breed(&self) -> Value {
        let mut slots: Vec<Option<u64>> = Vec::new();
        let (mut got, mut drops_done, mut generation) = (0, 0, None);
        loop {
            let p = self.get(&format!("/api/progress?from={got}"));
            let Some(b) = p["breeding"].as_object() else {
                assert!(p["breed_error"].is_null(), "{p}");
                break;
            };
            // Auto N goes on to its next generation: follow that one.
            if generation != Some(b["generation"].clone()) {
                generation = Some(b["generation"].clone());
                (slots, got, drops_done) = (Vec::new(), 0, 0);
                continue;
            }
            let n = b["candidates"].as_u64().unwrap() as usize;
            slots.resize(n, None);
            assert!(b["drops_done"].as_u64().unwrap() >= drops_done, "{p}");
            drops_done = b["drops_done"].as_u64().unwrap();
            assert_eq!(b["drops"].as_u64().unwrap(), n as u64 * 4, "{p}");
            for c in b["finished"].as_array().unwrap() {
                let slot = c["slot"].as_u64().unwrap() as usize;
                assert!(slots[slot].is_none(), "slot {slot} arrived twice");
                assert!(c["motion"]["frames"].as_u64().unwrap() > 0, "{c}");
                slots[slot] = Some(c["id"].as_u64().unwrap());
                got += 1;
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        let state = self.api("/api/state", "");
        assert!(state["breeding"].is_null(), "{state}");
        // A poll may land after the last candidate and before the commit,
        // or only after it: what arrived is the grid, where it arrived.
        let shown = ids(&state);
        if got > 0 && slots.len() == shown.len() {
            for (k, id) in slots.iter().enumerate() {
                assert!(
                    id.is_none() || *id == Some(shown[k]),
                    "slot {k}: {id:?} vs {shown:?}"
                );
            }
        } else if got == slots.len() && got > 0 {
            // "More like this" evaluated more than it keeps: what it keeps
            // arrived.
            for id in &shown {
                assert!(slots.contains(&Some(*id)), "{id} never arrived: {slots:?}");
            }
        }
        state
    }

    /// Breeds from `body` and waits for the generation.
    fn breed(&self, body: &str) -> Value {
        self.start_breed(body);
        self.finish_breed()
    }

    fn session(&self) -> Value {
        read_json(&self.dir.join("studio.json"))
    }
}

impl Drop for Studio {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn read_json(path: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn scratch(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

fn ids(state: &Value) -> Vec<u64> {
    state["candidates"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c["id"].as_u64().unwrap())
        .collect()
}

fn start_in(dir: &Path, seed: &str) -> Studio {
    let out = dir.to_str().unwrap();
    let mut args = vec!["--out", out, "--seed", seed];
    args.extend(SMALL);
    Studio::start(&args, dir)
}

/// The ids of a generation file's two best candidates by `key` of their
/// evaluation, highest first, ties to the earlier in the grid (as the
/// studio picks them for Auto N).
fn two_best(generation: &Value, key: impl Fn(&Value) -> f64) -> [u64; 2] {
    let mut ranked: Vec<(f64, usize, u64)> = generation
        .as_array()
        .unwrap()
        .iter()
        .enumerate()
        .map(|(k, c)| (key(&c["evaluation"]), k, c["id"].as_u64().unwrap()))
        .collect();
    ranked.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    [ranked[0].2, ranked[1].2]
}

#[test]
fn studio_refuses_what_it_must_and_keeps_running() {
    let dir = scratch("studio-security");
    // 10 s drops: its one breeding lasts long enough to be interrupted.
    let out = dir.to_str().unwrap();
    let s = Studio::start(
        &[
            "--out",
            out,
            "--seed",
            "3",
            "--grid",
            "4",
            "--seconds",
            "10",
        ],
        &dir,
    );
    let host = format!("Host: {}", s.host());
    let token = format!("?token={}", s.token);
    let get = |target: &str, headers: &[String]| s.raw("GET", target, headers, b"");

    let (status, page) = get(&format!("/{token}"), std::slice::from_ref(&host));
    assert_eq!(status, 200);
    assert!(
        page.contains("<canvas") || page.contains("canvas"),
        "{page}"
    );
    // Offline: the page names no other server.
    assert!(!page.contains("http://") && !page.contains("https://"));
    assert_eq!(
        get(&format!("/api/state{token}"), std::slice::from_ref(&host)).0,
        200
    );
    // The token in a header will do.
    let header = format!("X-Leafmagic-Token: {}", s.token);
    assert_eq!(get("/api/state", &[host.clone(), header.clone()]).0, 200);

    // No token, a wrong one, one of another length.
    for target in [
        "/api/state".to_string(),
        "/api/state?token=0123456789abcdef0123456789abcdef".to_string(),
        "/?token=".to_string(),
        format!("/api/state?token={}0", s.token),
    ] {
        let (status, reason) = get(&target, std::slice::from_ref(&host));
        assert_eq!(status, 403, "{target}: {reason}");
        assert!(reason.contains("token"), "{reason}");
    }
    // DNS rebinding: another name, or this name at another port.
    for bad in [
        "Host: attacker.example".to_string(),
        format!("Host: attacker.example:{}", s.port),
        format!("Host: 127.0.0.1:{}", s.port.wrapping_add(1)),
    ] {
        let (status, reason) = get(&format!("/api/state{token}"), std::slice::from_ref(&bad));
        assert_eq!(status, 403, "{bad}: {reason}");
        assert!(reason.contains("Host"), "{reason}");
    }
    assert_eq!(get(&format!("/api/state{token}"), &[]).0, 403, "no Host");
    // localhost is this machine too.
    let local = format!("Host: localhost:{}", s.port);
    assert_eq!(get(&format!("/api/state{token}"), &[local]).0, 200);
    // Another page in the browser.
    for origin in [
        "Origin: http://attacker.example".to_string(),
        "Origin: null".to_string(),
        format!("Origin: http://127.0.0.1:{}", s.port.wrapping_add(1)),
    ] {
        let (status, reason) = s.raw(
            "POST",
            &format!("/api/back{token}"),
            &[host.clone(), origin.clone()],
            b"{}",
        );
        assert_eq!(status, 403, "{origin}: {reason}");
        assert!(reason.contains("Origin"), "{reason}");
    }
    let own = format!("Origin: http://127.0.0.1:{}", s.port);
    assert_eq!(
        get(&format!("/api/state{token}"), &[host.clone(), own]).0,
        200
    );

    // Bodies: too large, malformed, or naming what is not there.
    let big = vec![b' '; 100 * 1024];
    let (status, _) = s.raw(
        "POST",
        &format!("/api/breed{token}"),
        std::slice::from_ref(&host),
        &big,
    );
    assert_eq!(status, 413);
    for (body, says) in [
        ("{\"picks\": [", "malformed"),
        ("not json", "malformed"),
        ("{\"picks\": \"../../etc/passwd\"}", "malformed"),
        ("{\"picks\": [0], \"path\": \"/tmp/x\"}", "unknown field"),
        ("{\"picks\": []}", "pick at least one"),
        ("{\"picks\": [999999]}", "not in generation"),
        ("{\"picks\": [0, 0]}", "twice"),
        ("{\"picks\": [0], \"scale\": 1e9}", "scale"),
    ] {
        let (status, reason) = s.call("POST", "/api/breed", body);
        assert_eq!(status, 400, "{body}: {reason}");
        assert!(reason.contains(says), "{body}: {reason}");
    }
    let (status, reason) = s.call("POST", "/api/back", "{}");
    assert_eq!(status, 400, "generation 0 has no parent: {reason}");
    let (status, reason) = s.call("POST", "/api/goto", "{\"generation\": 7}");
    assert_eq!(status, 400, "{reason}");

    // After all that, it answers, and nothing was bred.
    let state = s.api("/api/state", "");
    assert_eq!(state["generation"]["index"], 0);
    assert_eq!(s.session()["generations"].as_array().unwrap().len(), 1);

    // One breeding at a time: while one runs (it takes far longer than a
    // request), another, or moving in the tree, is refused with 409.
    let g0 = ids(&state);
    let started = s.start_breed(&format!("{{\"picks\": [{}]}}", g0[0]));
    assert_eq!(
        started["generation"]["index"], 0,
        "answered before it is bred"
    );
    assert_eq!(started["breeding"]["generation"], 1);
    assert_eq!(started["breeding"]["drops"], 16);
    for (path, body) in [
        ("/api/breed", format!("{{\"picks\": [{}]}}", g0[1])),
        ("/api/goto", "{\"generation\": 0}".to_string()),
    ] {
        let (status, reason) = s.call("POST", path, &body);
        assert_eq!(status, 409, "{path}: {reason}");
        assert!(reason.contains("being bred"), "{reason}");
    }
    // Keeping does not wait.
    s.api("/api/keep", &format!("{{\"id\": {}}}", g0[3]));
    let bred = s.finish_breed();
    assert_eq!(bred["generation"]["index"], 1);
    assert_eq!(s.session()["generations"].as_array().unwrap().len(), 2);
    assert_eq!(bred["collection"][0]["id"], g0[3]);
}

/// Breeds from two picks, goes back, branches from one pick: the session's
/// tree after these three actions.
fn pick_breed_back_branch(s: &Studio) -> (Vec<u64>, Vec<u64>) {
    let state = s.api("/api/state", "");
    let g0 = ids(&state);
    // No taste before the person has picked.
    assert!(
        state["taste_judgements"].is_null(),
        "{}",
        state["taste_judgements"]
    );
    assert!(
        state["candidates"]
            .as_array()
            .unwrap()
            .iter()
            .all(|c| c["taste"].is_null())
    );
    let two = vec![g0[1], g0[2]];
    let g1 = s.breed(&format!("{{\"picks\": [{}, {}]}}", two[0], two[1]));
    assert_eq!(g1["generation"]["index"], 1);
    let back = s.api("/api/back", "{}");
    assert_eq!(back["generation"]["index"], 0);
    assert_eq!(ids(&back), g0);
    // One grid judged: the two picked against the others that fell; the
    // model likes what was picked more than what was passed over.
    let fell: Vec<&Value> = back["candidates"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|c| c["class"] != "diverged")
        .collect();
    assert_eq!(
        back["taste_judgements"],
        fell.len(),
        "{}",
        back["taste_judgements"]
    );
    let mean_taste = |picked: bool| {
        let t: Vec<f64> = fell
            .iter()
            .filter(|c| two.contains(&c["id"].as_u64().unwrap()) == picked)
            .map(|c| c["taste"].as_f64().unwrap())
            .collect();
        assert!(t.iter().all(|v| (0.0..=1.0).contains(v)), "{t:?}");
        t.iter().sum::<f64>() / t.len() as f64
    };
    let (liked, passed) = (mean_taste(true), mean_taste(false));
    assert!(
        liked > passed,
        "taste of the picked {liked}, of the others {passed}"
    );
    let one = vec![g0[0]];
    let g2 = s.breed(&format!("{{\"picks\": [{}], \"scale\": 0.5}}", one[0]));
    assert_eq!(g2["generation"]["index"], 2);
    (two, one)
}

#[test]
fn studio_breeds_from_picks_and_keeps_a_tree() {
    let dir = scratch("studio-tree");
    let s = start_in(&dir, "5");
    let (two, one) = pick_breed_back_branch(&s);

    let session = s.session();
    let gens = session["generations"].as_array().unwrap();
    assert_eq!(gens.len(), 3);
    assert_eq!(session["current"], 2);
    // Both children of generation 0: a tree, not a line.
    assert_eq!(gens[1]["parent"], 0);
    assert_eq!(gens[2]["parent"], 0);
    let picks = |g: &Value| -> Vec<u64> {
        g["picks"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_u64().unwrap())
            .collect()
    };
    assert_eq!(picks(&gens[1]), two);
    assert_eq!(picks(&gens[2]), one);
    assert_eq!(gens[2]["scale"], 0.5);
    // The default scale shrinks from generation 0's.
    assert!(gens[1]["scale"].as_f64().unwrap() < gens[0]["scale"].as_f64().unwrap());

    // Generation 1's parents are exactly the two picks: variations of
    // each, a crossover of both, and a wild card with none.
    let g1 = read_json(&dir.join("gen-001.json"));
    let g1 = g1.as_array().unwrap();
    assert_eq!(g1.len(), 4);
    let mut parents: Vec<u64> = g1
        .iter()
        .flat_map(|c| c["parents"].as_array().unwrap().clone())
        .map(|v| v.as_u64().unwrap())
        .collect();
    parents.sort_unstable();
    parents.dedup();
    assert_eq!(parents, two);
    let origins: Vec<&str> = g1.iter().map(|c| c["origin"].as_str().unwrap()).collect();
    assert_eq!(origins, ["variation", "variation", "crossover", "wild"]);
    for c in g1 {
        assert_eq!(c["evaluation"]["releases"], 4, "dropped from 4 releases");
        let leaf = dir.join(format!("gen-001/leaf-{}.toml", c["id"]));
        assert!(leaf.is_file(), "{}", leaf.display());
    }
    // Generation 2, a branch from generation 0: its wild card may come
    // from the archive, from a cell only generation 1 showed.
    let g2 = read_json(&dir.join("gen-002.json"));
    let g1_ids: Vec<Value> = g1.iter().map(|c| c["id"].clone()).collect();
    for c in g2.as_array().unwrap() {
        let p = c["parents"].as_array().unwrap();
        let archive = c["origin"] == "archive" && p.len() == 1 && g1_ids.contains(&p[0]);
        assert!(
            p.is_empty() || p == &[Value::from(one[0])] || archive,
            "{c}"
        );
    }
    // The motion each is shown with.
    let motion = read_json(&dir.join("gen-001-motion.json"));
    assert!(motion[0]["frames"].as_u64().unwrap() > 20, "{}", motion[0]);

    keep_and_export(&s, &dir, g1[0]["id"].as_u64().unwrap(), two[0]);
    auto_generations(&s, &dir);
    more_like_this(&s, &dir);

    // Reopened, it is where it was, and goes on.
    let before = s.api("/api/state", "");
    drop(s);
    let r = Studio::start(&["--resume", dir.to_str().unwrap()], &dir);
    let after = r.api("/api/state", "");
    assert_eq!(after["generation"], before["generation"]);
    assert_eq!(after["candidates"], before["candidates"]);
    let back = r.api("/api/back", "{}");
    let current = before["generation"]["index"].as_u64().unwrap() as usize;
    assert_eq!(
        back["generation"]["index"],
        r.session()["generations"][current]["parent"]
    );
}

/// "Auto 2" from the current generation: two more generations, each
/// bred from the two best of the one before by breed's score (ties to the
/// earlier in the grid), marked as the machine's picks.
fn auto_generations(s: &Studio, dir: &Path) {
    for body in [
        "{\"generations\": 0}",
        "{\"generations\": 21}",
        "{\"n\": 2}",
    ] {
        let (status, reason) = s.call("POST", "/api/auto", body);
        assert_eq!(status, 400, "{body}: {reason}");
    }
    let before = s.session();
    let from = before["current"].as_u64().unwrap() as usize;
    let count = before["generations"].as_array().unwrap().len();
    let (status, text) = s.call("POST", "/api/auto", "{\"generations\": 2}");
    assert_eq!(status, 202, "{text}");
    let state = s.finish_breed();
    let after = s.session();
    let gens = after["generations"].as_array().unwrap();
    assert_eq!(gens.len(), count + 2);
    assert_eq!(state["generation"]["index"], count + 1);
    let mut parent = from;
    for g in &gens[count..] {
        assert_eq!(g["parent"], parent, "{g}");
        assert_eq!(g["auto"], true, "{g}");
        let bred_from = read_json(&dir.join(format!("gen-{parent:03}.json")));
        // The two best by breed's score (none: last).
        let best = two_best(&bred_from, |e| {
            e["score"].as_f64().unwrap_or(f64::NEG_INFINITY)
        });
        assert_eq!(g["picks"], serde_json::json!(best), "{g}");
        parent = g["index"].as_u64().unwrap() as usize;
    }
    // Generations a person bred are not marked.
    assert!(gens[1].get("auto").is_none(), "{}", gens[1]);
}

/// "More like this" of a candidate with a class: three times the grid
/// evaluated toward its fall (ids reserved for all), the grid's worth
/// kept, each a variation of it or a wild card; refused for a candidate
/// not on the grid or whose fall has no class.
fn more_like_this(s: &Studio, dir: &Path) {
    let state = s.api("/api/state", "");
    let (s_ok, s_bad): (Vec<&Value>, Vec<&Value>) = state["candidates"]
        .as_array()
        .unwrap()
        .iter()
        .partition(|c| c["class"] != "undetermined" && c["class"] != "diverged");
    let (status, reason) = s.call("POST", "/api/like", "{\"id\": 999999}");
    assert_eq!(status, 400, "{reason}");
    assert!(reason.contains("not in generation"), "{reason}");
    if let Some(bad) = s_bad.first() {
        let (status, reason) = s.call("POST", "/api/like", &format!("{{\"id\": {}}}", bad["id"]));
        assert_eq!(status, 400, "{reason}");
        assert!(reason.contains("no fall to breed toward"), "{reason}");
    }
    let id = s_ok.first().expect("a candidate with a class")["id"]
        .as_u64()
        .unwrap();
    let before = s.session();
    let first = before["next_id"].as_u64().unwrap();
    let (status, text) = s.call("POST", "/api/like", &format!("{{\"id\": {id}}}"));
    assert_eq!(status, 202, "{text}");
    let started: Value = serde_json::from_str(&text).unwrap();
    assert_eq!(started["breeding"]["candidates"], 12, "3 × the grid of 4");
    let bred = s.finish_breed();
    let after = s.session();
    let k = bred["generation"]["index"].as_u64().unwrap() as usize;
    let node = &after["generations"][k];
    assert_eq!(node["like"], id, "{node}");
    assert_eq!(node["picks"], serde_json::json!([id]));
    assert_eq!(node["parent"], before["current"]);
    assert_eq!(
        after["next_id"].as_u64().unwrap(),
        first + 12,
        "every evaluation's id used"
    );
    let g = read_json(&dir.join(format!("gen-{k:03}.json")));
    let g = g.as_array().unwrap();
    assert_eq!(g.len(), 4);
    for c in g {
        let cid = c["id"].as_u64().unwrap();
        assert!((first..first + 12).contains(&cid), "{cid}");
        let p = c["parents"].as_array().unwrap();
        // A wild card has no parent, or from the archive an elite's.
        assert!(
            p.is_empty() || p == &[Value::from(id)] || c["origin"] == "archive",
            "{c}"
        );
    }
    assert!(
        g.iter().any(|c| c["evaluation"]["distance"].is_number()),
        "some kept fall is near enough to be measured: {g:?}"
    );
}

/// The centre of every frame of a fall shown (`gen-NNN-motion.json`'s
/// float32 positions), m.
fn shown_centres(motion: &Value) -> Vec<[f64; 3]> {
    use base64::Engine as _;
    let bytes = base64::engine::general_purpose::STANDARD
        .decode(motion["positions"].as_str().unwrap())
        .unwrap();
    let n = motion["vertices"].as_u64().unwrap() as usize;
    let floats: Vec<f64> = bytes
        .chunks_exact(4)
        .map(|b| f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]])))
        .collect();
    floats
        .chunks_exact(3 * n)
        .map(|frame| {
            let mut c = [0.0; 3];
            for v in frame.chunks_exact(3) {
                (0..3).for_each(|j| c[j] += v[j] / n as f64);
            }
            c
        })
        .collect()
}

/// Keeps `a` (generation 1) and `b` (generation 0), refuses bad keeps and
/// exports, exports the two, and checks the files: each kept leaf as a
/// leaf file, glTF, USD, Alembic and PC2 with its OBJ, the glTF read back
/// by the crate's own reader playing the fall the page showed, lifted to
/// the start height, at the frame rate asked.
fn keep_and_export(s: &Studio, dir: &Path, a: u64, b: u64) {
    for (body, says) in [
        ("{\"id\": 999999}", "no candidate"),
        ("{\"id\": \"../x\"}", "malformed"),
        ("{\"id\": 1, \"path\": \"/tmp\"}", "unknown field"),
    ] {
        let (status, reason) = s.call("POST", "/api/keep", body);
        assert_eq!(status, 400, "{body}: {reason}");
        assert!(reason.contains(says), "{body}: {reason}");
    }
    let (status, reason) = s.call(
        "POST",
        "/api/export",
        "{\"fps\": 24, \"start_height_m\": 1}",
    );
    assert_eq!(status, 400, "an empty collection: {reason}");
    assert!(reason.contains("empty"), "{reason}");
    s.api("/api/keep", &format!("{{\"id\": {a}}}"));
    s.api("/api/keep", &format!("{{\"id\": {b}}}"));
    // Kept twice is kept once; taken out and kept again goes last.
    s.api("/api/keep", &format!("{{\"id\": {a}}}"));
    s.api("/api/keep", &format!("{{\"id\": {a}, \"keep\": false}}"));
    let state = s.api("/api/keep", &format!("{{\"id\": {a}, \"keep\": true}}"));
    let kept: Vec<u64> = state["collection"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c["id"].as_u64().unwrap())
        .collect();
    assert_eq!(kept, [b, a]);
    assert_eq!(state["collection"][1]["generation"], 1);
    assert_eq!(s.session()["kept"], serde_json::json!([b, a]), "recorded");
    for (body, says) in [
        ("{\"fps\": 0, \"start_height_m\": 1}", "frame rate"),
        ("{\"fps\": 1000, \"start_height_m\": 1}", "frame rate"),
        ("{\"fps\": 24, \"start_height_m\": -1}", "start height"),
        ("{\"fps\": 24, \"start_height_m\": 1e300}", "start height"),
        ("{\"fps\": 24}", "missing field"),
        (
            "{\"fps\": 24, \"start_height_m\": 1, \"dir\": \"/tmp\"}",
            "unknown field",
        ),
    ] {
        let (status, reason) = s.call("POST", "/api/export", body);
        assert_eq!(status, 400, "{body}: {reason}");
        assert!(reason.contains(says), "{body}: {reason}");
    }
    assert!(
        !dir.join("export").exists(),
        "a refused export writes nothing"
    );

    // At the page's own 20 fps, the exported fall is the one shown.
    let (fps, height) = (20.0, 2.5);
    let (status, text) = s.call(
        "POST",
        "/api/export",
        &format!("{{\"fps\": {fps}, \"start_height_m\": {height}}}"),
    );
    assert_eq!(status, 200, "{text}");
    let answer: Value = serde_json::from_str(&text).unwrap();
    let out = dir.join("export");
    let mut names: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    let mut expected: Vec<String> = [a, b]
        .iter()
        .flat_map(|id| {
            ["abc", "glb", "obj", "pc2", "toml", "usda"].map(|e| format!("leaf-{id}.{e}"))
        })
        .collect();
    expected.sort();
    assert_eq!(names, expected);
    assert_eq!(
        answer["files"].as_array().unwrap().len(),
        expected.len(),
        "{answer}"
    );
    for id in [a, b] {
        let stem = out.join(format!("leaf-{id}"));
        let (k, motion) = (0..3)
            .find_map(|k| {
                let m = read_json(&dir.join(format!("gen-{k:03}-motion.json")));
                m.as_array()
                    .unwrap()
                    .iter()
                    .find(|m| m["id"] == id)
                    .map(|m| (k, m.clone()))
            })
            .unwrap();
        let shown = shown_centres(&motion);
        let clip = leafmagic::formats::gltf::from_glb(&stem.with_extension("glb"), None, None)
            .unwrap_or_else(|e| panic!("leaf-{id}.glb: {e}"));
        assert_eq!(clip.fps, fps);
        let o = &clip.objects[0];
        assert_eq!(o.frame_count(), shown.len(), "leaf {id} of generation {k}");
        for (f, c) in shown.iter().enumerate() {
            let e = o.centre(f);
            let d = ((e.x - c[0]).powi(2) + (e.y - c[1]).powi(2) + (e.z - height - c[2]).powi(2))
                .sqrt();
            assert!(d < 1e-3, "leaf {id} frame {f}: {d} m from the fall shown");
        }
        let usda = std::fs::read_to_string(stem.with_extension("usda")).unwrap();
        let usd = leafmagic::formats::usd::read_usda_keys(&usda, "usda").unwrap();
        assert_eq!(usd.objects[0].frame_count(), shown.len());
        let abc = std::fs::read(stem.with_extension("abc")).unwrap();
        let abc = leafmagic::formats::alembic::read_abc(&abc, "abc").unwrap();
        assert_eq!(abc.objects[0].frame_count(), shown.len());
        let leaf = leafmagic::leaf::LeafSpec::read(&stem.with_extension("toml")).unwrap();
        leaf.model().unwrap();
        let pc2 = std::fs::read(stem.with_extension("pc2")).unwrap();
        assert_eq!(&pc2[..12], b"POINTCACHE2\0");
        let samples = i32::from_le_bytes([pc2[28], pc2[29], pc2[30], pc2[31]]);
        assert_eq!(samples as usize, shown.len());
    }

    // Again at 24 fps: the folder is replaced, with 24 frames a second.
    let (status, text) = s.call(
        "POST",
        "/api/export",
        "{\"fps\": 24, \"start_height_m\": 0}",
    );
    assert_eq!(status, 200, "{text}");
    let clip =
        leafmagic::formats::gltf::from_glb(&out.join(format!("leaf-{a}.glb")), None, None).unwrap();
    assert_eq!(clip.fps, 24.0);
    let seconds = s.session()["settings"]["seconds"].as_f64().unwrap();
    assert_eq!(
        clip.objects[0].frame_count(),
        (seconds * 24.0).round() as usize + 1
    );
}

#[test]
fn a_studio_killed_mid_breed_reopens_at_the_generation_before() {
    let dir = scratch("studio-kill");
    let out = dir.to_str().unwrap();
    // 10 s drops: the kill lands while generation 1 is being bred.
    let mut s = Studio::start(
        &[
            "--out",
            out,
            "--seed",
            "9",
            "--grid",
            "4",
            "--seconds",
            "10",
        ],
        &dir,
    );
    let g0 = ids(&s.api("/api/state", ""));
    let picks = format!("{{\"picks\": [{}, {}]}}", g0[0], g0[1]);
    s.start_breed(&picks);
    s.child.kill().unwrap(); // SIGKILL
    s.child.wait().unwrap();
    let session = s.session();
    assert_eq!(
        session["generations"].as_array().unwrap().len(),
        1,
        "{session}"
    );
    assert_eq!(session["current"], 0);
    drop(s);
    // Reopened: generation 0, and the same breeding goes through.
    let r = Studio::start(&["--resume", out], &dir);
    let state = r.api("/api/state", "");
    assert_eq!(state["generation"]["index"], 0);
    assert_eq!(ids(&state), g0);
    let bred = r.breed(&picks);
    assert_eq!(bred["generation"]["index"], 1);
    assert_eq!(
        r.session()["generations"][1]["picks"],
        serde_json::json!([g0[0], g0[1]])
    );
}

#[test]
fn studio_sessions_with_the_same_seed_and_picks_write_the_same_bytes() {
    let (da, db) = (scratch("studio-same-a"), scratch("studio-same-b"));
    let (a, b) = std::thread::scope(|scope| {
        let a = scope.spawn(|| {
            let s = start_in(&da, "11");
            pick_breed_back_branch(&s);
            s
        });
        let b = scope.spawn(|| {
            let s = start_in(&db, "11");
            pick_breed_back_branch(&s);
            s
        });
        (a.join().unwrap(), b.join().unwrap())
    });
    let files = super::breeding::same_files(&da, &db, "two studio sessions");
    assert!(files.len() > 10, "{:?}", files.keys().collect::<Vec<_>>());
    drop((a, b));
}

/// The pinned Playwright release of the browser test (driving the system's
/// Chromium: no browser download).
const PLAYWRIGHT: &str = "playwright==1.56.0";

/// The system's Chromium, if installed.
fn chromium_path() -> Option<PathBuf> {
    ["/usr/bin/chromium", "/usr/bin/chromium-browser"]
        .into_iter()
        .map(PathBuf::from)
        .find(|p| p.is_file())
}

/// A Python with Playwright importable, set up once per target directory
/// ([`crate::common::venv_python`]), or why there is none.
fn playwright_python() -> Result<PathBuf, String> {
    crate::common::venv_python("playwright-venv", "playwright.sync_api", PLAYWRIGHT)
}

/// Opens the studio in headless Chromium, waits for the grid, picks the
/// second candidate by a click and the third by its key, breeds with
/// Enter (the grid is replaced by one cell per candidate at once, filled
/// as each finishes, with a progress bar), screenshots the new grid (clock
/// held at 1.5 s), goes back with Backspace, branches from the first
/// candidate, keeps two leaves by their buttons (they fall side by side;
/// screenshot of that view), refuses a bad frame rate and exports at 24
/// fps from 1.5 m. Prints what the Rust side checks, as JSON. Any request
/// to another server is recorded (the page must need none).
const BROWSER_PY: &str = r##"
import json, sys
from playwright.sync_api import sync_playwright
url, chromium, shot, shot2 = sys.argv[1:5]
with sync_playwright() as p:
    browser = p.chromium.launch(executable_path=chromium, args=["--no-sandbox", "--disable-gpu"])
    page = browser.new_page(viewport={"width": 1000, "height": 900}, device_scale_factor=1)
    errors, foreign = [], []
    page.on("pageerror", lambda e: errors.append(str(e)))
    origin = url.split("/?")[0]
    page.on("request", lambda r: None if r.url.startswith(origin) else foreign.append(r.url))
    page.goto(url + "&t=1.5")
    page.wait_for_selector('body[data-drawn="0"]', timeout=120000)
    ids = page.eval_on_selector_all(".cell", "els => els.map(e => +e.dataset.id)")
    page.click(".cell:nth-child(2) canvas")
    page.keyboard.press("3")
    picked = page.eval_on_selector_all(".cell.picked", "els => els.map(e => +e.dataset.id)")
    # Every change of the grid while breeding: cells, and those still dropping.
    page.evaluate("""() => { window.seen = [];
      new MutationObserver(() => window.seen.push([document.querySelectorAll('.cell').length,
        document.querySelectorAll('.cell.pending').length,
        document.getElementById('progress').style.visibility]))
        .observe(document.getElementById('grid'), {subtree: true, childList: true, attributes: true}); }""")
    page.keyboard.press("Enter")
    page.wait_for_selector('body[data-drawn="1"]', timeout=600000)
    seen = page.evaluate("window.seen")
    page.wait_for_timeout(500)
    page.screenshot(path=shot)
    boxes = page.eval_on_selector_all(".cell canvas",
        "els => els.map(e => { const r = e.getBoundingClientRect(); return [r.x, r.y, r.width, r.height]; })")
    status = page.inner_text("#status")
    page.keyboard.press("Backspace")
    page.wait_for_selector('body[data-generation="0"]', timeout=60000)
    page.wait_for_selector('body[data-drawn="0"]', timeout=60000)
    branch_from = page.eval_on_selector(".cell:nth-child(1)", "e => +e.dataset.id")
    page.keyboard.press("1")
    page.keyboard.press("Enter")
    page.wait_for_selector('body[data-drawn="2"]', timeout=600000)
    g2 = page.eval_on_selector_all(".cell", "els => els.map(e => +e.dataset.id)")
    page.click(".cell:nth-child(1) button.keep")
    page.wait_for_selector('body[data-kept="1"]', timeout=60000)
    page.click(".cell:nth-child(2) button.keep")
    page.wait_for_selector('body[data-together="2"]', timeout=60000)
    page.wait_for_timeout(300)
    page.locator("#together").screenshot(path=shot2)
    page.fill("#fps", "0")
    page.click("#export")
    # (Playwright's selectors, not wait_for_function: the page's CSP allows no eval.)
    page.wait_for_selector("#exported:has-text('refused')", timeout=60000)
    refused = page.inner_text("#exported")
    page.fill("#fps", "24")
    page.fill("#height", "1.5")
    page.click("#export")
    page.wait_for_selector('body[data-exported]', timeout=600000)
    exported = page.inner_text("#exported")
    # Auto 1 toward typed descriptors: generation 3, its aim in the history.
    page.fill("#auto-n", "1")
    page.fill("#auto-toward", "descent=0.5")
    page.click("#auto")
    page.wait_for_selector('body[data-drawn="3"]', timeout=600000)
    tree = page.inner_text("#tree")
    page.check("#by-taste")
    page.wait_for_timeout(300)
    by_taste = page.eval_on_selector_all(".cell", "els => els.map(e => +e.dataset.id)")
    browser.close()
print(json.dumps({"ids": ids, "picked": picked, "boxes": boxes, "errors": errors,
                  "foreign": foreign, "status": status, "seen": seen, "branch_from": branch_from,
                  "g2": g2, "refused": refused, "exported": exported, "tree": tree,
                  "by_taste": by_taste}))
"##;

/// Skips (with the reason) where no browser or driver can be had, but
/// fails under CI, which must run the test.
fn unavailable(what: &str) {
    assert!(
        std::env::var("CI").as_deref() != Ok("true"),
        "CI=true: the browser test must run, but {what}"
    );
    eprintln!("skipped: studio browser test: {what}");
}

#[test]
fn studio_in_a_real_browser_picks_breeds_and_draws_every_candidate() {
    let Some(chromium) = chromium_path() else {
        return unavailable("no Chromium (apt-get install chromium)");
    };
    let python = match playwright_python() {
        Ok(p) => p,
        Err(e) => return unavailable(&e),
    };
    let dir = scratch("studio-browser");
    let s = start_in(&dir, "5");
    let url = format!("http://127.0.0.1:{}/?token={}", s.port, s.token);
    let shot = dir.with_extension("png");
    let shot2 = dir.with_extension("together.png");
    let out = Command::new(&python)
        .args(["-c", BROWSER_PY, &url])
        .arg(&chromium)
        .arg(&shot)
        .arg(&shot2)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let report: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(report["errors"], Value::Array(vec![]), "{report}");
    assert_eq!(report["foreign"], Value::Array(vec![]), "offline: {report}");
    let g0: Vec<u64> = report["ids"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_u64().unwrap())
        .collect();
    assert_eq!(g0.len(), 4);
    let two = vec![g0[1], g0[2]];
    assert_eq!(report["picked"], serde_json::json!(two));

    // The run directory: generation 1 bred from exactly those two, and
    // the page went back to generation 0.
    let session = s.session();
    assert_eq!(session["generations"][1]["parent"], 0);
    assert_eq!(session["generations"][1]["picks"], serde_json::json!(two));
    let g1 = read_json(&dir.join("gen-001.json"));
    let mut parents: Vec<u64> = g1
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|c| c["parents"].as_array().unwrap().clone())
        .map(|v| v.as_u64().unwrap())
        .collect();
    parents.sort_unstable();
    parents.dedup();
    assert_eq!(parents, two, "generation 1's parents are exactly the picks");
    // While breeding, the grid was the new generation's four cells, some
    // still dropping, under a visible progress bar.
    let seen = report["seen"].as_array().unwrap();
    assert!(
        seen.iter()
            .any(|s| s[0] == 4 && s[1].as_u64().unwrap() > 0 && s[2] == "visible"),
        "{report}"
    );
    // Back, then a branch from generation 0's first candidate.
    let branch_from = report["branch_from"].as_u64().unwrap();
    assert_eq!(branch_from, g0[0]);
    assert_eq!(session["generations"][2]["parent"], 0);
    assert_eq!(
        session["generations"][2]["picks"],
        serde_json::json!([g0[0]])
    );
    // On screen at the end: the Auto's generation 3, bred from 2.
    assert_eq!(session["current"], 3);
    // Two kept, recorded; a frame rate of 0 refused on the page.
    let g2: Vec<u64> = report["g2"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_u64().unwrap())
        .collect();
    assert_eq!(session["kept"], serde_json::json!([g2[0], g2[1]]));
    assert!(
        report["refused"].as_str().unwrap().contains("frame rate"),
        "{report}"
    );
    // Auto 1 typed toward descent=0.5: generation 3, from generation 2,
    // the aim recorded and shown in the history line.
    let session = s.session();
    let g3 = &session["generations"][3];
    assert_eq!(g3["parent"], 2, "{g3}");
    assert_eq!(g3["auto"], true, "{g3}");
    assert_eq!(g3["toward"]["descriptors"]["descent"], 0.5, "{g3}");
    assert!(
        report["tree"]
            .as_str()
            .unwrap()
            .contains("toward descent=0.5"),
        "{report}"
    );
    // The export: every format of both, the glTF read back at 24 fps
    // starting from 1.5 m.
    for id in [g2[0], g2[1]] {
        let stem = dir.join("export").join(format!("leaf-{id}"));
        for ext in ["toml", "glb", "usda", "abc", "pc2", "obj"] {
            assert!(stem.with_extension(ext).is_file(), "{report}: no .{ext}");
        }
        let clip = leafmagic::formats::gltf::from_glb(&stem.with_extension("glb"), None, None)
            .unwrap_or_else(|e| panic!("leaf-{id}.glb: {e}"));
        assert_eq!(clip.fps, 24.0);
        assert_eq!(clip.objects[0].frame_count(), 2 * 24 + 1);
        assert!((clip.objects[0].centre(0).z - 1.5).abs() < 0.01, "{report}");
    }

    // Every cell of the new grid drew its leaf and its trail.
    let boxes = report["boxes"].as_array().unwrap();
    assert_eq!(boxes.len(), 4, "{report}");
    let (image, width, height) = read_rgb(&shot);
    for (k, b) in boxes.iter().enumerate() {
        let b: Vec<usize> = (0..4).map(|i| b[i].as_f64().unwrap() as usize).collect();
        let (drawn, trail, leaf) = count_pixels(&image, width, height, [b[0], b[1], b[2], b[3]]);
        assert!(
            drawn > 500 && trail > 20 && leaf > 20,
            "cell {k}: {drawn} drawn, {trail} trail and {leaf} leaf pixels ({})",
            shot.display()
        );
    }
    // The two kept leaves side by side: two leaves' worth of leaf and
    // trail pixels, one in each half of the view.
    let (image, width, height) = read_rgb(&shot2);
    for half in 0..2 {
        let (drawn, trail, leaf) = count_pixels(
            &image,
            width,
            height,
            [half * width / 2, 0, width / 2, height],
        );
        assert!(
            drawn > 200 && trail > 10 && leaf > 10,
            "side by side, half {half}: {drawn} drawn, {trail} trail and {leaf} leaf pixels ({})",
            shot2.display()
        );
    }
}

/// A PNG's pixels as RGB rows, with its width and height.
fn read_rgb(path: &Path) -> (Vec<[u8; 3]>, usize, usize) {
    let mut decoder =
        png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    decoder.set_transformations(png::Transformations::EXPAND | png::Transformations::STRIP_16);
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    let channels = info.line_size / info.width as usize;
    let (w, h) = (info.width as usize, info.height as usize);
    let pixels = (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .map(|(x, y)| {
            let k = y * info.line_size + x * channels;
            [buf[k], buf[k + 1], buf[k + 2]]
        })
        .collect();
    (pixels, w, h)
}

/// In the box `[x, y, w, h]` (2 px in from its edges): the pixels that
/// differ from the canvas background, the trail's (orange) and the leaf's
/// (green).
fn count_pixels(
    image: &[[u8; 3]],
    width: usize,
    height: usize,
    b: [usize; 4],
) -> (usize, usize, usize) {
    let (mut drawn, mut trail, mut leaf) = (0, 0, 0);
    for y in b[1] + 2..(b[1] + b[3]).min(height) - 2 {
        for x in b[0] + 2..(b[0] + b[2]).min(width) - 2 {
            let [r, g, bl] = image[y * width + x].map(i32::from);
            // The canvas background is #10161f.
            if (r - 0x10).abs() + (g - 0x16).abs() + (bl - 0x1f).abs() > 12 {
                drawn += 1;
            }
            // The trail is orange, faded: red well above blue and green.
            if r > bl + 40 && r > g + 15 {
                trail += 1;
            }
            // The leaf is green.
            if g > r + 40 && g > bl + 40 {
                leaf += 1;
            }
        }
    }
    (drawn, trail, leaf)
}

/// The ids of `session`'s candidates `ids`, best first by breed's score
/// (ties to the lower id), the first `n`.
fn best_of(s: &leafmagic::studio::Session, ids: &[u64], n: usize) -> Vec<u64> {
    let mut scored: Vec<(f64, u64)> = ids
        .iter()
        .map(|id| (s.find(*id).unwrap().1.evaluation.score, *id))
        .collect();
    scored.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    scored.iter().take(n).map(|(_, id)| *id).collect()
}

/// `leafmagic CMD ARGS` run to success, its standard output.
fn run_ok(args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_leafmagic"))
        .args(args)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "leafmagic {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// The leaf files `export` wrote in `out`, by id.
fn exported_ids(out: &Path, ext: &str) -> Vec<u64> {
    let mut ids: Vec<u64> = std::fs::read_dir(out)
        .unwrap()
        .filter_map(|e| {
            let name = e.unwrap().file_name().to_string_lossy().into_owned();
            name.strip_prefix("leaf-")?
                .strip_suffix(&format!(".{ext}"))?
                .parse()
                .ok()
        })
        .collect();
    ids.sort_unstable();
    ids
}

#[test]
fn a_studio_session_is_a_run_directory_that_export_and_preview_read() {
    use leafmagic::studio::{Session, StudioSettings};
    let dir = scratch("studio-as-run");
    let settings = StudioSettings {
        grid: 4,
        seconds: 2.0,
        ..StudioSettings::new("a", leafmagic::motion::classify::MotionClass::Floater, 5)
    };
    let proto = leafmagic::leaf::LeafSpec::load("a").unwrap();
    let mut s = Session::create(&dir, settings, proto).unwrap();
    let g0 = s.current().0.ids.clone();
    s.breed(&g0[..2], None).unwrap();
    let g1 = s.current().0.ids.clone();
    assert!(g1.iter().all(|id| !g0.contains(id)));
    let d = dir.to_str().unwrap();

    // No collection: the run's last generation is the one on screen.
    let top = best_of(&s, &g1, 2);
    let out = dir.join("top");
    run_ok(&[
        "export",
        d,
        "--top",
        "2",
        "--format",
        "glb",
        "--out",
        out.to_str().unwrap(),
    ]);
    let mut want = top.clone();
    want.sort_unstable();
    assert_eq!(exported_ids(&out, "glb"), want);
    assert_eq!(exported_ids(&out, "toml"), want);
    let page = dir.join("page.html");
    run_ok(&["preview", d, "--top", "2", "--out", page.to_str().unwrap()]);
    let html = std::fs::read_to_string(&page).unwrap();
    for id in g1.iter().chain(&g0) {
        assert_eq!(
            html.contains(&format!("\"leaf-{id}\"")),
            top.contains(id),
            "leaf-{id} on the page: only the 2 best of the generation on screen"
        );
    }
    // --ids names any leaf of it; one of an earlier generation is refused.
    let one = dir.join("one");
    run_ok(&[
        "export",
        d,
        "--ids",
        &g1[3].to_string(),
        "--out",
        one.to_str().unwrap(),
    ]);
    assert_eq!(exported_ids(&one, "toml"), [g1[3]]);

    // A collection of two or more is what the commands read, whatever is
    // on screen: two leaves of generation 0 kept, and --top 2 exports them
    // even with generation 1 on screen.
    s.keep(g0[3], true).unwrap();
    s.keep(g0[1], true).unwrap();
    let kept = dir.join("kept");
    run_ok(&["export", d, "--top", "2", "--out", kept.to_str().unwrap()]);
    assert_eq!(exported_ids(&kept, "toml"), [g0[1], g0[3]]);
    // The session reopens as it was, the run files beside it.
    let reopened = Session::open(&dir).unwrap();
    assert_eq!(reopened.file().kept, [g0[3], g0[1]]);
    let _ = std::fs::remove_dir_all(&dir);
}

/// `studio --like FILE`: the example fall (here the prototype a's own 2 s fall, a floater,
/// written as a tracked CSV record with attitudes) is read once, copied
/// into the session, shown in the state beside the collection labelled
/// as the example, and Auto N breeds toward it: each generation evaluates
/// three times the grid by the distance to the example's descriptors,
/// keeps the grid's worth, and the next one picks the two closest.
#[test]
fn studio_with_an_example_fall_shows_it_and_breeds_auto_toward_it() {
    let dir = scratch("studio-like");
    std::fs::create_dir_all(&dir).unwrap();
    let (_, model) = leafmagic::leaf::LeafSpec::load_with_model("a").unwrap();
    let params = leafmagic::sim::drop::DropParams {
        seconds: 2.0,
        ..Default::default()
    };
    let fall = leafmagic::sim::drop::drop_leaf(&model, &params).unwrap();
    let csv = dir.join("tracked.csv");
    std::fs::write(&csv, fall.trajectory.try_to_csv_bytes().unwrap()).unwrap();
    let session = dir.join("session");
    let (csv_s, out) = (csv.to_str().unwrap(), session.to_str().unwrap());

    // A file that is not there is refused before anything is bred.
    let missing = Command::new(env!("CARGO_BIN_EXE_leafmagic"))
        .args(["studio", "--out", out, "--like", "/nonexistent/fall.csv"])
        .output()
        .unwrap();
    assert!(!missing.status.success());
    let err = String::from_utf8_lossy(&missing.stderr);
    assert!(err.contains("/nonexistent/fall.csv"), "{err}");
    assert!(!session.join("studio.json").exists());

    let mut args = vec!["--out", out, "--seed", "4", "--like", csv_s];
    args.extend(SMALL);
    let s = Studio::start(&args, &session);
    let state = s.api("/api/state", "");
    let example = &state["example"];
    assert_eq!(example["name"], csv_s, "{example}");
    assert_eq!(
        example["class"], "floater",
        "as `classify` finds it: {example}"
    );
    assert!(example["motion"]["frames"].as_u64().unwrap() > 10);
    assert!(example["motion"]["vertices"].as_u64().unwrap() > 0);
    assert_eq!(
        std::fs::read(session.join("example.csv")).unwrap(),
        std::fs::read(&csv).unwrap(),
        "copied as read"
    );
    assert_eq!(s.session()["example"], csv_s);

    let (status, text) = s.call("POST", "/api/auto", "{\"generations\": 2}");
    assert_eq!(status, 202, "{text}");
    s.finish_breed();
    let gens = s.session()["generations"].as_array().unwrap().clone();
    assert_eq!(gens.len(), 3);
    for g in &gens[1..] {
        assert_eq!(g["example"], true, "{g}");
        assert_eq!(g["ids"].as_array().unwrap().len(), 4, "{g}");
    }
    // Every id of the pool is used up: 3 × 4 evaluated per generation.
    assert_eq!(s.session()["next_id"], 4 + 2 * 3 * 4);
    // Generation 2's picks: the two of generation 1 closest to the example
    // (no distance: last; ties to the earlier in the grid).
    let bred_from = read_json(&session.join("gen-001.json"));
    assert!(
        bred_from
            .as_array()
            .unwrap()
            .iter()
            .any(|c| c["evaluation"]["distance"].is_f64()),
        "{bred_from}"
    );
    // Closest first: the best by the negated distance.
    let closest = two_best(&bred_from, |e| {
        -e["distance"].as_f64().unwrap_or(f64::INFINITY)
    });
    assert_eq!(gens[2]["picks"], serde_json::json!(closest));
    drop(s);

    // Reopened, the session shows the same example again.
    let r = Studio::start(&["--resume", out], &session);
    assert_eq!(r.api("/api/state", "")["example"], state["example"]);
}

/// Auto N toward descriptors the person types: a name the classifier does
/// not describe is refused naming it; "descent=D" breeds each generation
/// from a pool of three grids' worth, keeps the grid's worth closest to
/// D, and picks the next parents by that distance, so the grid's descent
/// speeds move toward D.
#[test]
fn studio_auto_breeds_toward_typed_descriptors() {
    let dir = scratch("studio-toward");
    let s = start_in(&dir, "6");
    for body in [
        "{\"generations\": 1, \"toward\": \"wobble=3\"}",
        "{\"generations\": 1, \"toward\": \"descent\"}",
        "{\"generations\": 1, \"toward\": \"descent=fast\"}",
    ] {
        let (status, reason) = s.call("POST", "/api/auto", body);
        assert_eq!(status, 400, "{body}: {reason}");
        assert!(reason.contains("auto toward"), "{reason}");
    }
    let descents = |g: usize| -> Vec<f64> {
        read_json(&dir.join(format!("gen-{g:03}.json")))
            .as_array()
            .unwrap()
            .iter()
            .filter_map(|c| c["evaluation"]["descent_m_s"].as_f64())
            .collect()
    };
    let first = descents(0);
    // A target well below every descent of the first grid.
    let target = 0.5 * first.iter().cloned().fold(f64::INFINITY, f64::min);
    let body = format!("{{\"generations\": 2, \"toward\": \"descent={target}\"}}");
    let (status, text) = s.call("POST", "/api/auto", &body);
    assert_eq!(status, 202, "{text}");
    s.finish_breed();
    let gens = s.session()["generations"].as_array().unwrap().clone();
    assert_eq!(gens.len(), 3);
    for g in &gens[1..] {
        assert_eq!(g["auto"], true, "{g}");
        assert_eq!(g["toward"]["descriptors"]["descent"], target, "{g}");
        assert!(g.get("example").is_none(), "{g}");
    }
    assert_eq!(s.session()["next_id"], 4 + 2 * 3 * 4);
    let closest = two_best(&read_json(&dir.join("gen-001.json")), |e| {
        -e["distance"].as_f64().unwrap_or(f64::INFINITY)
    });
    assert_eq!(gens[2]["picks"], serde_json::json!(closest));
    let off = |d: &[f64]| {
        let mut e: Vec<f64> = d.iter().map(|v| (v - target).abs()).collect();
        e.sort_by(f64::total_cmp);
        e[e.len() / 2]
    };
    let (before, after) = (off(&first), off(&descents(2)));
    assert!(
        after < before,
        "median |descent − {target}|: {before} in generation 0, {after} in generation 2"
    );
    let state = s.api("/api/state", "");
    let tree = &state["tree"];
    assert_eq!(
        tree[2]["toward"]["descriptors"]["descent"], target,
        "{tree}"
    );
    assert_eq!(tree[2]["toward"]["source"], "features", "{tree}");

    // Toward a candidate's fall: its shown drop's descriptors, for every
    // generation of the Auto; not both, and only a candidate on the grid.
    let id = state["generation"]["ids"][0].as_u64().unwrap();
    for body in [
        format!("{{\"generations\": 1, \"like\": {id}, \"toward\": \"descent=1\"}}"),
        "{\"generations\": 1, \"like\": 999999}".to_string(),
    ] {
        let (status, reason) = s.call("POST", "/api/auto", &body);
        assert_eq!(status, 400, "{body}: {reason}");
    }
    let (status, text) = s.call(
        "POST",
        "/api/auto",
        &format!("{{\"generations\": 2, \"like\": {id}}}"),
    );
    assert_eq!(status, 202, "{text}");
    s.finish_breed();
    let gens = s.session()["generations"].as_array().unwrap().clone();
    assert_eq!(gens.len(), 5);
    for g in &gens[3..] {
        assert_eq!(g["toward"]["source"], format!("leaf-{id}"), "{g}");
        assert_eq!(g["toward"]["descriptors"], gens[3]["toward"]["descriptors"]);
    }
    assert_eq!(gens[3]["parent"], 2);
}

/// `studio --law real`: the session's prototype falls under the real-paper
/// law (prototype.toml says so, as the page's state does), and the same
/// seed's candidates fall otherwise than under the paper's law; a session
/// is reopened with its own law only (`--resume` takes no `--law`).
#[test]
fn studio_law_sets_the_session_law_and_the_state_says_it() {
    let descents = |law: &str| {
        let dir = scratch(&format!("law-{law}"));
        let out = dir.to_str().unwrap().to_string();
        let mut args = vec!["--out", out.as_str(), "--law", law];
        args.extend(SMALL);
        let s = Studio::start(&args, &dir);
        let state = s.api("/api/state", "");
        let proto = std::fs::read_to_string(dir.join("prototype.toml")).unwrap();
        let candidates = state["candidates"].as_array().unwrap().clone();
        let d: Vec<f64> = candidates
            .iter()
            .map(|c| c["descent_m_s"].as_f64().unwrap_or(f64::NAN))
            .collect();
        (state["aero_law"].clone(), proto, d, dir)
    };
    let (real_law, real_proto, real, dir) = descents("real");
    let (paper_law, paper_proto, paper, _) = descents("paper");
    assert_eq!((real_law, paper_law), ("unsteady".into(), "linear".into()));
    assert!(real_proto.contains("law = \"unsteady\""), "{real_proto}");
    assert!(paper_proto.contains("law = \"linear\""), "{paper_proto}");
    assert_ne!(real, paper);
    let refused = Command::new(env!("CARGO_BIN_EXE_leafmagic"))
        .args([
            "studio",
            "--resume",
            dir.to_str().unwrap(),
            "--law",
            "paper",
        ])
        .output()
        .unwrap();
    assert!(!refused.status.success());
}
