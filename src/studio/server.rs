//! The studio's local web server: the page and a small JSON API over one
//! [`Session`].
//!
//! Security model (docs/guide/studio.md): it listens on 127.0.0.1 only; every
//! request must carry the session's random token (`?token=` or the
//! `X-Leafmagic-Token` header), a Host of `127.0.0.1:PORT` or
//! `localhost:PORT` (so a page that rebinds its own name to 127.0.0.1
//! cannot reach it) and no Origin but the server's own (so no other page
//! open in the browser can drive it); bodies are bounded; nothing a
//! request carries is used as a path. Every refusal is a 4xx with the
//! reason, and the server goes on.
//!
//! API (bodies JSON): `GET /` the page; `GET /api/state`; `POST
//! /api/breed` `{"picks": [id, ...], "scale": s?}` starts breeding in the
//! background (202; 409 while another generation is being bred) and `GET
//! /api/progress?from=N` tells how far it is, with the candidates finished
//! since the Nth; `POST /api/back` `{}`; `POST /api/goto` `{"generation":
//! k}`; `POST /api/keep` `{"id": id, "keep": bool?}`; `POST /api/export`
//! `{"fps": f, "start_height_m": h}` writes the collection under the
//! session's `export/`; `POST /api/auto` `{"generations": n}` breeds n
//! generations from the machine's picks in the background, as Breed, and
//! `POST /api/like` `{"id": id, "scale": s?}` one toward `id`'s fall. Each but progress and export answers with the
//! state.

use super::collection::{ExportRequest, export_collection};
use super::session::{
    Candidate, CandidateMotion, MAX_AUTO, MOTION_FPS, Pending, Session, StudioError,
};
use crate::motion::describe::MotionTarget;
use axum::Router;
use axum::body::Bytes;
use axum::extract::{DefaultBodyLimit, Request, State};
use axum::http::{HeaderValue, StatusCode, header};
use axum::middleware::{self, Next};
use axum::response::{IntoResponse, Response};
use axum::routing::{get, post};
use serde::Deserialize;
use serde_json::json;
use std::net::{Ipv4Addr, SocketAddr, TcpListener};
use std::sync::{Arc, Mutex};

/// Largest request body, bytes: a request names a few ids and a number,
/// so 64 KiB is ample and keeps a hostile body from costing memory.
pub const MAX_BODY: usize = 64 * 1024;
/// The header that may carry the token instead of the query.
pub const TOKEN_HEADER: &str = "x-leafmagic-token";

const PAGE: &str = include_str!("page.html");
const SCRIPT: &str = include_str!("studio.js");

/// The page: what no request can change, with the script inlined (nothing
/// is fetched but the API's JSON).
fn page() -> String {
    PAGE.replace("/*SCRIPT*/", SCRIPT)
}

/// A bound server, not yet serving.
#[derive(Debug)]
pub struct Server {
    listener: TcpListener,
    token: String,
    port: u16,
}

/// What every request is checked against, and the session with the
/// generation being bred.
///
/// Lock order: `session` before `job`, never the other way (a request
/// that must look at both takes the session first).
struct Shared {
    session: Mutex<Session>,
    job: Mutex<Option<Arc<Job>>>,
    /// Why the last breeding failed, until the next one starts.
    breed_error: Mutex<Option<String>>,
    token: String,
    hosts: [String; 2],
    origins: [String; 2],
}

/// A generation being bred in the background.
struct Job {
    /// Of an "Auto N": which generation of how many (1-based).
    auto: Option<(usize, usize)>,
    index: usize,
    parent: Option<usize>,
    picks: Vec<u64>,
    candidates: usize,
    releases: usize,
    /// The candidates finished so far, in the order they finished, each
    /// with its grid slot.
    finished: Mutex<Vec<serde_json::Value>>,
}

impl Job {
    fn new(pending: &Pending, auto: Option<(usize, usize)>) -> Job {
        let node = pending.node();
        Job {
            auto,
            index: node.index,
            parent: node.parent,
            picks: node.picks.clone(),
            candidates: node.ids.len(),
            releases: pending.releases(),
            finished: Mutex::new(Vec::new()),
        }
    }

    /// Its progress, with the finished candidates from the `from`th on.
    fn progress(&self, from: usize) -> serde_json::Value {
        let finished = self.finished.lock().unwrap_or_else(|e| e.into_inner());
        let done = finished.len();
        json!({
            "auto": self.auto,
            "generation": self.index,
            "parent": self.parent,
            "picks": self.picks,
            "candidates": self.candidates,
            "done": done,
            "drops_done": done * self.releases,
            "drops": self.candidates * self.releases,
            "finished": finished.get(from..).unwrap_or(&[]),
        })
    }
}

fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    // A panic in an earlier action leaves the session as its files last
    // recorded it: go on with it.
    m.lock().unwrap_or_else(|e| e.into_inner())
}

impl Server {
    /// Binds 127.0.0.1:`port` (0: any free port) with a fresh token of 128
    /// bits from the operating system's generator.
    pub fn bind(port: u16) -> std::io::Result<Server> {
        use rand::TryRng as _;
        let mut bytes = [0u8; 16];
        rand::rngs::SysRng
            .try_fill_bytes(&mut bytes)
            .map_err(std::io::Error::other)?;
        let token = bytes.iter().map(|b| format!("{b:02x}")).collect();
        let listener = TcpListener::bind(SocketAddr::from((Ipv4Addr::LOCALHOST, port)))?;
        let port = listener.local_addr()?.port();
        Ok(Server {
            listener,
            token,
            port,
        })
    }

    /// The port listened on.
    pub fn port(&self) -> u16 {
        self.port
    }

    /// The page's address, token included.
    pub fn url(&self) -> String {
        format!("http://127.0.0.1:{}/?token={}", self.port, self.token)
    }

    /// Serves `session` until the process ends (or the listener fails).
    pub fn serve(self, session: Session) -> std::io::Result<()> {
        let port = self.port;
        let shared = Arc::new(Shared {
            session: Mutex::new(session),
            job: Mutex::new(None),
            breed_error: Mutex::new(None),
            token: self.token,
            hosts: [format!("127.0.0.1:{port}"), format!("localhost:{port}")],
            origins: [
                format!("http://127.0.0.1:{port}"),
                format!("http://localhost:{port}"),
            ],
        });
        let app = Router::new()
            .route("/", get(serve_page))
            .route("/api/state", get(state))
            .route("/api/breed", post(breed))
            .route("/api/back", post(back))
            .route("/api/goto", post(go_to))
            .route("/api/progress", get(progress))
            .route("/api/auto", post(auto))
            .route("/api/like", post(like))
            .route("/api/keep", post(keep))
            .route("/api/export", post(export))
            .layer(DefaultBodyLimit::max(MAX_BODY))
            .layer(middleware::from_fn_with_state(shared.clone(), guard))
            .with_state(shared);
        self.listener.set_nonblocking(true)?;
        // One thread answers requests; actions run on the blocking pool,
        // breeding on a thread of its own with its drops on rayon's, so the
        // server stays responsive.
        let runtime = tokio::runtime::Builder::new_current_thread()
            .enable_io()
            .build()?;
        runtime.block_on(async move {
            let listener = tokio::net::TcpListener::from_std(self.listener)?;
            axum::serve(listener, app).await
        })
    }
}

/// A refusal with its reason as text.
fn refuse(status: StatusCode, reason: impl Into<String>) -> Response {
    let mut text = reason.into();
    text.push('\n');
    (status, text).into_response()
}

/// Equal without an early exit, so the time taken says nothing of how
/// much of a guess was right.
fn same(a: &str, b: &str) -> bool {
    a.len() == b.len() && a.bytes().zip(b.bytes()).fold(0u8, |d, (x, y)| d | (x ^ y)) == 0
}

/// The checks every request passes before any handler sees it.
async fn guard(State(app): State<Arc<Shared>>, request: Request, next: Next) -> Response {
    let headers = request.headers();
    let text = |name: header::HeaderName| headers.get(name).and_then(|v| v.to_str().ok());
    if !text(header::HOST).is_some_and(|h| app.hosts.iter().any(|a| a == h)) {
        return refuse(
            StatusCode::FORBIDDEN,
            format!(
                "refused: the Host header must be {} or {} (a request for another name may \
                 come from a page that rebound its name to this machine)",
                app.hosts[0], app.hosts[1]
            ),
        );
    }
    let from_query = request.uri().query().and_then(|q| {
        q.split('&')
            .find_map(|kv| kv.strip_prefix("token="))
            .map(str::to_string)
    });
    let given = from_query.or_else(|| {
        headers
            .get(TOKEN_HEADER)
            .and_then(|v| v.to_str().ok())
            .map(str::to_string)
    });
    if !given.is_some_and(|t| same(&t, &app.token)) {
        return refuse(
            StatusCode::FORBIDDEN,
            "refused: a missing or wrong session token (open the URL the studio printed)",
        );
    }
    if let Some(origin) = headers.get(header::ORIGIN) {
        let ok = origin
            .to_str()
            .is_ok_and(|o| app.origins.iter().any(|a| a == o));
        if !ok {
            return refuse(
                StatusCode::FORBIDDEN,
                format!(
                    "refused: requests from another page (Origin {:?}); only {} may drive \
                     the studio",
                    origin, app.origins[0]
                ),
            );
        }
    }
    let mut response = next.run(request).await;
    let h = response.headers_mut();
    // The token is in the URL: never sent on, never cached, never framed.
    h.insert(
        header::REFERRER_POLICY,
        HeaderValue::from_static("no-referrer"),
    );
    h.insert(header::CACHE_CONTROL, HeaderValue::from_static("no-store"));
    h.insert(
        header::CONTENT_SECURITY_POLICY,
        HeaderValue::from_static(
            "default-src 'none'; script-src 'unsafe-inline'; style-src 'unsafe-inline'; \
             connect-src 'self'; frame-ancestors 'none'",
        ),
    );
    response
}

async fn serve_page() -> Response {
    ([(header::CONTENT_TYPE, "text/html; charset=utf-8")], page()).into_response()
}

/// What an action answers: a JSON body with its status, or a refusal.
type Answer = Result<(StatusCode, serde_json::Value), Response>;

fn studio_refusal(e: StudioError) -> Response {
    match e {
        StudioError::Input(reason) => refuse(StatusCode::BAD_REQUEST, reason),
        e => refuse(StatusCode::INTERNAL_SERVER_ERROR, e.to_string()),
    }
}

/// Runs `action` off the async thread (writing files waits for the disk)
/// and answers with what it returns.
async fn blocking(
    app: Arc<Shared>,
    action: impl FnOnce(&Arc<Shared>) -> Answer + Send + 'static,
) -> Response {
    match tokio::task::spawn_blocking(move || action(&app)).await {
        Ok(Ok((status, body))) => (
            status,
            [(header::CONTENT_TYPE, "application/json")],
            body.to_string(),
        )
            .into_response(),
        Ok(Err(refusal)) => refusal,
        Err(e) => refuse(StatusCode::INTERNAL_SERVER_ERROR, format!("failed: {e}")),
    }
}

/// Runs `action` on the session and answers with the state, or the
/// action's refusal. With `moves` (the action changes the generation on
/// screen) it is refused while a generation is being bred: the page
/// would show one generation and receive another's candidates.
async fn with_session(
    app: Arc<Shared>,
    moves: bool,
    action: impl FnOnce(&mut Session) -> Result<(), StudioError> + Send + 'static,
) -> Response {
    blocking(app, move |app| {
        let mut session = lock(&app.session);
        if moves && let Some(job) = lock(&app.job).as_ref() {
            return Err(busy(job));
        }
        action(&mut session).map_err(studio_refusal)?;
        Ok((StatusCode::OK, state_json(app, &session)))
    })
    .await
}

/// The 409 while generation `job` is being bred.
fn busy(job: &Job) -> Response {
    let done = lock(&job.finished).len();
    refuse(
        StatusCode::CONFLICT,
        format!(
            "busy: generation {} is being bred ({done} of {} candidates done); wait for it \
             (GET /api/progress)",
            job.index, job.candidates
        ),
    )
}

/// A JSON body as `T`, or the 400 that says why not.
fn parse<T: for<'de> Deserialize<'de>>(body: &Bytes) -> Result<T, Response> {
    serde_json::from_slice(body).map_err(|e| {
        refuse(
            StatusCode::BAD_REQUEST,
            format!("malformed request body: {e}"),
        )
    })
}

async fn state(State(app): State<Arc<Shared>>) -> Response {
    with_session(app, false, |_| Ok(())).await
}

/// `GET /api/progress?from=N`: the generation being bred (null when none)
/// with its candidates finished from the Nth on, the generation on screen
/// and why the last breeding failed, if it did.
async fn progress(State(app): State<Arc<Shared>>, request: Request) -> Response {
    let from = match request.uri().query().and_then(|q| {
        q.split('&')
            .find_map(|kv| kv.strip_prefix("from="))
            .map(str::parse::<usize>)
    }) {
        None => 0,
        Some(Ok(n)) => n,
        Some(Err(e)) => {
            return refuse(
                StatusCode::BAD_REQUEST,
                format!("progress: from= must be a count of candidates: {e}"),
            );
        }
    };
    blocking(app, move |app| {
        let session = lock(&app.session);
        let breeding = lock(&app.job).as_ref().map(|j| j.progress(from));
        Ok((
            StatusCode::OK,
            json!({
                "generation": session.file().current,
                "breeding": breeding,
                "breed_error": lock(&app.breed_error).clone(),
            }),
        ))
    })
    .await
}

/// `POST /api/breed`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BreedRequest {
    picks: Vec<u64>,
    #[serde(default)]
    scale: Option<f64>,
}

async fn breed(State(app): State<Arc<Shared>>, body: Bytes) -> Response {
    match parse::<BreedRequest>(&body) {
        Ok(r) => blocking(app, move |app| start_breeding(app, &r)).await,
        Err(refusal) => refusal,
    }
}

/// Plans the generation, starts its evaluation on a thread of its own and
/// answers at once (202, the state with the breeding's progress).
fn start_breeding(app: &Arc<Shared>, r: &BreedRequest) -> Answer {
    start_job(app, false, 1, None, |s| s.plan(&r.picks, r.scale))
}

/// `POST /api/like`: "More like this" of candidate `id`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct LikeRequest {
    id: u64,
    #[serde(default)]
    scale: Option<f64>,
}

async fn like(State(app): State<Arc<Shared>>, body: Bytes) -> Response {
    match parse::<LikeRequest>(&body) {
        Ok(r) => {
            blocking(app, move |app| {
                start_job(app, false, 1, None, |s| s.plan_like(r.id, r.scale))
            })
            .await
        }
        Err(refusal) => refusal,
    }
}

/// `POST /api/auto`: `generations` bred one after another from the
/// machine's picks ([`Session::plan_auto`]), then the person again;
/// `toward` (optional) names descriptors to breed toward, as
/// `descent=0.8, spin=4` ([`MotionTarget::parse_features`]); `like`
/// (optional, not with `toward`) a candidate on the grid whose fall every
/// generation is bred toward ([`Session::fall_target`]).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct AutoRequest {
    generations: usize,
    #[serde(default)]
    toward: Option<String>,
    #[serde(default)]
    like: Option<u64>,
}

async fn auto(State(app): State<Arc<Shared>>, body: Bytes) -> Response {
    let r = match parse::<AutoRequest>(&body) {
        Ok(r) => r,
        Err(refusal) => return refusal,
    };
    if !(1..=MAX_AUTO).contains(&r.generations) {
        return refuse(
            StatusCode::BAD_REQUEST,
            format!(
                "auto: generations must be 1 to {MAX_AUTO}, got {}",
                r.generations
            ),
        );
    }
    let toward = match r.toward.as_deref().map(str::trim) {
        None | Some("") => None,
        Some(text) => match MotionTarget::parse_features(text, None) {
            Ok(t) => Some(t),
            Err(e) => return refuse(StatusCode::BAD_REQUEST, format!("auto toward: {e}")),
        },
    };
    if toward.is_some() && r.like.is_some() {
        return refuse(
            StatusCode::BAD_REQUEST,
            "auto: breed toward typed descriptors or toward a candidate's fall, not both"
                .to_string(),
        );
    }
    blocking(app, move |app| {
        let toward = match r.like {
            Some(id) => Some(lock(&app.session).fall_target(id).map_err(studio_refusal)?),
            None => toward,
        };
        start_job(app, true, r.generations, toward.clone(), move |s| {
            s.plan_auto(toward.as_ref())
        })
    })
    .await
}

/// Starts breeding the generation `plan` makes and then, to `total`, the
/// machine's ([`Session::plan_auto`] toward `toward`), on a thread of
/// their own, and answers at once (202, the state with the progress;
/// `auto` marks the progress of an "Auto N"). The thread records each candidate as it
/// finishes and commits each generation whole when its last one does: the
/// files hold only whole generations.
fn start_job(
    app: &Arc<Shared>,
    auto: bool,
    total: usize,
    toward: Option<MotionTarget>,
    plan: impl FnOnce(&Session) -> Result<Pending, StudioError>,
) -> Answer {
    if let Some(job) = lock(&app.job).as_ref() {
        return Err(busy(job));
    }
    let auto = move |k: usize| auto.then_some((k, total));
    let (pending, job) = {
        let session = lock(&app.session);
        let pending = plan(&session).map_err(studio_refusal)?;
        let mut slot = lock(&app.job);
        // Another request may have started one between the two looks.
        if let Some(job) = slot.as_ref() {
            return Err(busy(job));
        }
        let job = Arc::new(Job::new(&pending, auto(1)));
        *slot = Some(job.clone());
        *lock(&app.breed_error) = None;
        (pending, job)
    };
    let worker = app.clone();
    let spawned = std::thread::Builder::new()
        .name("studio-breed".to_string())
        .spawn(move || {
            let (mut pending, mut job) = (pending, job);
            for k in 1..=total {
                let shown = job.clone();
                let evaluated = pending.evaluate(|slot, c, m| {
                    let mut json = candidate_json(c, m);
                    json["slot"] = json!(slot);
                    lock(&shown.finished).push(json);
                });
                let mut session = lock(&worker.session);
                let next = session.commit(evaluated).and_then(|()| {
                    (k < total)
                        .then(|| session.plan_auto(toward.as_ref()))
                        .transpose()
                });
                let mut slot = lock(&worker.job);
                match next {
                    Ok(Some(p)) => {
                        job = Arc::new(Job::new(&p, auto(k + 1)));
                        *slot = Some(job.clone());
                        pending = p;
                    }
                    Ok(None) => break,
                    Err(e) => {
                        *lock(&worker.breed_error) = Some(e.to_string());
                        break;
                    }
                }
            }
            *lock(&worker.job) = None;
        });
    if let Err(e) = spawned {
        *lock(&app.job) = None;
        return Err(refuse(
            StatusCode::INTERNAL_SERVER_ERROR,
            format!("could not start breeding: {e}"),
        ));
    }
    let session = lock(&app.session);
    Ok((StatusCode::ACCEPTED, state_json(app, &session)))
}

/// `POST /api/back`: an empty object.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BackRequest {}

async fn back(State(app): State<Arc<Shared>>, body: Bytes) -> Response {
    match parse::<BackRequest>(&body) {
        Ok(BackRequest {}) => with_session(app, true, Session::back).await,
        Err(refusal) => refusal,
    }
}

/// `POST /api/goto`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct GoToRequest {
    generation: usize,
}

async fn go_to(State(app): State<Arc<Shared>>, body: Bytes) -> Response {
    match parse::<GoToRequest>(&body) {
        Ok(r) => with_session(app, true, move |s| s.go_to(r.generation)).await,
        Err(refusal) => refusal,
    }
}

/// `POST /api/keep`: `keep` false takes the leaf out of the collection.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct KeepRequest {
    id: u64,
    #[serde(default = "yes")]
    keep: bool,
}

fn yes() -> bool {
    true
}

async fn keep(State(app): State<Arc<Shared>>, body: Bytes) -> Response {
    match parse::<KeepRequest>(&body) {
        Ok(r) => with_session(app, false, move |s| s.keep(r.id, r.keep)).await,
        Err(refusal) => refusal,
    }
}

/// `POST /api/export`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ExportBody {
    fps: f64,
    start_height_m: f64,
}

/// Answers with the folder and the files written, relative to the
/// session directory.
async fn export(State(app): State<Arc<Shared>>, body: Bytes) -> Response {
    let r = match parse::<ExportBody>(&body) {
        Ok(r) => ExportRequest {
            fps: r.fps,
            start_height_m: r.start_height_m,
        },
        Err(refusal) => return refusal,
    };
    blocking(app, move |app| {
        let session = lock(&app.session);
        let files = export_collection(&session, r).map_err(studio_refusal)?;
        Ok((
            StatusCode::OK,
            json!({
                "dir": session.dir().join(super::collection::EXPORT_DIR).display().to_string(),
                "files": files.iter().map(|f| f.display().to_string()).collect::<Vec<_>>(),
            }),
        ))
    })
    .await
}

/// A candidate as the page shows it: its numbers and its fall.
fn candidate_json(c: &Candidate, m: &CandidateMotion) -> serde_json::Value {
    let r = c.evaluation.record();
    json!({
        "id": c.id,
        "origin": c.origin,
        "parents": c.parents,
        "class": r.class,
        "regime": r.regime,
        "score": r.score,
        "descent_m_s": r.descent_m_s,
        "drift_ratio": r.drift_ratio,
        "spin_rad_s": r.spin_rad_s,
        "kept": r.kept,
        "releases": r.releases,
        "error": r.error,
        "distance": r.distance,
        "motion": m,
    })
}

/// What the page shows: the settings, the tree, the current generation
/// with every candidate's numbers and fall, the collection (with the
/// falls, to play side by side) and the breeding under way, if any.
fn state_json(app: &Shared, session: &Session) -> serde_json::Value {
    let file = session.file();
    let (node, generation) = session.current();
    let preference = session.preference();
    let candidates: Vec<serde_json::Value> = generation
        .candidates
        .iter()
        .zip(&generation.motion)
        .map(|(c, m)| {
            let mut shown = candidate_json(c, m);
            shown["taste"] = json!(preference.as_ref().and_then(|p| p.taste(&c.evaluation)));
            shown
        })
        .collect();
    let collection: Vec<serde_json::Value> = file
        .kept
        .iter()
        .filter_map(|id| session.find(*id))
        .map(|(k, c, m)| {
            let mut shown = candidate_json(c, m);
            shown["generation"] = json!(k);
            shown
        })
        .collect();
    json!({
        "collection": collection,
        "breeding": lock(&app.job).as_ref().map(|j| j.progress(usize::MAX)),
        "breed_error": lock(&app.breed_error).clone(),
        "taste_judgements": preference.as_ref().map(|p| p.judgements),
        "settings": file.settings,
        "aero_law": session.prototype().aero.law,
        "dir": session.dir().display().to_string(),
        "generation": node,
        "next_scale": session.next_scale(),
        "tree": file.generations.iter().map(|g| json!({
            "index": g.index,
            "parent": g.parent,
            "picks": g.picks,
            "scale": g.scale,
            "auto": g.auto,
            "like": g.like,
            "toward": g.toward.as_ref().map(|t| json!({
                "source": t.source,
                "descriptors": t.descriptors,
            })),
        })).collect::<Vec<_>>(),
        "fps": MOTION_FPS,
        "candidates": candidates,
        "example": session.example().map(|e| json!({
            "name": e.name,
            "class": e.class,
            "motion": e.motion,
        })),
    })
}
