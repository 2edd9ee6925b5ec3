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
/// Enter, screenshots the new grid (clock held at 1.5 s), goes back with
/// Backspace. Prints what the Rust side checks, as JSON. Any request to
/// another server is recorded (the page must need none).
const BROWSER_PY: &str = r##"
import json, sys
from playwright.sync_api import sync_playwright
url, chromium, shot = sys.argv[1:4]
with sync_playwright() as p:
    browser = p.chromium.launch(executable_path=chromium, args=["--no-sandbox", "--disable-gpu"])
    page = browser.new_page(viewport={"width": 1000, "height": 760}, device_scale_factor=1)
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
    page.keyboard.press("Enter")
    page.wait_for_selector('body[data-drawn="1"]', timeout=600000)
    page.wait_for_timeout(500)
    page.screenshot(path=shot)
    boxes = page.eval_on_selector_all(".cell canvas",
        "els => els.map(e => { const r = e.getBoundingClientRect(); return [r.x, r.y, r.width, r.height]; })")
    status = page.inner_text("#status")
    page.keyboard.press("Backspace")
    page.wait_for_selector('body[data-generation="0"]', timeout=60000)
    browser.close()
print(json.dumps({"ids": ids, "picked": picked, "boxes": boxes, "errors": errors,
                  "foreign": foreign, "status": status}))
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
    let out = Command::new(&python)
        .args(["-c", BROWSER_PY, &url])
        .arg(&chromium)
        .arg(&shot)
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
    assert_eq!(session["current"], 0);

    // Every cell of the new grid drew its leaf and its trail.
    let mut decoder =
        png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&shot).unwrap()));
    decoder.set_transformations(png::Transformations::EXPAND | png::Transformations::STRIP_16);
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    let channels = info.line_size / info.width as usize;
    let pixel = |x: usize, y: usize| {
        let k = y * info.line_size + x * channels;
        [buf[k], buf[k + 1], buf[k + 2]]
    };
    let boxes = report["boxes"].as_array().unwrap();
    assert_eq!(boxes.len(), 4, "{report}");
    for (k, b) in boxes.iter().enumerate() {
        let b: Vec<usize> = (0..4).map(|i| b[i].as_f64().unwrap() as usize).collect();
        let (mut drawn, mut trail, mut leaf) = (0, 0, 0);
        for y in b[1] + 2..(b[1] + b[3]).min(info.height as usize) - 2 {
            for x in b[0] + 2..(b[0] + b[2]).min(info.width as usize) - 2 {
                let [r, g, bl] = pixel(x, y).map(i32::from);
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
        assert!(
            drawn > 500 && trail > 20 && leaf > 20,
            "cell {k}: {drawn} drawn, {trail} trail and {leaf} leaf pixels ({})",
            shot.display()
        );
    }
}
