//! `cargo host serve`: the machine in a web page, for a browser on this PC or a
//! phone on the same network.
//!
//! The page (assets/, built into the binary, no CDN: it works offline) talks to
//! the server over one websocket. The server is axum on tokio; the machine link
//! runs on a thread of its own (link.rs) and its messages reach every browser.
//! Many browsers may watch; one controls at a time: a browser allowed to
//! control (access.rs) takes control with its first command or the "take
//! control" button, and every other browser then watches.
//!
//! No browser can make the server hold much for it: each one's task sends one
//! message at a time and waits for it to go out (at most [`SEND_TIMEOUT`],
//! then the browser is dropped); the status and the job are "latest value"
//! channels, so a browser that falls behind skips stale reports instead of
//! queueing them; big things (the job's preview, the path so far) go out in
//! pieces of at most [`link::CHUNK`] points, and the small events share one
//! bounded ring ([`link::EVENTS`]) that a browser too far behind is dropped
//! from (the page reconnects and catches up). Connections per address and
//! message sizes are bounded too, each with an error saying so.

pub mod access;
pub mod job;
pub mod link;

use access::{Access, Role};
use anyhow::{Context, Result};
use axum::extract::ws::{Message, WebSocket, WebSocketUpgrade};
use axum::extract::{ConnectInfo, Query, Request as HttpRequest, State};
use axum::http::{header, HeaderMap, HeaderValue, StatusCode};
use axum::middleware::{self, Next};
use axum::response::{Html, IntoResponse, Response};
use axum::routing::get;
use axum::Router;
use job::{Job, Source};
use link::{Hub, JobView, Request};
use serde::Deserialize;
use serde_json::{json, Value};
use std::collections::HashMap;
use std::net::{IpAddr, SocketAddr};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{mpsc, Arc, Mutex};
use std::time::Duration;
use tokio::sync::broadcast::error::RecvError;

/// Websockets open at once from one address.
pub const PER_ADDRESS: usize = 8;
/// Websockets open at once in all.
pub const CLIENTS: usize = 64;
/// Largest message a browser may send (a job goes in parts of at most 512 KiB).
pub const MESSAGE: usize = 1 << 20;
/// Largest job, uploaded in parts.
pub const JOB_BYTES: usize = 64 << 20;
/// A message to a browser not taken in this time: the browser is dropped.
pub const SEND_TIMEOUT: Duration = Duration::from_secs(15);

/// The headers of every answer: no framing, no referrer (the token is in the
/// page's address), nothing from anywhere but this server.
const CSP: &str = "default-src 'none'; script-src 'self'; style-src 'self'; \
    connect-src 'self'; img-src 'self' data:; base-uri 'none'; form-action 'none'; \
    frame-ancestors 'none'";

struct App {
    access: Access,
    hub: Arc<Hub>,
    requests: Mutex<mpsc::Sender<Request>>,
    next_client: AtomicU64,
    /// The browser in control, if any.
    controller: Mutex<Option<u64>>,
    /// Open websockets per address.
    open: Mutex<HashMap<IpAddr, usize>>,
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

    fn open(&self) -> std::sync::MutexGuard<'_, HashMap<IpAddr, usize>> {
        self.open.lock().unwrap_or_else(|e| e.into_inner())
    }
}

/// One open websocket counted against its address while it lives.
struct Slot {
    app: Arc<App>,
    ip: IpAddr,
}

impl Slot {
    fn take(app: &Arc<App>, ip: IpAddr) -> Result<Slot, &'static str> {
        let mut open = app.open();
        if open.values().sum::<usize>() >= CLIENTS {
            return Err("too many browsers connected");
        }
        let n = open.entry(ip).or_insert(0);
        if *n >= PER_ADDRESS {
            return Err("too many connections from this address");
        }
        *n += 1;
        Ok(Slot {
            app: app.clone(),
            ip,
        })
    }
}

impl Drop for Slot {
    fn drop(&mut self) {
        let mut open = self.app.open();
        if let Some(n) = open.get_mut(&self.ip) {
            *n -= 1;
            if *n == 0 {
                open.remove(&self.ip);
            }
        }
    }
}

/// Starts the link to `port` and serves the page on `listen` until Ctrl-C;
/// `allow` are host names (besides the address) the page may be reached by.
pub fn run(port: String, listen: SocketAddr, private: bool, allow: Vec<String>) -> Result<()> {
    let rt = tokio::runtime::Runtime::new().context("starting the async runtime")?;
    rt.block_on(async move {
        let listener = tokio::net::TcpListener::bind(listen)
            .await
            .with_context(|| format!("listening on {listen}"))?;
        let addr = listener.local_addr()?;
        let access = Access::new(addr.ip(), private, &allow);
        announce(addr, &access, private);
        let hub = Hub::new();
        let (tx, rx) = mpsc::channel();
        let link_hub = hub.clone();
        std::thread::spawn(move || link::run(port, link_hub, rx));
        let app = Arc::new(App {
            access,
            hub,
            requests: Mutex::new(tx),
            next_client: AtomicU64::new(1),
            controller: Mutex::new(None),
            open: Mutex::new(HashMap::new()),
        });
        let router = Router::new()
            .route("/", get(index))
            .route("/app.js", get(script))
            .route("/style.css", get(style))
            .route("/ws", get(ws))
            .layer(middleware::from_fn_with_state(app.clone(), guard))
            .with_state(app);
        axum::serve(
            listener,
            router.into_make_service_with_connect_info::<SocketAddr>(),
        )
        .with_graceful_shutdown(async {
            let _ = tokio::signal::ctrl_c().await;
        })
        .await
        .context("serving")
    })
}

/// Prints where to point a browser; with a token, as URLs and a QR code.
/// This is the only place the token is ever printed.
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
    use std::io::Write;
    let _ = std::io::stdout().flush();
}

/// Every request: refused unless its Host names this server (DNS rebinding);
/// every answer: the headers that keep it out of frames and other sites.
async fn guard(State(app): State<Arc<App>>, req: HttpRequest, next: Next) -> Response {
    let host = req
        .headers()
        .get(header::HOST)
        .and_then(|v| v.to_str().ok());
    let mut r = if app.access.host_allowed(host) {
        next.run(req).await
    } else {
        (
            StatusCode::MISDIRECTED_REQUEST,
            "inkstep: this server does not answer to that host name (see --allow-host)\n",
        )
            .into_response()
    };
    let h = r.headers_mut();
    h.insert(header::X_FRAME_OPTIONS, HeaderValue::from_static("DENY"));
    h.insert(
        header::CONTENT_SECURITY_POLICY,
        HeaderValue::from_static(CSP),
    );
    h.insert(
        header::REFERRER_POLICY,
        HeaderValue::from_static("no-referrer"),
    );
    h.insert(
        header::X_CONTENT_TYPE_OPTIONS,
        HeaderValue::from_static("nosniff"),
    );
    h.insert(header::CACHE_CONTROL, HeaderValue::from_static("no-store"));
    r
}

#[derive(Deserialize)]
struct TokenQuery {
    token: Option<String>,
}

async fn index(State(app): State<Arc<App>>, Query(q): Query<TokenQuery>) -> Response {
    match app.access.role(q.token.as_deref()) {
        Some(_) => Html(include_str!("assets/index.html")).into_response(),
        None => (
            StatusCode::UNAUTHORIZED,
            "inkstep: this machine's page needs the link with its token\n",
        )
            .into_response(),
    }
}

async fn script() -> Response {
    (
        [(header::CONTENT_TYPE, "text/javascript; charset=utf-8")],
        include_str!("assets/app.js"),
    )
        .into_response()
}

async fn style() -> Response {
    (
        [(header::CONTENT_TYPE, "text/css; charset=utf-8")],
        include_str!("assets/style.css"),
    )
        .into_response()
}

async fn ws(
    upgrade: WebSocketUpgrade,
    State(app): State<Arc<App>>,
    ConnectInfo(peer): ConnectInfo<SocketAddr>,
    Query(q): Query<TokenQuery>,
    headers: HeaderMap,
) -> Response {
    let text = |h| {
        headers
            .get(h)
            .and_then(|v: &header::HeaderValue| v.to_str().ok())
    };
    if !app
        .access
        .origin_allowed(text(header::ORIGIN), text(header::HOST))
    {
        return (StatusCode::FORBIDDEN, "cross-origin websocket refused\n").into_response();
    }
    let Some(role) = app.access.role(q.token.as_deref()) else {
        return (StatusCode::UNAUTHORIZED, "token needed\n").into_response();
    };
    let slot = match Slot::take(&app, peer.ip()) {
        Ok(s) => s,
        Err(why) => {
            return (StatusCode::TOO_MANY_REQUESTS, format!("inkstep: {why}\n")).into_response()
        }
    };
    // The protocol's limit is above ours, so that a message over ours is
    // answered with an error rather than a dropped connection.
    upgrade
        .max_message_size(2 * MESSAGE)
        .max_frame_size(2 * MESSAGE)
        .write_buffer_size(0)
        .max_write_buffer_size(4 * link::CHUNK_BYTES)
        .on_upgrade(move |s| client(s, app, role, slot))
}

/// Sends one message; false when the browser is gone or did not take it in time.
async fn put(s: &mut WebSocket, text: &str) -> bool {
    matches!(
        tokio::time::timeout(SEND_TIMEOUT, s.send(Message::Text(text.into()))).await,
        Ok(Ok(()))
    )
}

async fn put_job(s: &mut WebSocket, job: &JobView) -> bool {
    if !put(s, &job.head).await {
        return false;
    }
    for c in &job.preview {
        let sent = tokio::time::timeout(SEND_TIMEOUT, s.send(Message::Binary(c.clone()))).await;
        if !matches!(sent, Ok(Ok(()))) {
            return false;
        }
    }
    put(s, r#"{"t":"preview_end"}"#).await
}

/// A job arriving in parts from one browser.
struct Upload {
    kind: String,
    name: String,
    size: f64,
    parts: usize,
    data: String,
}

/// One browser: catch up, then forward the link's messages and carry out its own.
async fn client(mut s: WebSocket, app: Arc<App>, role: Role, _slot: Slot) {
    let id = app.next_client.fetch_add(1, Ordering::Relaxed);
    let mut events = app.hub.out.subscribe();
    let mut status = app.hub.status.subscribe();
    let mut job = app.hub.job.subscribe();
    let holder = *app.controller();
    let hello = json!({
        "t": "hello",
        "id": id,
        "role": if role == Role::Control { "control" } else { "watch" },
        "holder": holder,
        "limits": {"message": MESSAGE, "job": JOB_BYTES},
    });
    if !put(&mut s, &hello.to_string()).await {
        return;
    }
    for m in app.hub.catch_up() {
        if !put(&mut s, &m).await {
            return;
        }
    }
    let current = job.borrow_and_update().clone();
    if let Some(j) = current {
        if !put_job(&mut s, &j).await {
            return;
        }
    }
    // The path so far, piece by piece (never all of it held for one browser).
    let mut from = 0;
    while let Some(piece) = app.hub.path_piece(from) {
        from += link::CHUNK;
        if !put(&mut s, &piece).await {
            return;
        }
    }
    status.mark_changed();
    let mut upload: Option<Upload> = None;
    loop {
        tokio::select! {
            m = events.recv() => match m {
                Ok(text) => {
                    if !put(&mut s, &text).await {
                        break;
                    }
                }
                // Too slow to follow: the page reconnects and catches up.
                Err(RecvError::Lagged(_)) | Err(RecvError::Closed) => break,
            },
            r = status.changed() => {
                if r.is_err() {
                    break;
                }
                let m = status.borrow_and_update().clone();
                if let Some(m) = m {
                    if !put(&mut s, &m).await {
                        break;
                    }
                }
            }
            r = job.changed() => {
                if r.is_err() {
                    break;
                }
                let j = job.borrow_and_update().clone();
                if let Some(j) = j {
                    if !put_job(&mut s, &j).await {
                        break;
                    }
                }
            }
            m = s.recv() => match m {
                Some(Ok(Message::Text(t))) => {
                    let reply = if t.len() > MESSAGE {
                        Some(json!({"t": "denied", "why": format!(
                            "message of {} bytes: at most {} (jobs go in parts)", t.len(), MESSAGE)}))
                    } else {
                        command(&app, id, role, &t, &mut upload).await
                    };
                    if let Some(r) = reply {
                        if !put(&mut s, &r.to_string()).await {
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

/// Whether `line` may go to the board as one command: one line of printable
/// ASCII, at most 120 characters. Grbl picks `?`, `!` and `~` out of the byte
/// stream wherever they appear (and every byte from 0x80 up, and the control
/// characters such as 0x18, reset), so a line carrying one would do more than
/// it says: refused, with the reason.
pub fn check_line(line: &str) -> Result<(), String> {
    if line.trim().is_empty() {
        return Err("an empty line".into());
    }
    if line.len() > 120 {
        return Err(format!("{} characters: at most 120", line.len()));
    }
    for (i, c) in line.chars().enumerate() {
        let why = match c {
            '?' | '!' | '~' => "a real-time command (Grbl acts on it wherever it appears)",
            ' '..='~' => continue,
            '\u{80}'.. => "not ASCII (bytes from 0x80 are real-time commands)",
            _ => "a control character",
        };
        return Err(format!(
            "character {} ({:?}, U+{:04X}) is {why}: nothing was sent",
            i + 1,
            c,
            c as u32
        ));
    }
    Ok(())
}

/// Carries out one message of a browser; the answer for that browser alone, if any.
async fn command(
    app: &Arc<App>,
    id: u64,
    role: Role,
    text: &str,
    upload: &mut Option<Upload>,
) -> Option<Value> {
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
            let cid = m["id"].as_u64().unwrap_or(0);
            if let Err(why) = check_line(line) {
                return Some(json!({"t": "answer", "id": cid, "ok": false, "error": why}));
            }
            app.request(Request::Line {
                id: cid,
                text: line.to_string(),
            });
            None
        }
        "load" => {
            let kind = m["kind"].as_str().unwrap_or("").to_string();
            let name = m["name"].as_str().unwrap_or("job").to_string();
            let size = m["size"].as_f64().unwrap_or(20.0);
            let parts = m["parts"].as_u64().unwrap_or(0) as usize;
            let bytes = m["bytes"].as_u64().unwrap_or(0) as usize;
            if bytes > JOB_BYTES {
                *upload = None;
                return Some(json!({"t": "error", "text": too_big(&name, bytes)}));
            }
            if parts == 0 {
                let data = m["data"].as_str().unwrap_or("").to_string();
                return build(app, kind, name, data, size).await;
            }
            *upload = Some(Upload {
                kind,
                name,
                size,
                parts,
                data: String::with_capacity(bytes.min(JOB_BYTES)),
            });
            None
        }
        "part" => {
            let Some(u) = upload.as_mut() else {
                return deny("a part without a load");
            };
            let piece = m["data"].as_str().unwrap_or("");
            if u.data.len() + piece.len() > JOB_BYTES {
                let name = u.name.clone();
                *upload = None;
                return Some(json!({"t": "error", "text": too_big(&name, JOB_BYTES + 1)}));
            }
            u.data.push_str(piece);
            u.parts -= 1;
            if u.parts > 0 {
                return None;
            }
            let u = upload.take()?;
            build(app, u.kind, u.name, u.data, u.size).await
        }
        "run" => {
            app.request(Request::Run);
            None
        }
        "stop" => {
            app.request(Request::Stop);
            None
        }
        "resume" => {
            let line = m["line"].as_u64().and_then(|n| usize::try_from(n).ok());
            app.request(Request::Resume(line));
            None
        }
        _ => deny("unknown command"),
    }
}

fn too_big(name: &str, bytes: usize) -> String {
    format!(
        "{name}: {:.1} MB is over the web view's limit of {} MB (cargo host send takes any size)",
        bytes as f64 / 1e6,
        JOB_BYTES >> 20
    )
}

/// Builds a job away from the async threads and hands it to the link.
async fn build(
    app: &Arc<App>,
    kind: String,
    name: String,
    data: String,
    size: f64,
) -> Option<Value> {
    let (pen, machine) = app.hub.pen_and_machine();
    let failed = name.clone();
    let built = tokio::task::spawn_blocking(move || {
        let src = match kind.as_str() {
            "svg" => Source::Svg(&data),
            "text" => Source::Text(&data, size),
            _ => Source::Gcode(&data),
        };
        Job::new(&name, src, pen, &machine)
    })
    .await;
    match built {
        Ok(Ok(job)) => {
            if !job.estimated {
                // The firmware's estimate of a big job takes seconds: the job
                // is shown now, its estimate follows.
                let (pen, machine) = app.hub.pen_and_machine();
                let (id, lines, moves) = (job.id, job.lines.clone(), job.moves.clone());
                let app2 = app.clone();
                tokio::task::spawn_blocking(move || {
                    let j = Job {
                        id,
                        name: String::new(),
                        lines,
                        moves,
                        ends_s: Vec::new(),
                        total: 0.0,
                        estimated: false,
                        preview_bin: Vec::new(),
                        left_out: Vec::new(),
                        page: None,
                    };
                    let (ends_s, total) = j.estimate(&machine, pen);
                    app2.request(Request::Estimate { id, ends_s, total });
                });
            }
            app.request(Request::Load(Box::new(job)));
            None
        }
        Ok(Err(e)) => Some(json!({"t": "error", "text": format!("{failed}: {e:#}")})),
        Err(e) => Some(json!({"t": "error", "text": e.to_string()})),
    }
}

#[cfg(test)]
mod tests {
    use super::check_line;

    #[test]
    fn only_printable_ascii_lines_go_to_the_board() {
        for ok in [
            "$X",
            "$J=G91 G21 X10 F2000",
            "$110=2500",
            "G0 X1 (a comment)",
        ] {
            assert_eq!(check_line(ok), Ok(()), "{ok}");
        }
        for bad in [
            "G4 P0\u{18}",
            "G4 P0 (\u{84})",
            "G0 X1?",
            "G0 X1 (hold!)",
            "G0~",
            "G0\tX1",
            "G0\nX1",
            "G0 X1 é",
            "",
            "   ",
        ] {
            assert!(check_line(bad).is_err(), "{bad:?}");
        }
        assert!(check_line(&"G0".repeat(61)).is_err());
        assert!(check_line("G4 P0\u{18}")
            .unwrap_err()
            .contains("control character"));
    }
}
