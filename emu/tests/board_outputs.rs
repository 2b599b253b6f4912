//! The outputs that follow the motion with no host traffic, and what a board shows
//! when it cannot run, on the real image (issue 23, defects 1-4): the drivers' enable
//! (PA9) and the 4-phase coils released `$1` ms after the last step (255 keeps them),
//! the busy LED (PC13) and busy output (PC15) clear within 5 ms of it, `FS:` says the
//! real feed, a C8 (F_SIZE 64 KB) blinks and answers over USB with the part it needs,
//! a sender that waited after opening the port gets the welcome again, and floods of
//! resets and `?` through the USB path cut no line and lose no answer.

mod common;

use common::booted;
use inkstep_emu::clock::{T_PER_MS, T_PER_S};
use inkstep_emu::session::Session;

const PA: usize = 0;
const PC: usize = 2;

/// Send `line` and expect `ok`.
fn ok(s: &mut Session, line: &str) {
    let got = s.command(line, 2 * T_PER_S).unwrap();
    assert!(got.contains("ok"), "{line}: {got:?}");
}

/// Run until steps came after `since` and then none for 20 ms; the time of the last.
fn run_to_rest(s: &mut Session, since: u64) -> u64 {
    let limit = s.now() + 20 * T_PER_S;
    loop {
        s.run_for(5 * T_PER_MS).unwrap();
        let t = s.m.state().board.steps.last().map_or(0, |st| st.t);
        if t > since && s.now() - t > 20 * T_PER_MS {
            return t;
        }
        assert!(s.now() < limit, "no rest");
    }
}

/// Changes of pin `n` of port `p` after `t`: (time, level).
fn changes(s: &mut Session, p: usize, n: usize, t: u64) -> Vec<(u64, bool)> {
    s.m.state()
        .board
        .pin_changes
        .iter()
        .filter(|c| c.0 > t && c.1 == p && c.2 == n)
        .map(|c| (c.0, c.3))
        .collect()
}

fn ms(t: u64) -> f64 {
    t as f64 / T_PER_MS as f64
}

/// `$1=100`: /EN (PA9, active low) goes low before the first step and high 100 ms
/// after the last; `$1=0` at once; 255 keeps it low.
#[test]
fn the_drivers_are_released_step_idle_delay_after_the_last_step() {
    let mut s = booted(None);
    s.m.board().watch[PA] |= 1 << 9;
    for (delay, want_ms) in [(100u32, Some(100.0)), (0, Some(0.0)), (255, None)] {
        ok(&mut s, &format!("$1={delay}"));
        let t0 = s.now();
        ok(&mut s, "G21 G91 G1 F600 X1");
        let last = run_to_rest(&mut s, t0);
        s.run_for(2 * T_PER_S).unwrap();
        let first_step =
            s.m.state()
                .board
                .steps
                .iter()
                .find(|st| st.t > t0)
                .unwrap()
                .t;
        let on = changes(&mut s, PA, 9, t0);
        assert!(
            on.first().is_some_and(|&(t, high)| !high && t < first_step) || !s.m.board().pin(PA, 9),
            "$1={delay}: enabled before the first step: {on:?}"
        );
        let off = on
            .iter()
            .find(|&&(t, high)| high && t > last)
            .map(|&(t, _)| ms(t - last));
        eprintln!("$1={delay}: released {off:?} ms after the last step");
        match want_ms {
            Some(w) => {
                let got = off.expect("never released");
                assert!(
                    (got - w).abs() <= 2.0,
                    "$1={delay}: released after {got} ms"
                );
                assert!(s.m.board().pin(PA, 9), "stays released");
            }
            None => assert!(
                off.is_none() && !s.m.board().pin(PA, 9),
                "255 keeps them on"
            ),
        }
    }
}

/// 4-phase (`$200=1`): the coils (PA0-PA7) all go low `$1` ms after the last step;
/// before, PA0 and PA4 stayed high for good.
#[test]
fn the_four_phase_coils_are_released_too() {
    let mut s = booted(None);
    s.m.board().watch[PA] |= 0xFF;
    ok(&mut s, "$200=1");
    ok(&mut s, "$1=50");
    for line in ["G21 G91 G1 F300 X1", "G1 Y-1", "G1 X-1 Y1"] {
        let t0 = s.now();
        ok(&mut s, line);
        s.run_for(2 * T_PER_S).unwrap();
        let ch: Vec<(u64, usize, bool)> =
            s.m.state()
                .board
                .pin_changes
                .iter()
                .filter(|c| c.0 > t0 && c.1 == PA && c.2 < 8)
                .map(|c| (c.0, c.2, c.3))
                .collect();
        assert!(ch.len() > 8, "{line}: the coils moved: {}", ch.len());
        let levels: Vec<bool> = (0..8).map(|n| s.m.board().pin(PA, n)).collect();
        assert_eq!(levels, [false; 8], "{line}: every coil off at rest");
        // The release: the last changes, all to low, 50 ms after the step before.
        let release = ch.last().unwrap().0;
        let last_step = ch.iter().rev().find(|c| c.0 < release).unwrap().0;
        let after = ms(release - last_step);
        eprintln!("{line}: coils released {after:.2} ms after the last step");
        assert!((after - 50.0).abs() <= 2.0, "{line}: {after} ms");
    }
}

/// PC13 (LED, active low) and PC15 say busy during the moves and clear within 5 ms
/// of the last step, with no byte from the host after the lines: the five X1
/// moves, then moves of other lengths and feeds, each followed by rest (before, the
/// protocol task could go to sleep with the LED still on, until the next byte).
#[test]
fn busy_led_and_output_clear_within_5_ms_of_the_last_step_without_host_traffic() {
    let mut s = booted(None);
    s.m.board().watch[PC] |= (1 << 13) | (1 << 15);
    ok(&mut s, "G21 G91");
    let mut jobs: Vec<Vec<String>> = vec![vec!["G1 F600 X1".to_string(); 5]];
    for k in 0..24u32 {
        let len = 0.05 + 0.13 * f64::from(k % 7);
        let feed = 200 + 170 * (k % 11);
        let sign = if k % 2 == 0 { "" } else { "-" };
        jobs.push(vec![format!("G1 F{feed} X{sign}{len:.3} Y{len:.3}")]);
    }
    let mut worst: f64 = 0.0;
    for job in &jobs {
        let t0 = s.now();
        for line in job {
            ok(&mut s, line);
        }
        let last = run_to_rest(&mut s, t0);
        s.run_for(300 * T_PER_MS).unwrap();
        let led = changes(&mut s, PC, 13, t0);
        let out = changes(&mut s, PC, 15, t0);
        assert!(
            led.first().is_some_and(|c| !c.1),
            "{job:?}: LED lit: {led:?}"
        );
        assert!(
            out.first().is_some_and(|c| c.1),
            "{job:?}: busy output high: {out:?}"
        );
        assert!(
            s.m.board().pin(PC, 13) && !s.m.board().pin(PC, 15),
            "{job:?}: clear at rest"
        );
        let (led_off, out_off) = (led.last().unwrap().0, out.last().unwrap().0);
        assert!(led_off > last && out_off > last, "{job:?}");
        let late = ms(led_off.max(out_off) - last);
        worst = worst.max(late);
        assert!(
            late <= 5.0,
            "{job:?}: busy cleared {late} ms after the last step"
        );
    }
    eprintln!(
        "busy LED and output clear at most {worst:.2} ms after the last step ({} jobs)",
        jobs.len()
    );
}

/// `FS:` mid-move is the feed within 1 % (it said 0, or the start rate 60), and 0 at
/// rest.
#[test]
fn the_status_report_gives_the_real_feed_at_cruise_and_zero_at_rest() {
    let mut s = booted(None);
    for (line, feed, cruise_at) in [
        ("G21 G90 G1 X60 F1500", 1500.0, 1000),
        ("G1 X160 F3000", 3000.0, 1000),
        ("G91 G1 X-10 F600", 600.0, 500),
    ] {
        ok(&mut s, line);
        s.run_for(cruise_at * T_PER_MS).unwrap();
        let st = s.status().unwrap();
        let (fs, _) = st.feed.unwrap();
        eprintln!("{line}: {} FS {fs}", st.state);
        assert_eq!(st.state, "Run");
        assert!((fs - feed).abs() <= feed * 0.01, "{line}: FS {fs}");
        s.wait_idle(20 * T_PER_S).unwrap();
        let st = s.status().unwrap();
        assert_eq!(st.feed.unwrap().0, 0.0, "at rest");
    }
}

/// On an STM32F103C8 (F_SIZE 64 KB) the image does not run, visibly: USB enumerates
/// and answers with the alarm and the part needed, the LED blinks its code, the
/// drivers stay off and nothing moves.
#[test]
fn a_c8_blinks_and_names_the_part_it_needs_over_usb_with_the_motors_off() {
    let mut s = Session::new(common::elf(), None).unwrap();
    s.m.board().f_size_kb = 64;
    s.m.board().watch[PA] |= 1 << 9;
    s.m.board().watch[PC] |= 1 << 13;
    s.boot().expect("USB enumerates on a C8");
    s.run_for(50 * T_PER_MS).unwrap();
    let hello = s.take_received();
    assert!(
        hello.contains("Grbl 1.1h")
            && hello.contains("[MSG:Wrong chip: this image needs an STM32F103CB"),
        "{hello:?}"
    );
    assert_eq!(s.status().unwrap().state, "Alarm");
    // The commands that would unlock say why they cannot; motion is locked out.
    for (line, names_the_part) in [("$X", true), ("$H", true), ("G0 X10", false)] {
        let got = s.command(line, T_PER_S).unwrap();
        assert!(got.contains("error:9"), "{line}: {got:?}");
        assert_eq!(
            got.contains("STM32F103CB"),
            names_the_part,
            "{line}: {got:?}"
        );
    }
    let t = s.now();
    s.run_for(4 * T_PER_S).unwrap();
    let b = &s.m.state().board;
    assert!(b.steps.is_empty(), "nothing moved");
    assert!(b.pin(PA, 9), "/EN high: drivers off");
    assert!(
        !b.pin_changes.iter().any(|c| c.1 == PA && c.2 == 9 && !c.3),
        "the drivers were never enabled"
    );
    let led: Vec<u64> = b
        .pin_changes
        .iter()
        .filter(|c| c.0 > t && c.1 == PC && c.2 == 13 && !c.3)
        .map(|c| c.0)
        .collect();
    eprintln!("LED flashes in 4 s: {}", led.len());
    // Three flashes every 2 s.
    assert!((5..=7).contains(&led.len()), "{} flashes in 4 s", led.len());
    // The same image on a CB runs.
    let mut cb = booted(None);
    cb.run_for(50 * T_PER_MS).unwrap();
    assert!(!cb.take_received().contains("Wrong chip"));
}

/// bCNC opens the port (DTR), waits a second, flushes its input and sends: it gets
/// the welcome ahead of its first answer, so it learns the version.
#[test]
fn a_sender_that_waits_after_opening_the_port_gets_the_welcome_again() {
    let mut s = booted(None);
    s.run_for(T_PER_S).unwrap();
    let flushed = s.take_received();
    assert!(flushed.contains("Grbl 1.1h"), "{flushed:?}");
    let got = s.command("$I", T_PER_S).unwrap();
    let welcome = got.find("Grbl 1.1h").expect("the welcome again");
    assert!(welcome < got.find("[VER:").unwrap(), "{got:?}");
    // A sender that speaks at once gets it once.
    s.m.board().host.port_open = false;
    s.run_for(20 * T_PER_MS).unwrap();
    s.take_received();
    s.m.board().host.port_open = true;
    s.run_for(10 * T_PER_MS).unwrap();
    let got = s.take_received() + &s.command("$I", T_PER_S).unwrap();
    assert_eq!(got.matches("Grbl 1.1h").count(), 1, "{got:?}");
}

/// Floods in one write, through the real USB path: 300 soft resets then `?` cut no
/// line and the `?` is answered; 500 `?` get 500 reports (the image answered 18).
#[test]
fn floods_of_resets_and_queries_cut_no_line_and_lose_no_answer() {
    let mut s = booted(None);
    s.run_for(20 * T_PER_MS).unwrap();
    s.take_received();
    let mut bytes = vec![0x18u8; 300];
    bytes.push(b'?');
    s.send(&bytes);
    s.run_for(500 * T_PER_MS).unwrap();
    let got = s.take_received();
    let lines: Vec<&str> = got
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect();
    for l in &lines {
        assert!(
            *l == "Grbl 1.1h ['$' for help]" || l.starts_with("<Idle|") && l.ends_with('>'),
            "cut or unexpected line {l:?} in {got:?}"
        );
    }
    assert_eq!(
        lines.iter().filter(|l| l.starts_with('<')).count(),
        1,
        "{got:?}"
    );
    assert_eq!(
        lines.last().map(|l| l.starts_with('<')),
        Some(true),
        "{got:?}"
    );

    s.send(&[b'?'; 500]);
    s.run_for(2 * T_PER_S).unwrap();
    let got = s.take_received();
    let reports = got
        .lines()
        .map(str::trim)
        .filter(|l| l.starts_with("<Idle|") && l.ends_with('>'))
        .count();
    eprintln!(
        "300 resets: {} lines; 500 queries: {reports} reports",
        lines.len()
    );
    assert_eq!(reports, 500);
    assert_eq!(
        got.lines().filter(|l| !l.trim().is_empty()).count(),
        500,
        "{got:?}"
    );
}
