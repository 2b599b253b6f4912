//! What the web view's socket tests share: the real `inkstep-host serve` binary on a
//! free loopback port (killed however the test ends), the simulator behind a pty, and a
//! wait for the next message a browser would get that matches.
#![allow(dead_code)]

use futures_util::StreamExt;
use serde_json::Value;
use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;
use tokio_tungstenite::tungstenite::Message;

/// `inkstep-host serve --port PORT_PATH` on 127.0.0.1, ended when dropped.
pub struct Server {
    child: Child,
    /// The TCP port it listens on (from its first line of output).
    pub port: u16,
}

impl Server {
    pub fn start(port_path: &Path) -> Server {
        let mut child = Command::new(env!("CARGO_BIN_EXE_inkstep-host"))
            .args(["serve", "--port"])
            .arg(port_path)
            .args(["--listen", "127.0.0.1:0"])
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        let mut out = BufReader::new(child.stdout.take().unwrap());
        let mut line = String::new();
        out.read_line(&mut line).unwrap();
        let port = line
            .split("http://127.0.0.1:")
            .nth(1)
            .and_then(|r| r.split('/').next())
            .and_then(|p| p.parse().ok())
            .unwrap_or_else(|| panic!("no address in {line:?}"));
        // The rest of its output, read so that it never blocks on a full pipe.
        std::thread::spawn(move || std::io::copy(&mut out, &mut std::io::sink()));
        Server { child, port }
    }

    pub fn pid(&self) -> u32 {
        self.child.id()
    }

    pub fn ws_url(&self) -> String {
        format!("ws://127.0.0.1:{}/ws", self.port)
    }
}

impl Drop for Server {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// The simulator behind a pty linked at `link`, until `stop` is set; returns once the
/// link exists (or after 5 s).
pub fn sim_at(link: &Path, stop: &Arc<AtomicBool>) -> std::thread::JoinHandle<()> {
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

pub type Ws =
    tokio_tungstenite::WebSocketStream<tokio_tungstenite::MaybeTlsStream<tokio::net::TcpStream>>;

/// The next message for which `want` holds, within `secs`.
pub async fn until(ws: &mut Ws, secs: u64, mut want: impl FnMut(&Value) -> bool) -> Option<Value> {
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
