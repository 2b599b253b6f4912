//! A lost serial port in the web view: browsers are told the link is down, a
//! browser joining then is sent no stale state or position, and when the
//! machine comes back at the same path the link reopens it and status flows.
//! The real binary and the simulator behind a pty (in this process, started
//! after the server so that the server does not inherit the pty's master).
//! Its own test file: a server spawned by a test running alongside would
//! inherit the pty too, and the port would never close.

mod web_common;

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use web_common::{sim_at, until, Server};

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_lost_port_shows_no_stale_state_and_the_link_comes_back() {
    let dir = std::env::temp_dir().join(format!("inkstep-web-lost-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let link = dir.join("tty");
    let server = Server::start(&link);
    let stop = Arc::new(AtomicBool::new(false));
    let sim = sim_at(&link, &stop);
    let url = server.ws_url();
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
    drop(server);
    stop2.store(true, Ordering::Relaxed);
    let _ = sim2.join();
    let _ = std::fs::remove_dir_all(&dir);
}
