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
//! /api/breed` `{"picks": [id, ...], "scale": s?}`; `POST /api/back` `{}`;
//! `POST /api/goto` `{"generation": k}`. Each answers with the state.

use super::session::{MOTION_FPS, Session, StudioError};
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

/// What every request is checked against.
struct Shared {
    session: Mutex<Session>,
    token: String,
    hosts: [String; 2],
    origins: [String; 2],
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
            .layer(DefaultBodyLimit::max(MAX_BODY))
            .layer(middleware::from_fn_with_state(shared.clone(), guard))
            .with_state(shared);
        self.listener.set_nonblocking(true)?;
        // One thread answers requests; breeding runs on the blocking pool
        // and its drops on rayon's, so the server stays responsive.
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

/// Runs `action` on the session off the async thread (breeding takes
/// seconds) and answers with the state, or the action's refusal.
async fn with_session(
    app: Arc<Shared>,
    action: impl FnOnce(&mut Session) -> Result<(), StudioError> + Send + 'static,
) -> Response {
    let result = tokio::task::spawn_blocking(move || {
        // A panic in an earlier action leaves the session as its files
        // last recorded it: go on with it.
        let mut session = app.session.lock().unwrap_or_else(|e| e.into_inner());
        action(&mut session).map(|()| state_json(&session))
    })
    .await;
    match result {
        Ok(Ok(body)) => (
            [(header::CONTENT_TYPE, "application/json")],
            body.to_string(),
        )
            .into_response(),
        Ok(Err(StudioError::Input(reason))) => refuse(StatusCode::BAD_REQUEST, reason),
        Ok(Err(e)) => refuse(StatusCode::INTERNAL_SERVER_ERROR, e.to_string()),
        Err(e) => refuse(StatusCode::INTERNAL_SERVER_ERROR, format!("failed: {e}")),
    }
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
    with_session(app, |_| Ok(())).await
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
        Ok(r) => with_session(app, move |s| s.breed(&r.picks, r.scale)).await,
        Err(refusal) => refusal,
    }
}

/// `POST /api/back`: an empty object.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BackRequest {}

async fn back(State(app): State<Arc<Shared>>, body: Bytes) -> Response {
    match parse::<BackRequest>(&body) {
        Ok(BackRequest {}) => with_session(app, Session::back).await,
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
        Ok(r) => with_session(app, move |s| s.go_to(r.generation)).await,
        Err(refusal) => refusal,
    }
}

/// What the page shows: the settings, the tree, the current generation
/// with every candidate's numbers and fall.
pub fn state_json(session: &Session) -> serde_json::Value {
    let file = session.file();
    let (node, generation) = session.current();
    let candidates: Vec<serde_json::Value> = generation
        .candidates
        .iter()
        .zip(&generation.motion)
        .map(|(c, m)| {
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
                "motion": m,
            })
        })
        .collect();
    json!({
        "settings": file.settings,
        "dir": session.dir().display().to_string(),
        "generation": node,
        "next_scale": session.next_scale(),
        "tree": file.generations.iter().map(|g| json!({
            "index": g.index,
            "parent": g.parent,
            "picks": g.picks,
            "scale": g.scale,
        })).collect::<Vec<_>>(),
        "fps": MOTION_FPS,
        "candidates": candidates,
    })
}
