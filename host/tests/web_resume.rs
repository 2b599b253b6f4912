//! The web view's Continue (resume) action and its late estimate: a line of text is
//! run and stopped midway, the page is told where it can continue, Continue runs the
//! rest (the state rebuilt, the pen travelling to the line), the job ends done and the
//! resume point is cleared. A job too big to simulate while it loads is shown at
//! once and the firmware's estimate follows. The real binary and the simulator behind
//! a pty (started after the server, see web_lost.rs).

mod web_common;

use futures_util::SinkExt;
use serde_json::json;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use tokio_tungstenite::tungstenite::Message;
use web_common::{sim_at, until, Server, Ws};

async fn send(ws: &mut Ws, v: serde_json::Value) {
    ws.send(Message::Text(v.to_string().into())).await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_stopped_job_continues_where_it_stopped() {
    let dir = std::env::temp_dir().join(format!("inkstep-web-resume-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let link = dir.join("tty");
    let server = Server::start(&link);
    let stop = Arc::new(AtomicBool::new(false));
    let sim = sim_at(&link, &stop);
    let (mut ws, _) = tokio_tungstenite::connect_async(server.ws_url())
        .await
        .unwrap();
    assert!(until(&mut ws, 15, |v| v["t"] == "settings").await.is_some());
    send(
        &mut ws,
        json!({"t": "load", "kind": "text", "name": "hi", "data": "Hi 42", "size": 12.0}),
    )
    .await;
    // The job's head and "nothing to resume" come on separate channels, in
    // either order.
    let (mut job, mut fresh) = (None, false);
    until(&mut ws, 20, |v| {
        if v["t"] == "job" {
            job = Some(v.clone());
        }
        fresh |= v["t"] == "resumable" && v["line"].is_null();
        job.is_some() && fresh
    })
    .await;
    let job = job.expect("loaded");
    assert!(fresh, "a new job has nothing to resume");
    let gen = job["gen"].clone();
    assert!(job["est_s"].as_f64().unwrap() > 3.0, "{job}");
    send(&mut ws, json!({"t": "run"})).await;
    // A third of the way, stop.
    let mid = until(&mut ws, 60, |v| {
        v["t"] == "status" && v["job"]["done"].as_f64().is_some_and(|d| d > 0.35)
    })
    .await;
    assert!(mid.is_some(), "the job runs");
    send(&mut ws, json!({"t": "stop"})).await;
    let r = until(&mut ws, 10, |v| v["t"] == "resumable" && v["gen"] == gen)
        .await
        .expect("a resume point");
    let line = r["line"].as_u64().expect("a line");
    assert!(line > 3, "{r}");
    assert!(
        until(&mut ws, 10, |v| v["t"] == "status" && v["state"] == "Idle")
            .await
            .is_some()
    );
    send(&mut ws, json!({"t": "resume"})).await;
    let log = until(&mut ws, 10, |v| {
        v["t"] == "log"
            && v["text"]
                .as_str()
                .is_some_and(|t| t.starts_with("resuming"))
    })
    .await
    .expect("resuming");
    assert!(
        log["text"]
            .as_str()
            .unwrap()
            .contains(&format!("at line {line}")),
        "{log}"
    );
    let done = until(&mut ws, 90, |v| v["t"] == "done")
        .await
        .expect("done");
    assert_eq!(done["ok"], true, "{done}");
    assert!(
        until(&mut ws, 5, |v| v["t"] == "resumable" && v["line"].is_null())
            .await
            .is_some()
    );

    // A job of more moves than are simulated while it loads: shown at once,
    // the firmware's estimate after.
    let mut g = String::from("G21 G90\nM3\nG1 F3000\n");
    for k in 0..30_000 {
        let (x, y) = ((k % 200) as f64 * 0.2, (k / 200) as f64 * 0.2);
        g.push_str(&format!("G1 X{x:.1} Y{y:.1}\n"));
    }
    g.push_str("M5\nG0 X0 Y0\n");
    send(
        &mut ws,
        json!({"t": "load", "kind": "gcode", "name": "big.nc", "data": g}),
    )
    .await;
    // The head (and its rough estimate) and the firmware's estimate come on
    // separate channels: either may be read first.
    let (mut job, mut ests) = (None::<serde_json::Value>, Vec::new());
    until(&mut ws, 60, |v| {
        if v["t"] == "job" && v["name"] == "big.nc" {
            job = Some(v.clone());
        }
        if v["t"] == "estimate" {
            ests.push(v.clone());
        }
        job.as_ref()
            .is_some_and(|j| ests.iter().any(|e| e["gen"] == j["gen"]))
    })
    .await;
    let job = job.expect("loaded");
    let est = ests
        .into_iter()
        .find(|e| e["gen"] == job["gen"])
        .expect("the firmware's estimate follows");
    let (rough, firm) = (
        job["est_s"].as_f64().unwrap(),
        est["est_s"].as_f64().unwrap(),
    );
    // The firmware's figure for this program on a board with the simulator's
    // settings, the pen at the origin where the text parked it. (A head read
    // after the estimate arrived already carries it.)
    let want = inkstep_host::estimate::estimate(
        &g,
        &inkstep_core::settings::Settings::default(),
        inkstep_host::geom::Pt::new(0.0, 0.0),
        &[],
    )
    .job_s;
    println!(
        "big.nc: estimate when loaded {rough:.1} s, the firmware's {firm:.1} s (want {want:.1} s)"
    );
    assert!((firm - want).abs() < 1e-3 * want, "{firm} vs {want}");
    drop(server);
    stop.store(true, Ordering::Relaxed);
    let _ = sim.join();
    let _ = std::fs::remove_dir_all(&dir);
}
