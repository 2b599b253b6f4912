//! The web view's time estimate against the machine: star.nc and a line of text
//! (short strokes and many pen lifts), estimated with the machine's settings, are
//! run through the simulator (the firmware's own planner and stepper timing, in
//! virtual time) as the page sends them, and the estimate must be within 1 % of the
//! time the job took, from its first motion to the end of the program.

use inkstep_core::settings::Settings;
use inkstep_host::geom::Pt;
use inkstep_host::web::job::{Job, Source};
use inkstep_sim::board::{Board, TICK_HZ};
use inkstep_sim::run::{run_on, Flow};

fn compare(what: &str, job: &Job, s: &Settings) -> f64 {
    let g: String = job.lines.iter().map(|l| l.text.clone() + "\n").collect();
    let mut b = Board::new(s.clone());
    let r = run_on(&mut b, &g, Flow::CharCount(128));
    assert!(
        r.errors.is_empty() && r.alarms.is_empty() && !r.timed_out,
        "{what}"
    );
    let took = r.rel(r.end) as f64 / TICK_HZ as f64;
    let est = job.total_s();
    let off = (est - took) / took;
    println!(
        "{what}: estimated {est:.3} s, the simulator took {took:.3} s ({:+.2} %)",
        off * 100.0
    );
    off
}

#[test]
fn the_estimate_is_within_one_percent_of_the_job_time() {
    let m = Settings::default();
    let star =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../bench/star.nc")).unwrap();
    let job = Job::new("star.nc", Source::Gcode(&star), Pt::new(0.0, 0.0), &m).unwrap();
    let a = compare("star.nc", &job, &m);
    let text = Job::new(
        "text",
        Source::Text("一帆风顺 Hello", 8.0),
        Pt::new(0.0, 0.0),
        &m,
    )
    .unwrap();
    let b = compare("text (一帆风顺 Hello, 8 mm)", &text, &m);
    // A servo pen that waits 400 ms at every lift ($204) and drop ($207): a text job is
    // mostly pen changes, and the estimate follows the machine's settings.
    let mut slow = m.clone();
    slow.set(201, 1.0).unwrap();
    slow.set(204, 400.0).unwrap();
    slow.set(207, 400.0).unwrap();
    let servo = Job::new(
        "text",
        Source::Text("一帆风顺 Hello", 8.0),
        Pt::new(0.0, 0.0),
        &slow,
    )
    .unwrap();
    let c = compare("text, servo pen with $204=$207=400", &servo, &slow);
    assert!(servo.total_s() > text.total_s() * 1.2, "the pen counts");
    for (what, off) in [("star.nc", a), ("text", b), ("text, servo", c)] {
        assert!(off.abs() < 0.01, "{what} off by {:.2} %", off * 100.0);
    }
}
