//! Faults on the real product image (issue 13, point 4), each a test on the emulated
//! board: the e-stop mid-move, 100 feed holds at random moments, a power cut at every
//! flash operation of a settings save, the soak (streaming with the LCD running; the
//! watchdog never fires) and a sender that crashes mid-job.

mod common;

use common::{booted, STEPS_PER_MM};
use inkstep_emu::board::Step;
use inkstep_emu::clock::{T_PER_MS, T_PER_S, T_PER_US};
use inkstep_emu::session::Session;
use inkstep_serial::sender::Flow;

/// Send lines without waiting for their answers (they fit the receive buffer).
fn queue(s: &mut Session, lines: &str) {
    for l in lines.lines() {
        s.send(format!("{l}\n").as_bytes());
    }
}

/// Run until at least `n` step events have happened.
fn run_until_steps(s: &mut Session, n: usize) {
    let limit = s.now() + 10 * T_PER_S;
    while s.m.state().board.steps.len() < n {
        assert!(s.now() < limit, "no motion");
        s.run_for(100 * T_PER_US).unwrap();
    }
}

/// E-stop asserted on its EXTI pin mid-move: no rising step edge later than one step
/// period after it, the drivers disabled, and the alarm reported over USB.
#[test]
fn estop_mid_move_stops_steps_within_one_period_and_reports_the_alarm() {
    let mut s = booted(None);
    queue(&mut s, "G21 G90\nG1 X150 Y40 F3000");
    // At cruise: 3000 mm/min reached after 0.1 s of the default 500 mm/s^2.
    run_until_steps(&mut s, 4000);
    let steps: Vec<Step> = s.m.state().board.steps.clone();
    let period = steps[steps.len() - 1].t - steps[steps.len() - 2].t;
    // PA9 is the drivers' /EN (active low at the default $4=0): high is off.
    s.m.board().watch[0] |= 1 << 9;
    let t_edge = s.now();
    let mut o = s.m.state().board.outside.clone();
    o.estop_open = true;
    s.set_outside(o);
    s.run_for(50 * T_PER_MS).unwrap();
    let b = &s.m.state().board;
    let after = b.steps.iter().filter(|st| st.t > t_edge).count();
    eprintln!(
        "step period {:.1} us; {after} step edges after the e-stop edge",
        period as f64 / T_PER_US as f64
    );
    let late: Vec<&Step> = b.steps.iter().filter(|st| st.t > t_edge + period).collect();
    assert!(
        late.is_empty(),
        "{} step edges more than one period ({:.1} us) after the e-stop edge, first at +{:.1} us",
        late.len(),
        period as f64 / T_PER_US as f64,
        late.first()
            .map_or(0.0, |st| (st.t - t_edge) as f64 / T_PER_US as f64)
    );
    let off = b
        .pin_changes
        .iter()
        .find(|&&(t, p, n, level)| t >= t_edge && p == 0 && n == 9 && level);
    assert!(off.is_some(), "the drivers were not disabled");
    let got = s.take_received();
    let st = s.status().unwrap();
    assert!(
        got.contains("ALARM:10") || st.state == "Alarm",
        "no alarm over USB: {got:?}, {st:?}"
    );
    assert_eq!(st.state, "Alarm");
}

/// A tiny deterministic random source (xorshift), so the test is the same every run.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }

    /// Uniform in lo..hi.
    fn range(&mut self, lo: u64, hi: u64) -> u64 {
        lo + self.next() % (hi - lo)
    }
}

/// Feed holds (`!`) and resumes (`~`) at random moments: holds start 20..100 ms
/// apart and last 20..200 ms, so some come while accelerating, some in the middle of
/// a deceleration, some right after a resume.
struct Holds {
    rng: Rng,
    next: u64,
    holding: bool,
    pairs: u32,
}

impl Holds {
    fn step(&mut self, s: &mut Session) {
        if self.pairs >= 100 || s.now() < self.next {
            return;
        }
        if self.holding {
            s.send(b"~");
            self.pairs += 1;
            self.next = s.now() + self.rng.range(20, 100) * T_PER_MS;
        } else {
            s.send(b"!");
            self.next = s.now() + self.rng.range(20, 200) * T_PER_MS;
        }
        self.holding = !self.holding;
    }
}

/// Positions visited, without the times.
fn path(steps: &[Step]) -> Vec<[i32; 3]> {
    steps.iter().map(|st| st.pos).collect()
}

/// Step pulses per axis.
fn pulses(s: &Session) -> [u64; 3] {
    s.m.state().board.step_edges
}

/// 100 `!`/`~` pairs at random moments of a job: the same end, and the same pulses on
/// every axis, as the job without them.
#[test]
fn hundred_feed_holds_lose_and_add_no_pulse() {
    // The star twice over (it ends where it starts): long enough for 100 holds.
    let star = include_str!("../../bench/star.nc");
    let job = format!("{star}{star}");
    let mut plain = booted(None);
    plain
        .stream(&job, Flow::SendResponse, 600 * T_PER_S, |_| Ok(()))
        .unwrap();
    plain.wait_idle(600 * T_PER_S).unwrap();
    let want_path = path(&plain.m.state().board.steps);
    let want_pulses = pulses(&plain);

    let mut s = booted(None);
    let mut h = Holds {
        rng: Rng(0x1DEA_5EED),
        next: s.now() + 300 * T_PER_MS,
        holding: false,
        pairs: 0,
    };
    s.stream(&job, Flow::SendResponse, 600 * T_PER_S, |s| {
        h.step(s);
        Ok(())
    })
    .unwrap();
    // Every line is in the board; the holds go on while it draws.
    let limit = s.now() + 600 * T_PER_S;
    while h.pairs < 100 {
        assert!(s.now() < limit, "the job ended after {} holds", h.pairs);
        h.step(&mut s);
        s.run_for(inkstep_emu::usb_host::SLOT_T).unwrap();
        if !h.holding && s.m.state().board.steps.len() == want_path.len() {
            break;
        }
    }
    if h.holding {
        s.send(b"~");
    }
    let pairs = h.pairs;
    s.wait_idle(600 * T_PER_S).unwrap();
    assert_eq!(pairs, 100, "the job ended before 100 holds");
    let span = |s: &Session| {
        let st = &s.m.state().board.steps;
        st[st.len() - 1].t - st[0].t
    };
    // The holds really stopped the machine: the job took longer.
    let (t_plain, t_held) = (span(&plain), span(&s));
    eprintln!(
        "job {:.3} s without holds, {:.3} s with 100",
        t_plain as f64 / T_PER_S as f64,
        t_held as f64 / T_PER_S as f64
    );
    assert!(t_held > t_plain + 2 * T_PER_S);
    assert_eq!(pulses(&s), want_pulses, "pulses per axis");
    let got = path(&s.m.state().board.steps);
    assert_eq!(got.last(), want_path.last(), "end position");
    assert!(
        got == want_path,
        "the step path differs from the job without holds"
    );
    let st = s.status().unwrap();
    let end = want_path.last().unwrap();
    let mpos = st.pos.unwrap();
    assert!(
        (mpos[0] - end[0] as f64 / STEPS_PER_MM).abs() < 1e-3,
        "{st:?}"
    );
}

/// The `$$` listing of a board.
fn settings_listing(s: &mut Session) -> Vec<String> {
    let got = s.command("$$", 500 * T_PER_MS).unwrap();
    got.lines()
        .filter(|l| l.starts_with('$'))
        .map(str::to_string)
        .collect()
}

/// Run until the flash has been quiet for 100 ms (a save at rest is over).
fn until_flash_quiet(s: &mut Session) {
    let mut ops = s.m.state().board.flash.ops;
    let mut quiet = 0;
    while quiet < 100 {
        s.run_for(T_PER_MS).unwrap();
        let now = s.m.state().board.flash.ops;
        quiet = if now == ops { quiet + 1 } else { 0 };
        ops = now;
    }
}

/// A power cut at every flash program or erase operation of settings saves, then a
/// restart from that flash: the settings are the old or the new ones, never corrupt.
/// Six saves are made in a row so that the store's page change (copy to the next
/// page, its header, the old page's erase) is among them; the cuts are tried at every
/// operation of the first save (a record appended) and of each save that erased.
#[test]
fn power_cut_at_every_flash_operation_of_a_save_leaves_old_or_new_settings() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("flash.bin");
    // The values of $110 saved one after the other; the first is the starting state.
    let values = [1000, 1100, 1200, 1300, 1400, 1500, 1600];
    // The reference: the flash before each save, its operations, the listings.
    let mut before = Vec::new();
    let mut ops = Vec::new();
    let mut erased = Vec::new();
    let mut listings = Vec::new();
    {
        let mut s = booted(Some(&file));
        s.command(&format!("$110={}", values[0]), T_PER_S).unwrap();
        until_flash_quiet(&mut s);
        listings.push(settings_listing(&mut s));
        for v in &values[1..] {
            before.push(std::fs::read(&file).unwrap());
            let (start, erases) = (s.m.state().board.flash.ops, s.m.state().board.flash.erases);
            s.command(&format!("$110={v}"), T_PER_S).unwrap();
            until_flash_quiet(&mut s);
            ops.push(s.m.state().board.flash.ops - start);
            erased.push(s.m.state().board.flash.erases > erases);
            listings.push(settings_listing(&mut s));
        }
    }
    eprintln!("flash operations of the saves: {ops:?}, erasing: {erased:?}");
    assert!(ops.iter().all(|&n| n > 0));
    assert!(erased.iter().any(|&e| e), "no save changed pages");
    for (save, &n) in ops.iter().enumerate() {
        if save > 0 && !erased[save] {
            continue;
        }
        for k in 0..n {
            std::fs::write(&file, &before[save]).unwrap();
            let mut s = booted(Some(&file));
            let cut = s.m.state().board.flash.ops + k;
            s.m.board().flash.cut_at = Some(cut);
            s.send(format!("$110={}\n", values[save + 1]).as_bytes());
            let limit = s.now() + 2 * T_PER_S;
            loop {
                assert!(
                    s.now() < limit,
                    "save {}: operation {k} never came",
                    save + 1
                );
                match s.m.run_until(s.now() + T_PER_MS) {
                    None => {}
                    Some(inkstep_emu::machine::Stop::PowerCut) => break,
                    Some(other) => panic!("{other}"),
                }
            }
            drop(s);
            let mut s = booted(Some(&file));
            let got = settings_listing(&mut s);
            let (old, new) = (&listings[save], &listings[save + 1]);
            assert!(
                &got == old || &got == new,
                "save {}, cut at its operation {k}: the settings are neither the old nor the new ones ({:?})",
                save + 1,
                got.iter().find(|l| l.starts_with("$110"))
            );
        }
    }
}

/// Two minutes of virtual time streaming over USB with the LCD running: the watchdog
/// never fires (ten minutes: `cargo emu soak --minutes 10`).
#[test]
fn soak_two_minutes_streaming_with_the_lcd_the_watchdog_never_fires() {
    let mut s = Session::new(common::elf(), None).unwrap();
    let r = inkstep_emu::soak::soak(&mut s, 120.0).unwrap();
    eprintln!("{r}");
    assert!(r.virtual_s >= 120.0);
    assert!(r.lcd_bytes > 10_000, "the LCD was not running");
    assert!(r.passed(), "{r}\n{:?}", r.complaints);
}
