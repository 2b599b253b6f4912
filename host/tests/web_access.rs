//! Who gets in to `inkstep-host serve`: on loopback the page is open and a
//! browser may control; on another address a browser without the token only
//! watches (its commands are refused) and one with it controls; with
//! `--private` nothing is served without the token; a websocket from a page of
//! another origin is refused. The real binary, over real sockets on loopback
//! (listening on 0.0.0.0 with an ephemeral port stands for "another address").

use futures_util::{SinkExt, StreamExt};
use serde_json::Value;
use std::io::{BufRead, BufReader, Read, Write};
use std::process::{Child, Command, Stdio};
use std::sync::{Arc, Mutex};
use std::time::Duration;
use tokio_tungstenite::tungstenite::client::IntoClientRequest;
use tokio_tungstenite::tungstenite::Message;

struct Server {
    child: Child,
    port: u16,
    token: Option<String>,
    later: Arc<Mutex<String>>,
}

impl Drop for Server {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Starts the server (its machine port does not exist: the link just retries).
fn serve(listen: &str, private: bool) -> Server {
    serve_with(listen, private, "/nonexistent/inkstep-tty", &[])
}

/// Starts the server on machine port `port`, with more arguments `extra`;
/// everything it prints after its start goes to `Server::later`.
fn serve_with(listen: &str, private: bool, machine: &str, extra: &[&str]) -> Server {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_inkstep-host"));
    cmd.args(["serve", "--port", machine, "--listen", listen]);
    cmd.args(extra);
    if private {
        cmd.arg("--private");
    }
    let mut child = cmd
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut out = BufReader::new(child.stdout.take().unwrap());
    let (mut port, mut token) = (None, None);
    let mut line = String::new();
    while port.is_none() || (token.is_none() && !listen.starts_with("127.")) {
        line.clear();
        assert!(out.read_line(&mut line).unwrap() > 0, "serve ended early");
        if let Some(rest) = line.split("on 0.0.0.0:").nth(1) {
            port = rest
                .split(|c: char| !c.is_ascii_digit())
                .next()
                .unwrap()
                .parse()
                .ok();
        }
        if let Some(rest) = line.split("http://127.0.0.1:").nth(1) {
            port = rest.split('/').next().unwrap().parse().ok();
        }
        if let Some(t) = line.trim().strip_prefix("token: ") {
            token = Some(t.to_string());
        }
    }
    // The rest of the announcement (URLs, QR code) is printed at once; what
    // comes later is collected (and keeps the pipes from filling).
    let later = Arc::new(Mutex::new(String::new()));
    let mut err = child.stderr.take().unwrap();
    let l = later.clone();
    std::thread::spawn(move || {
        let mut s = String::new();
        let _ = err.read_to_string(&mut s);
        l.lock().unwrap().push_str(&s);
    });
    let l = later.clone();
    std::thread::spawn(move || {
        let mut skipping = true;
        let mut line = String::new();
        while out.read_line(&mut line).unwrap_or(0) > 0 {
            // The announcement ends with the QR code's last row.
            if !(skipping
                && (line.starts_with("  http://")
                    || line.contains('\u{2580}')
                    || line.contains('\u{2588}')
                    || line.contains('\u{2584}')
                    || line.trim().is_empty()))
            {
                skipping = false;
                l.lock().unwrap().push_str(&line);
            }
            line.clear();
        }
    });
    Server {
        child,
        port: port.unwrap(),
        token,
        later,
    }
}

/// The status code of GET `path`.
fn get(port: u16, path: &str) -> u16 {
    request(port, path, &format!("127.0.0.1:{port}"), "").0
}

/// GET `path` with this `Host` and more header lines: status and head.
fn request(port: u16, path: &str, host: &str, more: &str) -> (u16, String) {
    let mut s = std::net::TcpStream::connect(("127.0.0.1", port)).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
    write!(
        s,
        "GET {path} HTTP/1.1\r\nHost: {host}\r\n{more}Connection: close\r\n\r\n"
    )
    .unwrap();
    let mut all = Vec::new();
    let _ = s.read_to_end(&mut all);
    let text = String::from_utf8_lossy(&all).to_string();
    let head = text
        .split("\r\n\r\n")
        .next()
        .unwrap_or("")
        .to_ascii_lowercase();
    (text[9..12].parse().unwrap(), head)
}

type Ws =
    tokio_tungstenite::WebSocketStream<tokio_tungstenite::MaybeTlsStream<tokio::net::TcpStream>>;

async fn connect(port: u16, token: Option<&str>, origin: Option<&str>) -> Result<Ws, u16> {
    connect_as(port, token, origin, None).await
}

/// Opens the websocket, with another `Host` header when given.
async fn connect_as(
    port: u16,
    token: Option<&str>,
    origin: Option<&str>,
    host: Option<&str>,
) -> Result<Ws, u16> {
    let q = token.map_or(String::new(), |t| format!("?token={t}"));
    let mut req = format!("ws://127.0.0.1:{port}/ws{q}")
        .into_client_request()
        .unwrap();
    if let Some(o) = origin {
        req.headers_mut().insert("Origin", o.parse().unwrap());
    }
    if let Some(h) = host {
        req.headers_mut().insert("Host", h.parse().unwrap());
    }
    match tokio_tungstenite::connect_async(req).await {
        Ok((ws, _)) => Ok(ws),
        Err(tokio_tungstenite::tungstenite::Error::Http(r)) => Err(r.status().as_u16()),
        Err(e) => panic!("{e}"),
    }
}

/// The next message of type `t`.
async fn next(ws: &mut Ws, t: &str) -> Value {
    let wait = async {
        while let Some(m) = ws.next().await {
            if let Ok(Message::Text(s)) = m {
                let v: Value = serde_json::from_str(&s).unwrap();
                if v["t"] == t {
                    return v;
                }
            }
        }
        panic!("closed before a {t:?} message");
    };
    tokio::time::timeout(Duration::from_secs(10), wait)
        .await
        .unwrap_or_else(|_| panic!("no {t:?} message"))
}

async fn say(ws: &mut Ws, msg: &str) {
    ws.send(Message::Text(msg.into())).await.unwrap();
}

#[tokio::test]
async fn loopback_is_open_and_one_browser_controls_at_a_time() {
    let s = serve("127.0.0.1:0", false);
    assert_eq!(s.token, None);
    assert_eq!(get(s.port, "/"), 200);
    let mut a = connect(s.port, None, Some(&format!("http://127.0.0.1:{}", s.port)))
        .await
        .unwrap();
    let hello = next(&mut a, "hello").await;
    assert_eq!(hello["role"], "control");
    say(&mut a, r#"{"t":"take"}"#).await;
    assert_eq!(next(&mut a, "control").await["holder"], hello["id"]);
    // A second browser may control too, but not while the first holds it.
    let mut b = connect(s.port, None, None).await.unwrap();
    let hb = next(&mut b, "hello").await;
    assert_eq!(hb["holder"], hello["id"]);
    say(&mut b, r#"{"t":"rt","b":33}"#).await;
    assert!(next(&mut b, "denied").await["why"]
        .as_str()
        .unwrap()
        .contains("another browser"));
    say(&mut b, r#"{"t":"take"}"#).await;
    assert_eq!(next(&mut a, "control").await["holder"], hb["id"]);
    // A page of another origin may not open the websocket at all.
    assert_eq!(
        connect(s.port, None, Some("http://evil.example"))
            .await
            .err(),
        Some(403)
    );
}

#[tokio::test]
async fn elsewhere_the_token_controls_and_without_it_a_browser_watches() {
    let s = serve("0.0.0.0:0", false);
    let token = s.token.clone().expect("a token is printed");
    assert_eq!(get(s.port, "/"), 200);
    let mut watcher = connect(s.port, None, None).await.unwrap();
    assert_eq!(next(&mut watcher, "hello").await["role"], "watch");
    say(&mut watcher, r#"{"t":"take"}"#).await;
    assert!(next(&mut watcher, "denied").await["why"]
        .as_str()
        .unwrap()
        .contains("only watch"));
    let mut wrong = connect(s.port, Some("00112233445566778899aabbccddeeff"), None)
        .await
        .unwrap();
    assert_eq!(next(&mut wrong, "hello").await["role"], "watch");
    let mut ctl = connect(s.port, Some(&token), None).await.unwrap();
    let hello = next(&mut ctl, "hello").await;
    assert_eq!(hello["role"], "control");
    say(&mut ctl, r#"{"t":"take"}"#).await;
    // Every browser, the watcher too, sees who controls.
    assert_eq!(next(&mut watcher, "control").await["holder"], hello["id"]);
}

#[tokio::test]
async fn private_shows_nothing_without_the_token() {
    let s = serve("0.0.0.0:0", true);
    let token = s.token.clone().expect("a token is printed");
    assert_eq!(get(s.port, "/"), 401);
    assert_eq!(get(s.port, "/?token=wrong"), 401);
    assert_eq!(get(s.port, &format!("/?token={token}")), 200);
    assert_eq!(connect(s.port, None, None).await.err(), Some(401));
    let mut ctl = connect(s.port, Some(&token), None).await.unwrap();
    assert_eq!(next(&mut ctl, "hello").await["role"], "control");
}

#[tokio::test]
async fn a_rebinding_page_gets_nothing() {
    // evil.example resolved to 127.0.0.1: the browser sends its name as Host
    // (and as Origin: to the browser this is evil.example's own page).
    let s = serve("127.0.0.1:0", false);
    let p = s.port;
    assert_eq!(request(p, "/", &format!("evil.example:{p}"), "").0, 421);
    assert_eq!(
        request(p, "/app.js", &format!("evil.example:{p}"), "").0,
        421
    );
    let evil = format!("http://evil.example:{p}");
    assert_eq!(
        connect_as(p, None, Some(&evil), Some(&format!("evil.example:{p}")))
            .await
            .err(),
        Some(421)
    );
    // The names this server does answer to.
    assert_eq!(request(p, "/", &format!("localhost:{p}"), "").0, 200);
    assert_eq!(request(p, "/", &format!("127.0.0.1:{p}"), "").0, 200);
    let local = format!("http://localhost:{p}");
    assert!(
        connect_as(p, None, Some(&local), Some(&format!("localhost:{p}")))
            .await
            .is_ok()
    );
    // A page on another port of this computer is another origin.
    assert_eq!(
        connect(p, None, Some("http://127.0.0.1:1")).await.err(),
        Some(403)
    );
    // --allow-host adds a name, and only that one.
    let named = serve_with(
        "127.0.0.1:0",
        false,
        "/nonexistent/inkstep-tty",
        &["--allow-host", "plotter.lan"],
    );
    let q = named.port;
    assert_eq!(request(q, "/", &format!("plotter.lan:{q}"), "").0, 200);
    assert_eq!(request(q, "/", &format!("evil.example:{q}"), "").0, 421);
}

#[tokio::test]
async fn the_page_cannot_be_framed_and_sends_no_referrer() {
    let s = serve("127.0.0.1:0", false);
    for path in ["/", "/app.js", "/style.css"] {
        let (code, head) = request(s.port, path, &format!("127.0.0.1:{}", s.port), "");
        assert_eq!(code, 200, "{path}");
        assert!(head.contains("\r\nx-frame-options: deny"), "{path}: {head}");
        let csp = head
            .lines()
            .find_map(|l| l.strip_prefix("content-security-policy: "))
            .unwrap_or_else(|| panic!("{path}: no CSP in {head}"));
        for part in [
            "frame-ancestors 'none'",
            "default-src 'none'",
            "script-src 'self'",
            "connect-src 'self'",
        ] {
            assert!(csp.contains(part), "{path}: {csp}");
        }
        assert!(!csp.contains("unsafe"), "{csp}");
        assert!(head.contains("\r\nreferrer-policy: no-referrer"), "{path}");
    }
    // The page has no inline script or style (the CSP would block them).
    let mut t = std::net::TcpStream::connect(("127.0.0.1", s.port)).unwrap();
    write!(
        t,
        "GET / HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n"
    )
    .unwrap();
    let mut page = String::new();
    t.read_to_string(&mut page).unwrap();
    assert!(page.contains("<script src=\"/app.js\"></script>"));
    assert!(!page.contains("<script>") && !page.contains("<style>") && !page.contains(" style=\""));
}

#[tokio::test]
async fn the_token_stays_out_of_the_logs() {
    let s = serve("0.0.0.0:0", true);
    let token = s.token.clone().unwrap();
    assert_eq!(get(s.port, &format!("/?token={token}")), 200);
    assert_eq!(get(s.port, &format!("/?token={token}x")), 401);
    assert_eq!(
        request(s.port, &format!("/?token={token}"), "evil.example", "").0,
        421
    );
    let mut ctl = connect(s.port, Some(&token), None).await.unwrap();
    assert_eq!(next(&mut ctl, "hello").await["role"], "control");
    say(&mut ctl, r#"{"t":"cmd","id":1,"line":"$$"}"#).await;
    // The link logs its failure to open the port: the browser sees the log.
    let mut logged = String::new();
    let wait = async {
        while let Some(Ok(Message::Text(m))) = ctl.next().await {
            logged.push_str(&m);
            if m.contains("\"answer\"") {
                break;
            }
        }
    };
    let _ = tokio::time::timeout(Duration::from_secs(5), wait).await;
    drop(ctl);
    tokio::time::sleep(Duration::from_millis(300)).await;
    let later = s.later.lock().unwrap().clone();
    assert!(
        !later.contains(&token),
        "the token was printed again: {later}"
    );
    assert!(
        !logged.contains(&token),
        "the token reached a browser: {logged}"
    );
}

#[tokio::test]
async fn connections_and_messages_are_bounded_with_an_error() {
    let s = serve("127.0.0.1:0", false);
    let mut open = Vec::new();
    for _ in 0..8 {
        open.push(connect(s.port, None, None).await.unwrap());
    }
    assert_eq!(connect(s.port, None, None).await.err(), Some(429));
    open.pop();
    tokio::time::sleep(Duration::from_millis(200)).await;
    let mut ws = connect(s.port, None, None).await.unwrap();
    next(&mut ws, "hello").await;
    let big = format!(r#"{{"t":"cmd","id":1,"line":"{}"}}"#, "x".repeat(1_500_000));
    say(&mut ws, &big).await;
    assert!(next(&mut ws, "denied").await["why"]
        .as_str()
        .unwrap()
        .contains("at most 1048576"));
    // A job over the limit is refused before it is sent, with the limit.
    say(
        &mut ws,
        r#"{"t":"load","kind":"gcode","name":"huge.nc","parts":200,"bytes":100000000}"#,
    )
    .await;
    let e = next(&mut ws, "error").await["text"]
        .as_str()
        .unwrap()
        .to_string();
    assert!(e.contains("huge.nc") && e.contains("64 MB"), "{e}");
    // The connection is still usable.
    say(&mut ws, r#"{"t":"cmd","id":2,"line":"G0 X1!"}"#).await;
    assert_eq!(next(&mut ws, "answer").await["ok"], false);
}
