//! No browser can starve the machine or the server: with a 10 MB job loaded,
//! 50 websockets that never read (each from its own address, as the limit per
//! address is 8) leave the server's memory within a stated bound, and a
//! browser that reads keeps getting the status at the rate the link polls it.
//! The real binary linked to the simulator behind a pty, over real sockets.

mod web_common;

use futures_util::{SinkExt, StreamExt};
use serde_json::Value;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};
use tokio::io::AsyncWriteExt;
use tokio_tungstenite::tungstenite::Message;
use web_common::{sim_at, Server};

/// What 50 clients that never read may add to the server's resident memory.
const BOUND_MB: f64 = 64.0;

fn rss_kb(pid: u32, field: &str) -> u64 {
    let s = std::fs::read_to_string(format!("/proc/{pid}/status")).unwrap();
    s.lines()
        .find_map(|l| l.strip_prefix(field))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse().ok())
        .unwrap()
}

/// About `bytes` of G-code: a long pen-down random walk in short moves.
fn big_job(bytes: usize) -> String {
    let mut g = String::from("G21 G90\nM3\nG1 F3000\n");
    let (mut x, mut y, mut seed) = (0.0f64, 0.0f64, 12345u64);
    while g.len() < bytes {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        x = (x + ((seed >> 33) % 200) as f64 / 100.0 - 1.0).clamp(-40.0, 40.0);
        y = (y + ((seed >> 13) % 200) as f64 / 100.0 - 1.0).clamp(-40.0, 40.0);
        g.push_str(&format!("G1 X{x:.3} Y{y:.3}\n"));
    }
    g.push_str("M5\nG0 X0 Y0\n");
    g
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn fifty_clients_that_never_read_leave_memory_bounded_and_status_flowing() {
    let dir = std::env::temp_dir().join(format!("inkstep-web-load-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let link = dir.join("tty");
    let stop = Arc::new(AtomicBool::new(false));
    let sim = sim_at(&link, &stop);
    let server = Server::start(&link);
    let (port, pid) = (server.port, server.pid());
    let (mut ws, _) = tokio_tungstenite::connect_async(format!("ws://127.0.0.1:{port}/ws"))
        .await
        .unwrap();
    let job = big_job(10_000_000);
    let (moves, load_s) = load(&mut ws, &job, "big.nc").await;
    assert!(moves > 300_000, "{moves} moves");
    // A big job's estimate follows its load (the firmware's planner over all its
    // moves, seconds of work and memory of its own): measured once it is done, the
    // memory the clients below add is theirs alone.
    let estimated = async {
        while let Some(Ok(m)) = ws.next().await {
            if let Message::Text(t) = m {
                if serde_json::from_str::<Value>(&t).unwrap()["t"] == "estimate" {
                    return;
                }
            }
        }
    };
    tokio::time::timeout(Duration::from_secs(120), estimated)
        .await
        .expect("the big job's estimate arrives");
    let before = rss_kb(pid, "VmRSS:");

    // 50 clients from 50 addresses that open the websocket and never read.
    let mut quiet = Vec::new();
    for i in 0..50u32 {
        let sock = tokio::net::TcpSocket::new_v4().unwrap();
        sock.set_recv_buffer_size(4096).unwrap();
        sock.bind(format!("127.0.0.{}:0", i + 2).parse().unwrap())
            .unwrap();
        let mut s = sock
            .connect(format!("127.0.0.1:{port}").parse().unwrap())
            .await
            .unwrap();
        s.write_all(
            format!(
                "GET /ws HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nUpgrade: websocket\r\n\
                 Connection: Upgrade\r\nSec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n\
                 Sec-WebSocket-Version: 13\r\n\r\n"
            )
            .as_bytes(),
        )
        .await
        .unwrap();
        quiet.push(s);
    }

    // Meanwhile the reading browser counts its status reports.
    let (mut n, mut gap, mut last) = (0u32, 0f64, Instant::now());
    let window = Duration::from_secs(6);
    let start = Instant::now();
    let mut peak = before;
    while start.elapsed() < window {
        if let Ok(Some(Ok(Message::Text(t)))) =
            tokio::time::timeout(Duration::from_millis(500), ws.next()).await
        {
            let v: Value = serde_json::from_str(&t).unwrap();
            if v["t"] == "status" {
                n += 1;
                gap = gap.max(last.elapsed().as_secs_f64());
                last = Instant::now();
            }
        }
        peak = peak.max(rss_kb(pid, "VmRSS:"));
    }
    let rate = n as f64 / window.as_secs_f64();
    let added = (peak.saturating_sub(before)) as f64 / 1024.0;
    println!(
        "10 MB job ({moves} moves) loaded in {load_s:.1} s; server RSS {:.0} MB with one browser, \
         at most {:.0} MB with 50 that never read (+{added:.1} MB, bound {BOUND_MB} MB); \
         the reading browser got {rate:.1} status reports/s (the link polls 20/s), longest gap {:.0} ms",
        before as f64 / 1024.0,
        peak as f64 / 1024.0,
        gap * 1000.0
    );
    assert!(added < BOUND_MB, "50 quiet clients added {added:.1} MB");
    assert!(rate > 12.0, "{rate:.1} reports/s");
    assert!(gap < 2.0, "a gap of {gap:.2} s");
    // A browser that takes nothing for 15 s is dropped: each quiet socket,
    // read now, ends (after what the server had written before giving up).
    let since = start.elapsed();
    tokio::time::sleep(Duration::from_secs(17).saturating_sub(since)).await;
    let mut closed = 0;
    for mut q in quiet {
        let mut buf = vec![0u8; 1 << 16];
        let drain = async {
            loop {
                match tokio::io::AsyncReadExt::read(&mut q, &mut buf).await {
                    Ok(0) | Err(_) => return true,
                    Ok(_) => {}
                }
            }
        };
        if tokio::time::timeout(Duration::from_secs(5), drain)
            .await
            .unwrap_or(false)
        {
            closed += 1;
        }
    }
    println!("after 17 s, {closed} of the 50 quiet websockets had been closed by the server");
    assert_eq!(closed, 50);
    drop(server);
    stop.store(true, Ordering::Relaxed);
    let _ = sim.join();
    let _ = std::fs::remove_dir_all(&dir);
}

type Ws =
    tokio_tungstenite::WebSocketStream<tokio_tungstenite::MaybeTlsStream<tokio::net::TcpStream>>;

/// Loads `job` in parts as the page does; its moves and the seconds until its
/// whole preview came back.
async fn load(ws: &mut Ws, job: &str, name: &str) -> (u64, f64) {
    let parts: Vec<&str> = job
        .as_bytes()
        .chunks(128 * 1024)
        .map(|c| std::str::from_utf8(c).unwrap())
        .collect();
    let t0 = Instant::now();
    let head = serde_json::json!({"t": "load", "kind": "gcode", "name": name, "parts": parts.len(), "bytes": job.len()});
    ws.send(Message::Text(head.to_string().into()))
        .await
        .unwrap();
    for p in &parts {
        let m = serde_json::json!({"t": "part", "data": p});
        ws.send(Message::Text(m.to_string().into())).await.unwrap();
    }
    let (mut moves, mut rows) = (0, 0);
    let loaded = async {
        while let Some(Ok(m)) = ws.next().await {
            let t = match m {
                Message::Text(t) => t,
                // A piece of the preview: the generation, then rows of 5 f32.
                Message::Binary(b) => {
                    assert_eq!((b.len() - 4) % 20, 0, "whole rows");
                    rows += ((b.len() - 4) / 20) as u64;
                    continue;
                }
                _ => continue,
            };
            let v: Value = serde_json::from_str(&t).unwrap();
            match v["t"].as_str() {
                Some("job") if v["name"] == name => moves = v["moves"].as_u64().unwrap(),
                Some("preview_end") if moves > 0 => return,
                Some("error") => panic!("{v}"),
                _ => {}
            }
        }
    };
    tokio::time::timeout(Duration::from_secs(180), loaded)
        .await
        .expect("the job loads");
    assert_eq!(rows, moves);
    (moves, t0.elapsed().as_secs_f64())
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_50_mb_job_loads() {
    let server = Server::start(std::path::Path::new("/nonexistent/inkstep-tty"));
    let (port, pid) = (server.port, server.pid());
    let (mut ws, _) = tokio_tungstenite::connect_async(format!("ws://127.0.0.1:{port}/ws"))
        .await
        .unwrap();
    let job = big_job(50_000_000);
    let (moves, secs) = load(&mut ws, &job, "50mb.nc").await;
    println!(
        "a 50 MB job ({moves} moves) loaded in {secs:.1} s; server peak RSS {:.0} MB",
        rss_kb(pid, "VmHWM:") as f64 / 1024.0
    );
    assert!(moves > 2_000_000);
}
