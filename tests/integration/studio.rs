//! `leafmagic studio`: its server refuses what it must (no token, a foreign
//! Host or Origin, a large or malformed body) and keeps running; breeding
//! from picks records the picks and parents, going back and branching makes
//! a tree, a session reopens where it was, and the same seed and picks
//! write the same bytes. Requests are plain HTTP over a TcpStream.

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

#[test]
fn studio_refuses_what_it_must_and_keeps_running() {
    let dir = scratch("studio-security");
    let s = start_in(&dir, "3");
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
}

/// Breeds from two picks, goes back, branches from one pick: the session's
/// tree after these three actions.
fn pick_breed_back_branch(s: &Studio) -> (Vec<u64>, Vec<u64>) {
    let g0 = ids(&s.api("/api/state", ""));
    let two = vec![g0[1], g0[2]];
    let g1 = s.api(
        "/api/breed",
        &format!("{{\"picks\": [{}, {}]}}", two[0], two[1]),
    );
    assert_eq!(g1["generation"]["index"], 1);
    let back = s.api("/api/back", "{}");
    assert_eq!(back["generation"]["index"], 0);
    assert_eq!(ids(&back), g0);
    let one = vec![g0[0]];
    let g2 = s.api(
        "/api/breed",
        &format!("{{\"picks\": [{}], \"scale\": 0.5}}", one[0]),
    );
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
    let g2 = read_json(&dir.join("gen-002.json"));
    for c in g2.as_array().unwrap() {
        let p = c["parents"].as_array().unwrap();
        assert!(p.is_empty() || p == &[Value::from(one[0])], "{c}");
    }
    // The motion each is shown with.
    let motion = read_json(&dir.join("gen-001-motion.json"));
    assert!(motion[0]["frames"].as_u64().unwrap() > 20, "{}", motion[0]);

    // Reopened, it is where it was, and goes on.
    let before = s.api("/api/state", "");
    drop(s);
    let r = Studio::start(&["--resume", dir.to_str().unwrap()], &dir);
    let after = r.api("/api/state", "");
    assert_eq!(after["generation"], before["generation"]);
    assert_eq!(after["candidates"], before["candidates"]);
    let back = r.api("/api/back", "{}");
    assert_eq!(back["generation"]["index"], 0);
}

/// Every file under `dir`, by relative path, with its bytes.
fn files(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else {
                out.push((
                    p.strip_prefix(dir).unwrap().to_path_buf(),
                    std::fs::read(&p).unwrap(),
                ));
            }
        }
    }
    out.sort();
    out
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
    let (fa, fb) = (files(&da), files(&db));
    let names = |f: &[(PathBuf, Vec<u8>)]| f.iter().map(|(p, _)| p.clone()).collect::<Vec<_>>();
    assert_eq!(names(&fa), names(&fb));
    assert!(fa.len() > 10, "{:?}", names(&fa));
    for ((p, x), (_, y)) in fa.iter().zip(&fb) {
        assert!(x == y, "{} differs", p.display());
    }
    drop((a, b));
}
