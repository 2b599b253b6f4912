//! The web view's time estimate against the machine: star.nc and a line of text
//! (short strokes and many pen lifts), estimated from the firmware's default
//! settings, are run through the simulator (the firmware's own planner and
//! stepper timing, in virtual time), and the estimate must be within 10 % of
//! the time the job took.

use inkstep_host::geom::Pt;
use inkstep_host::web::job::{Job, Machine, Source};
use inkstep_sim::board::TICK_HZ;
use inkstep_sim::run::{run_gcode, Flow};

fn compare(what: &str, job: &Job) -> f64 {
    let g: String = job.lines.iter().map(|l| l.text.clone() + "\n").collect();
    let r = run_gcode(&g, Flow::CharCount(128));
    assert!(
        r.errors.is_empty() && r.alarms.is_empty() && !r.timed_out,
        "{what}"
    );
    let took = r.rel(r.end) as f64 / TICK_HZ as f64;
    let est = job.total_s();
    let off = (est - took) / took;
    println!(
        "{what}: estimated {est:.2} s, the simulator took {took:.2} s ({:+.1} %)",
        off * 100.0
    );
    off
}

#[test]
fn the_estimate_is_within_ten_percent_of_the_job_time() {
    let m = Machine::default();
    let star =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../bench/star.nc")).unwrap();
    let job = Job::new("star.nc", Source::Gcode(&star), Pt::new(0.0, 0.0), &m).unwrap();
    let a = compare("star.nc", &job);
    let text = Job::new(
        "text",
        Source::Text("一帆风顺 Hello", 8.0),
        Pt::new(0.0, 0.0),
        &m,
    )
    .unwrap();
    let b = compare("text (一帆风顺 Hello, 8 mm)", &text);
    // The pen time alone is a large part of a text job: leaving it out is well off.
    let bare = Machine {
        servo_s: Some(0.0),
        ..m
    };
    let without = Job::new(
        "text",
        Source::Text("一帆风顺 Hello", 8.0),
        Pt::new(0.0, 0.0),
        &bare,
    )
    .unwrap();
    assert!(without.total_s() < text.total_s() * 0.8, "the pen counts");
    assert!(a.abs() < 0.10, "star.nc off by {:.1} %", a * 100.0);
    assert!(b.abs() < 0.10, "text off by {:.1} %", b * 100.0);
}
