//! A lost serial port in the web view: browsers are told the link is down, a
//! browser joining then is sent no stale state or position, and when the
//! machine comes back at the same path the link reopens it and status flows.
//! The real binary and the simulator behind a pty (in this process, started
//! after the server so that the server does not inherit the pty's master).
//! Its own test file: a server spawned by a test running alongside would
//! inherit the pty too, and the port would never close.

use futures_util::StreamExt;
use serde_json::Value;
use std::io::{BufRead, BufReader};
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;
use tokio_tungstenite::tungstenite::Message;

struct Kill(std::process::Child);

impl Drop for Kill {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// Starts the simulator behind a pty linked at `link`; stops when `stop` is set.
fn sim_at(link: &std::path::Path, stop: &Arc<AtomicBool>) -> std::thread::JoinHandle<()> {
    let (l, s) = (link.to_path_buf(), stop.clone());
    let h = std::thread::spawn(move || {
        let _ = inkstep_sim::serve::serve(Some(&l), 1.0, || s.load(Ordering::Relaxed));
    });
    for _ in 0..100 {
        if link.exists() {
            break;
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    h
}

type Ws =
    tokio_tungstenite::WebSocketStream<tokio_tungstenite::MaybeTlsStream<tokio::net::TcpStream>>;

/// The next message for which `want` holds, within `secs`.
async fn until(ws: &mut Ws, secs: u64, mut want: impl FnMut(&Value) -> bool) -> Option<Value> {
    let wait = async {
        while let Some(Ok(m)) = ws.next().await {
            if let Message::Text(t) = m {
                let v: Value = serde_json::from_str(&t).unwrap();
                if want(&v) {
                    return Some(v);
                }
            }
        }
        None
    };
    tokio::time::timeout(Duration::from_secs(secs), wait)
        .await
        .ok()
        .flatten()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_lost_port_shows_no_stale_state_and_the_link_comes_back() {
    let dir = std::env::temp_dir().join(format!("inkstep-web-lost-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let link = dir.join("tty");
    let mut child = Kill(
        Command::new(env!("CARGO_BIN_EXE_inkstep-host"))
            .args([
                "serve",
                "--port",
                link.to_str().unwrap(),
                "--listen",
                "127.0.0.1:0",
            ])
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .unwrap(),
    );
    let mut out = BufReader::new(child.0.stdout.take().unwrap());
    let mut line = String::new();
    out.read_line(&mut line).unwrap();
    let port: u16 = line
        .split("http://127.0.0.1:")
        .nth(1)
        .and_then(|r| r.split('/').next())
        .and_then(|p| p.parse().ok())
        .unwrap();
    std::thread::spawn(move || std::io::copy(&mut out, &mut std::io::sink()));
    let stop = Arc::new(AtomicBool::new(false));
    let sim = sim_at(&link, &stop);
    let url = format!("ws://127.0.0.1:{port}/ws");
    let (mut ws, _) = tokio_tungstenite::connect_async(&url).await.unwrap();
    assert!(until(&mut ws, 15, |v| v["t"] == "status").await.is_some());
    // The machine goes away (the cable is pulled).
    stop.store(true, Ordering::Relaxed);
    let _ = sim.join();
    let down = until(&mut ws, 10, |v| v["t"] == "link" && v["up"] == false).await;
    assert!(down.is_some(), "the browser is told the link is down");
    // A browser joining now is told so, and is sent no (stale) status.
    let (mut late, _) = tokio_tungstenite::connect_async(&url).await.unwrap();
    let mut seen = Vec::new();
    let first = until(&mut late, 2, |v| {
        seen.push(v["t"].as_str().unwrap_or("").to_string());
        v["t"] == "status"
    })
    .await;
    assert!(
        first.is_none(),
        "a status while the port is away: {first:?}"
    );
    assert!(seen.iter().any(|t| t == "link"), "{seen:?}");
    // The machine comes back at the same path: the link reopens it.
    let stop2 = Arc::new(AtomicBool::new(false));
    let sim2 = sim_at(&link, &stop2);
    assert!(until(&mut ws, 10, |v| v["t"] == "link" && v["up"] == true)
        .await
        .is_some());
    assert!(until(&mut ws, 10, |v| v["t"] == "status").await.is_some());
    drop(child);
    stop2.store(true, Ordering::Relaxed);
    let _ = sim2.join();
    let _ = std::fs::remove_dir_all(&dir);
}
