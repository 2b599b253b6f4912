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
use std::time::Duration;
use tokio_tungstenite::tungstenite::client::IntoClientRequest;
use tokio_tungstenite::tungstenite::Message;

struct Server {
    child: Child,
    port: u16,
    token: Option<String>,
}

impl Drop for Server {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Starts the server (its machine port does not exist: the link just retries).
fn serve(listen: &str, private: bool) -> Server {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_inkstep-host"));
    cmd.args([
        "serve",
        "--port",
        "/nonexistent/inkstep-tty",
        "--listen",
        listen,
    ]);
    if private {
        cmd.arg("--private");
    }
    let mut child = cmd.stdout(Stdio::piped()).spawn().unwrap();
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
    // Keep draining stdout so the server never blocks on a full pipe.
    std::thread::spawn(move || std::io::copy(&mut out, &mut std::io::sink()));
    Server {
        child,
        port: port.unwrap(),
        token,
    }
}

/// The status code of GET `path`.
fn get(port: u16, path: &str) -> u16 {
    let mut s = std::net::TcpStream::connect(("127.0.0.1", port)).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
    write!(
        s,
        "GET {path} HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nConnection: close\r\n\r\n"
    )
    .unwrap();
    let mut head = [0u8; 12];
    s.read_exact(&mut head).unwrap();
    String::from_utf8_lossy(&head[9..12]).parse().unwrap()
}

type Ws =
    tokio_tungstenite::WebSocketStream<tokio_tungstenite::MaybeTlsStream<tokio::net::TcpStream>>;

async fn connect(port: u16, token: Option<&str>, origin: Option<&str>) -> Result<Ws, u16> {
    let q = token.map_or(String::new(), |t| format!("?token={t}"));
    let mut req = format!("ws://127.0.0.1:{port}/ws{q}")
        .into_client_request()
        .unwrap();
    if let Some(o) = origin {
        req.headers_mut().insert("Origin", o.parse().unwrap());
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
