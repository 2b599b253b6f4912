//! `cargo host serve`: the machine in a web page, for a browser on this PC or a
//! phone on the same network.
//!
//! The page (assets/, built into the binary, no CDN: it works offline) talks to
//! the server over one websocket. The server is axum on tokio; the machine link
//! runs on a thread of its own (link.rs) and its messages are broadcast to every
//! browser. Many browsers may watch; one controls at a time: a browser allowed
//! to control (access.rs) takes control with its first command or the "take
//! control" button, and every other browser then watches.

pub mod access;
pub mod job;
pub mod link;

use access::{same_origin, Access, Role};
use anyhow::{Context, Result};
use axum::extract::ws::{Message, WebSocket, WebSocketUpgrade};
use axum::extract::{Query, State};
use axum::http::{header, HeaderMap, StatusCode};
use axum::response::{Html, IntoResponse, Response};
use axum::routing::get;
use axum::Router;
use job::{Job, Source};
use link::{Hub, Request};
use serde::Deserialize;
use serde_json::{json, Value};
use std::collections::HashMap;
use std::net::SocketAddr;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{mpsc, Arc, Mutex};
use tokio::sync::broadcast::error::RecvError;

/// The page: HTML with its style sheet and script put inline, so that one
/// request (gated like the websocket) brings everything.
fn page() -> String {
    include_str!("assets/index.html")
        .replace("/*STYLE*/", include_str!("assets/style.css"))
        .replace("/*SCRIPT*/", include_str!("assets/app.js"))
}

struct App {
    access: Access,
    hub: Arc<Hub>,
    requests: Mutex<mpsc::Sender<Request>>,
    page: String,
    next_client: AtomicU64,
    /// The browser in control, if any.
    controller: Mutex<Option<u64>>,
}

impl App {
    fn request(&self, r: Request) {
        // The link thread ends only with the server.
        let _ = self
            .requests
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .send(r);
    }

    fn controller(&self) -> std::sync::MutexGuard<'_, Option<u64>> {
        self.controller.lock().unwrap_or_else(|e| e.into_inner())
    }
}

/// Starts the link to `port` and serves the page on `listen` until Ctrl-C.
pub fn run(port: String, listen: SocketAddr, private: bool) -> Result<()> {
    let rt = tokio::runtime::Runtime::new().context("starting the async runtime")?;
    rt.block_on(async move {
        let listener = tokio::net::TcpListener::bind(listen)
            .await
            .with_context(|| format!("listening on {listen}"))?;
        let addr = listener.local_addr()?;
        let access = Access::new(addr.ip(), private);
        announce(addr, &access, private);
        let hub = Hub::new();
        let (tx, rx) = mpsc::channel();
        let link_hub = hub.clone();
        std::thread::spawn(move || link::run(port, link_hub, rx));
        let app = Arc::new(App {
            access,
            hub,
            requests: Mutex::new(tx),
            page: page(),
            next_client: AtomicU64::new(1),
            controller: Mutex::new(None),
        });
        let router = Router::new()
            .route("/", get(index))
            .route("/ws", get(ws))
            .with_state(app);
        axum::serve(listener, router)
            .with_graceful_shutdown(async {
                let _ = tokio::signal::ctrl_c().await;
            })
            .await
            .context("serving")
    })
}

/// Prints where to point a browser; with a token, as URLs and a QR code.
fn announce(addr: SocketAddr, access: &Access, private: bool) {
    let Some(token) = access.token() else {
        println!("inkstep web view: http://{addr}/ (open to this computer only)");
        return;
    };
    let hosts: Vec<String> = if addr.ip().is_unspecified() {
        if_addrs::get_if_addrs()
            .unwrap_or_default()
            .into_iter()
            .filter(|i| !i.is_loopback() && i.ip().is_ipv4())
            .map(|i| format!("{}:{}", i.ip(), addr.port()))
            .collect()
    } else {
        vec![addr.to_string()]
    };
    let watch = if private {
        "without it, nothing is shown (--private)"
    } else {
        "without it, a browser may only watch"
    };
    println!("inkstep web view on {addr}: controlling needs the token ({watch})");
    println!("  token: {token}");
    for h in &hosts {
        println!("  http://{h}/?token={token}");
    }
    if let Some(h) = hosts.first() {
        let url = format!("http://{h}/?token={token}");
        if let Ok(code) = qrcode::QrCode::new(url.as_bytes()) {
            let art = code
                .render::<qrcode::render::unicode::Dense1x2>()
                .quiet_zone(true)
                .build();
            println!("{art}");
        }
    }
}

#[derive(Deserialize)]
struct TokenQuery {
    token: Option<String>,
}

fn token_of(q: &HashMap<String, String>) -> Option<&str> {
    q.get("token").map(String::as_str)
}

async fn index(State(app): State<Arc<App>>, Query(q): Query<HashMap<String, String>>) -> Response {
    match app.access.role(token_of(&q)) {
        Some(_) => (
            [(header::CACHE_CONTROL, "no-store")],
            Html(app.page.clone()),
        )
            .into_response(),
        None => (
            StatusCode::UNAUTHORIZED,
            "inkstep: this machine's page needs the link with its token\n",
        )
            .into_response(),
    }
}

async fn ws(
    upgrade: WebSocketUpgrade,
    State(app): State<Arc<App>>,
    Query(q): Query<TokenQuery>,
    headers: HeaderMap,
) -> Response {
    let text = |h| {
        headers
            .get(h)
            .and_then(|v: &header::HeaderValue| v.to_str().ok())
    };
    if !same_origin(text(header::ORIGIN), text(header::HOST)) {
        return (StatusCode::FORBIDDEN, "cross-origin websocket refused\n").into_response();
    }
    let Some(role) = app.access.role(q.token.as_deref()) else {
        return (StatusCode::UNAUTHORIZED, "token needed\n").into_response();
    };
    upgrade
        .max_message_size(64 << 20)
        .on_upgrade(move |s| client(s, app, role))
}

async fn send(s: &mut WebSocket, v: &Value) -> bool {
    s.send(Message::Text(v.to_string().into())).await.is_ok()
}

/// One browser: catch up, then forward the link's messages and carry out its own.
async fn client(mut s: WebSocket, app: Arc<App>, role: Role) {
    let id = app.next_client.fetch_add(1, Ordering::Relaxed);
    let mut rx = app.hub.out.subscribe();
    let holder = *app.controller();
    let hello = json!({
        "t": "hello",
        "id": id,
        "role": if role == Role::Control { "control" } else { "watch" },
        "holder": holder,
    });
    if !send(&mut s, &hello).await {
        return;
    }
    for m in app.hub.catch_up() {
        if !send(&mut s, &m).await {
            return;
        }
    }
    loop {
        tokio::select! {
            m = rx.recv() => match m {
                Ok(text) => {
                    if s.send(Message::Text(text.as_ref().into())).await.is_err() {
                        break;
                    }
                }
                // Too slow to follow: the page reconnects and catches up.
                Err(RecvError::Lagged(_)) | Err(RecvError::Closed) => break,
            },
            m = s.recv() => match m {
                Some(Ok(Message::Text(t))) => {
                    let reply = command(&app, id, role, &t).await;
                    if let Some(r) = reply {
                        if !send(&mut s, &r).await {
                            break;
                        }
                    }
                }
                Some(Ok(Message::Close(_))) | None | Some(Err(_)) => break,
                Some(Ok(_)) => {}
            },
        }
    }
    let mut c = app.controller();
    if *c == Some(id) {
        *c = None;
        drop(c);
        app.hub.publish(&json!({"t": "control", "holder": null}));
    }
}

/// Real-time bytes a browser may send: hold, resume, reset, jog cancel, overrides.
fn realtime_allowed(b: u8) -> bool {
    matches!(b, b'!' | b'~' | 0x18 | 0x85 | 0x90..=0x9D)
}

/// Carries out one message of a browser; the answer for that browser alone, if any.
async fn command(app: &Arc<App>, id: u64, role: Role, text: &str) -> Option<Value> {
    let deny = |why: &str| Some(json!({"t": "denied", "why": why}));
    let Ok(m) = serde_json::from_str::<Value>(text) else {
        return deny("not a message");
    };
    if role != Role::Control {
        return deny("this browser may only watch (open the link with the token to control)");
    }
    {
        let mut c = app.controller();
        let take = m["t"] == "take" || c.is_none();
        if take && *c != Some(id) {
            *c = Some(id);
            drop(c);
            app.hub.publish(&json!({"t": "control", "holder": id}));
        } else if *c != Some(id) {
            return deny("another browser has control (take it with \"Take control\")");
        }
    }
    match m["t"].as_str().unwrap_or("") {
        "take" => None,
        "rt" => match m["b"].as_u64().and_then(|b| u8::try_from(b).ok()) {
            Some(b) if realtime_allowed(b) => {
                app.request(Request::Realtime(b));
                None
            }
            _ => deny("not a real-time command"),
        },
        "cmd" => {
            let line = m["line"].as_str().unwrap_or("");
            if line.is_empty() || line.len() > 120 || line.contains(['\n', '\r']) {
                return deny("one line of at most 120 characters");
            }
            app.request(Request::Line {
                id: m["id"].as_u64().unwrap_or(0),
                text: line.to_string(),
            });
            None
        }
        "load" => {
            let (pen, rapid) = app.hub.pen_and_rapid();
            let kind = m["kind"].as_str().unwrap_or("").to_string();
            let name = m["name"].as_str().unwrap_or("job").to_string();
            let data = m["data"].as_str().unwrap_or("").to_string();
            let size = m["size"].as_f64().unwrap_or(20.0);
            let built = tokio::task::spawn_blocking(move || {
                let src = match kind.as_str() {
                    "svg" => Source::Svg(&data),
                    "text" => Source::Text(&data, size),
                    _ => Source::Gcode(&data),
                };
                Job::new(&name, src, pen, rapid)
            })
            .await;
            match built {
                Ok(Ok(job)) => {
                    app.request(Request::Load(Box::new(job)));
                    None
                }
                Ok(Err(e)) => Some(json!({"t": "error", "text": format!("{e:#}")})),
                Err(e) => Some(json!({"t": "error", "text": e.to_string()})),
            }
        }
        "run" => {
            app.request(Request::Run);
            None
        }
        "stop" => {
            app.request(Request::Stop);
            None
        }
        _ => deny("unknown command"),
    }
}
