//! `cargo emu bench`: figures measured on the real product image in the emulator (the
//! cycle model of emu/README.md), printed as the README's table:
//! - CPU load per task (each RTIC task is an exception) at idle and while drawing
//!   bench/star.nc streamed over USB;
//! - the `?` answer time: from the bulk OUT packet that carries the `?` to the first
//!   bulk IN packet that carries the report;
//! - the highest step-event rate the firmware sustains while a job streams over USB
//!   with `?` polling and the LCD running: straight moves split into 2 mm segments at
//!   rising feeds; sustained = the cruise runs at the requested rate with no gap (a
//!   step interval over 1.5 times the median, the step queue running dry). Along X one
//!   event is one X step, so the settings' 100 kHz per axis bound it; diagonals traced
//!   point by point ($212=0: one axis per event) reach twice that, up to and beyond the
//!   planner's cap ([`inkstep_core::stepper::MAX_STEP_RATE`]): above it the cruise
//!   runs at the cap, without gaps (the bench fails when a trial does not);
//! - e-stop latency: from the e-stop pin's edge to the drivers' enable pin turning off,
//!   and to the last step edge;
//! - every pulse counted at the planner's cap ([`crate::count_trial`]): realistic lines,
//!   along X and point by point on a diagonal, the final position pulse by pulse
//!   against the commanded one and the reported `MPos`, and the firmware's late step
//!   armings (the bench fails when a pulse is added or lost).

use crate::clock::{T_PER_MS, T_PER_S, T_PER_US};
use crate::cpu_model::CpuModel;
use crate::session::{repo_root, Session};
use crate::soak::PROGRAMS;
use inkstep_serial::sender::Flow;
use std::fmt::Write as _;
use std::path::Path;

/// Interrupt names of the medium-density STM32F103 that the firmware binds (RM0008
/// table 63), by IRQ number.
const IRQ_NAMES: [(usize, &str); 12] = [
    (6, "EXTI0"),
    (7, "EXTI1"),
    (9, "EXTI3"),
    (10, "EXTI4"),
    (15, "DMA1_CHANNEL5"),
    (20, "USB_LP_CAN_RX0"),
    (23, "EXTI9_5"),
    (28, "TIM2"),
    (31, "I2C1_EV"),
    (35, "SPI1"),
    (39, "USART3"),
    (40, "EXTI15_10"),
];

/// The name of exception `e`: its vector, and the RTIC task bound to it in
/// src/main.rs when there is one (`#[task(binds = X, ..)] fn name`).
pub fn task_name(e: usize, tasks: &[(String, String)]) -> String {
    let vector = match e {
        0 => return "thread mode (init, idle)".into(),
        15 => "SysTick".to_string(),
        3 => "HardFault".to_string(),
        e if e >= 16 => IRQ_NAMES
            .iter()
            .find(|(n, _)| *n == e - 16)
            .map_or(format!("IRQ{}", e - 16), |(_, s)| s.to_string()),
        e => format!("exception {e}"),
    };
    match tasks.iter().find(|(b, _)| *b == vector) {
        Some((_, task)) => format!("{task} ({vector})"),
        None => vector,
    }
}

/// The exception number of the vector that RTIC task `task` binds in src/main.rs
/// (16 + its IRQ number; 15 for SysTick), so that a check on a task follows it when it
/// moves to another vector.
pub fn task_exception(task: &str) -> Option<usize> {
    let tasks = rtic_tasks();
    let (vector, _) = tasks.iter().find(|(_, t)| t == task)?;
    if vector == "SysTick" {
        return Some(15);
    }
    IRQ_NAMES
        .iter()
        .find(|(_, v)| v == vector)
        .map(|(n, _)| 16 + n)
}

/// (vector, task) pairs from the product's source.
pub fn rtic_tasks() -> Vec<(String, String)> {
    let src = std::fs::read_to_string(repo_root().join("src/main.rs")).unwrap_or_default();
    let mut out = Vec::new();
    let mut binds: Option<String> = None;
    for line in src.lines() {
        let l = line.trim();
        if let Some(rest) = l.strip_prefix("#[task(binds = ") {
            binds = rest.split([',', ')']).next().map(|s| s.trim().to_string());
        } else if let (Some(b), Some(rest)) = (&binds, l.strip_prefix("fn ")) {
            if let Some(name) = rest.split('(').next() {
                out.push((b.clone(), name.to_string()));
            }
            binds = None;
        }
    }
    out
}

/// Busy time per exception (and asleep) over a window.
#[derive(Clone, Debug)]
pub struct Load {
    pub span: u64,
    /// (exception, busy time, entries), busiest first.
    pub tasks: Vec<(usize, u64, u64)>,
    pub sleep: u64,
}

fn snapshot(s: &mut Session) -> (Vec<u64>, Vec<u64>, u64, u64) {
    let now = s.now();
    let p = s.m.state_mut().profile_now();
    (p.busy.clone(), p.entries.clone(), p.sleep, now)
}

fn load_between(a: &(Vec<u64>, Vec<u64>, u64, u64), b: &(Vec<u64>, Vec<u64>, u64, u64)) -> Load {
    let mut tasks: Vec<(usize, u64, u64)> = (0..a.0.len())
        .map(|e| (e, b.0[e] - a.0[e], b.1[e] - a.1[e]))
        .filter(|&(_, t, n)| t > 0 || n > 0)
        .collect();
    tasks.sort_by_key(|t| std::cmp::Reverse(t.1));
    Load {
        span: b.3 - a.3,
        tasks,
        sleep: b.2 - a.2,
    }
}

/// Load at idle: `seconds` with nothing to do after the LCD is up.
pub fn idle_load(elf: &Path, seconds: u64) -> Result<Load, String> {
    let mut s = Session::new(elf, None)?;
    s.boot()?;
    s.run_for(2 * T_PER_S)?;
    let a = snapshot(&mut s);
    s.run_for(seconds * T_PER_S)?;
    Ok(load_between(&a, &snapshot(&mut s)))
}

/// What drawing star.nc showed: the load from its first to its last step, the `?`
/// answer times, the interrupt lateness of the cycle model.
pub struct Drawing {
    pub load: Load,
    /// `?` answer times (OUT packet to IN packet), in time units, of the questions
    /// during which the flash was not written.
    pub answers: Vec<u64>,
    /// The same for the questions that overlapped a settings save's flash writes (the
    /// `$` lines at the top of star.nc): the CPU stalls while the flash is programmed.
    pub answers_during_save: Vec<u64>,
    pub lateness: crate::machine::Lateness,
}

/// Stream star.nc (send-response, as the equivalence check does) with `?` every
/// 50 ms plus a little (so the questions fall at every phase of the 1 ms schedule).
pub fn drawing(elf: &Path) -> Result<Drawing, String> {
    let mut s = Session::new(elf, None)?;
    s.boot()?;
    s.m.board().host.packets = Some(Vec::new());
    s.m.state_mut().lateness = Default::default();
    let mut marks: Vec<(Vec<u64>, Vec<u64>, u64, u64)> = Vec::new();
    let mut next_q = s.now();
    let mut steps_seen = 0;
    let (_, star) = PROGRAMS[0];
    // When the flash was programmed or erased (seen once per slot of the host's
    // schedule): a `?` whose answer spans one of these waited for a settings save.
    let mut flash_ops = s.m.board().flash.ops;
    let mut flash_at: Vec<u64> = Vec::new();
    let mut watch = |s: &mut Session| {
        let ops = s.m.board().flash.ops;
        if ops != flash_ops {
            flash_ops = ops;
            flash_at.push(s.now());
        }
        if s.now() >= next_q {
            s.send(b"?");
            next_q = s.now() + 50 * T_PER_MS + 37 * T_PER_US;
        }
        // The load window: from the first step to the last.
        let n = s.m.state().board.steps.len();
        if n > 0 && steps_seen == 0 {
            marks.push(snapshot(s));
        }
        if n > steps_seen {
            steps_seen = n;
            let snap = snapshot(s);
            if marks.len() < 2 {
                marks.push(snap);
            } else {
                marks[1] = snap;
            }
        }
        Ok(())
    };
    s.stream(star, Flow::SendResponse, 600 * T_PER_S, &mut watch)?;
    let end = s.now() + 600 * T_PER_S;
    loop {
        s.run_for(crate::usb_host::SLOT_T)?;
        watch(&mut s)?;
        let last = s.m.state().board.steps.last().map_or(0, |st| st.t);
        if s.now() > last + 500 * T_PER_MS || s.now() > end {
            break;
        }
    }
    if marks.len() < 2 {
        return Err("star.nc drew nothing".into());
    }
    let load = load_between(&marks[0], &marks[1]);
    let packets = s.m.board().host.packets.take().unwrap_or_default();
    let mut answers = Vec::new();
    let mut answers_during_save = Vec::new();
    for (i, p) in packets.iter().enumerate() {
        if p.out && p.data.contains(&b'?') {
            if let Some(r) = packets[i + 1..]
                .iter()
                .find(|r| !r.out && r.data.contains(&b'<'))
            {
                // A flash operation seen after the OUT packet and no later than one
                // host slot after the IN packet (when the watch last looked).
                let saving = flash_at
                    .iter()
                    .any(|&f| f > p.t && f <= r.t + crate::usb_host::SLOT_T);
                if saving {
                    answers_during_save.push(r.t - p.t);
                } else {
                    answers.push(r.t - p.t);
                }
            }
        }
    }
    Ok(Drawing {
        load,
        answers,
        answers_during_save,
        lateness: s.m.state().lateness.clone(),
    })
}

/// The moves of a rate trial.
#[derive(Clone, Copy, PartialEq, Eq)]
pub enum Pattern {
    /// Along X (DDA): one event per X step.
    AlongX,
    /// 45 degrees, point by point: one axis per event, two events per step of each.
    ClassicDiagonal,
}

/// One rate trial: requested step events per second, and what the cruise did.
pub struct RateTrial {
    pub requested: f64,
    /// Step events per second at cruise (the median interval).
    pub achieved: f64,
    /// The longest step interval at cruise over the median.
    pub worst_gap: f64,
    pub complaints: usize,
}

impl RateTrial {
    /// The rate the planner lets the cruise run at: the requested one, or the cap.
    pub fn planned(&self) -> f64 {
        self.requested
            .min(f64::from(inkstep_core::stepper::MAX_STEP_RATE))
    }
    pub fn sustained(&self) -> bool {
        self.complaints == 0 && self.worst_gap <= 1.5 && self.achieved >= 0.99 * self.planned()
    }
}

/// Steps per mm of X for the rate trials; $110 = 7499 mm/min keeps the axis just under
/// the settings' limit of 100 kHz ($110 x $100 / 60).
const RATE_STEPS_PER_MM: f64 = 800.0;

/// Moves in 2 mm segments (of X, or of X and Y) at `rate` step events per second for
/// about a second, streamed with character counting, `?` every 100 ms, the LCD
/// running.
pub fn rate_trial(elf: &Path, rate: f64, pattern: Pattern) -> Result<RateTrial, String> {
    let mut s = Session::new(elf, None)?;
    s.boot()?;
    let (setup, segment, events_per_mm): (&[&str], &str, f64) = match pattern {
        Pattern::AlongX => (
            &["$100=800", "$110=7499", "$120=20000"],
            "X2\n",
            RATE_STEPS_PER_MM,
        ),
        Pattern::ClassicDiagonal => (
            &[
                "$100=800",
                "$101=800",
                "$110=7499",
                "$111=7499",
                "$120=20000",
                "$121=20000",
                "$212=0",
            ],
            "X2 Y2\n",
            // Per mm of path: 1/sqrt 2 mm of each axis, every step its own event.
            2.0 * RATE_STEPS_PER_MM / std::f64::consts::SQRT_2,
        ),
    };
    for c in setup {
        let got = s.command(c, T_PER_S)?;
        if got.contains("error") {
            return Err(format!("{c}: {got}"));
        }
    }
    let feed = rate / events_per_mm * 60.0;
    let per_segment = events_per_mm
        * if pattern == Pattern::AlongX {
            2.0
        } else {
            2.0 * std::f64::consts::SQRT_2
        };
    let segments = ((rate / per_segment).ceil() as usize).max(20);
    let mut job = format!("G21 G91\nG1 F{feed:.1}\n");
    for _ in 0..segments {
        job.push_str(segment);
    }
    let first_step = s.m.state().board.steps.len();
    let mut next_q = s.now();
    let r = s.stream(&job, Flow::CharCount(128), 600 * T_PER_S, |s| {
        if s.now() >= next_q {
            s.send(b"?");
            next_q = s.now() + 100 * T_PER_MS;
        }
        Ok(())
    })?;
    s.wait_idle(600 * T_PER_S)?;
    let steps = &s.m.state().board.steps[first_step..];
    // Cruise: the middle 60 % of the steps.
    let (a, b) = (steps.len() / 5, steps.len() * 4 / 5);
    let mut iv: Vec<u64> = steps[a..b].windows(2).map(|w| w[1].t - w[0].t).collect();
    if iv.is_empty() {
        return Err("no steps".into());
    }
    let worst = *iv.iter().max().unwrap_or(&0);
    iv.sort_unstable();
    let median = iv[iv.len() / 2].max(1);
    Ok(RateTrial {
        requested: rate,
        achieved: T_PER_S as f64 / median as f64,
        worst_gap: worst as f64 / median as f64,
        complaints: r.errors.len() + r.alarms.len(),
    })
}

/// E-stop latency at `n` moments of a move at cruise: the worst time from the pin
/// edge to /EN off, and the step edges that came after the pin edge in all.
pub fn estop_latency(elf: &Path, n: usize) -> Result<(u64, usize), String> {
    let mut worst = (0, 0);
    for k in 0..n {
        let mut s = Session::new(elf, None)?;
        s.boot()?;
        s.send(b"G21 G90\nG1 X150 Y40 F3000\n");
        // At cruise, then at a different phase of the step period each time.
        s.run_for(800 * T_PER_MS + k as u64 * 37 * T_PER_US)?;
        s.m.board().watch[0] |= 1 << 9;
        let edge = s.now();
        let mut o = s.m.state().board.outside.clone();
        o.estop_open = true;
        s.set_outside(o);
        s.run_for(20 * T_PER_MS)?;
        let b = &s.m.state().board;
        let off = b
            .pin_changes
            .iter()
            .find(|&&(t, p, pin, level)| t >= edge && p == 0 && pin == 9 && level)
            .map(|c| c.0 - edge)
            .ok_or("the drivers were not turned off")?;
        let after = b.steps.iter().filter(|st| st.t > edge).count();
        worst = (worst.0.max(off), worst.1 + after);
    }
    Ok(worst)
}

fn us(t: u64) -> f64 {
    t as f64 / T_PER_US as f64
}

fn load_table(out: &mut String, title: &str, l: &Load, tasks: &[(String, String)]) {
    let pct = |t: u64| 100.0 * t as f64 / l.span as f64;
    let _ = writeln!(
        out,
        "\n{title} ({:.2} s of virtual time)\n\n| task (vector) | CPU | entries/s |\n|---|---:|---:|",
        l.span as f64 / T_PER_S as f64
    );
    let secs = l.span as f64 / T_PER_S as f64;
    for &(e, t, n) in &l.tasks {
        let _ = writeln!(
            out,
            "| {} | {:.2} % | {:.0} |",
            task_name(e, tasks),
            pct(t),
            n as f64 / secs
        );
    }
    let busy: u64 = l.tasks.iter().map(|t| t.1).sum();
    let _ = writeln!(
        out,
        "| **all (asleep in WFI: {:.1} %)** | **{:.2} %** | |",
        pct(l.sleep),
        pct(busy)
    );
}

/// The whole bench, as the README's markdown.
/// Every figure under both cycle models (emu/README.md, "Cycle model"), typical
/// first; the bench fails when a trial fails under either. `--cpu` picks one.
pub fn run(elf: &Path, models: &[CpuModel]) -> Result<String, String> {
    // Each model on a thread of its own (the machines share nothing; CI has two cores),
    // reported in the order asked.
    let results: Vec<Result<String, String>> = std::thread::scope(|scope| {
        let runs: Vec<_> = models
            .iter()
            .map(|&m| {
                scope.spawn(move || {
                    CpuModel::set_for_thread(m);
                    run_model(elf)
                })
            })
            .collect();
        runs.into_iter()
            .map(|r| {
                r.join()
                    .unwrap_or_else(|_| Err("the bench's thread panicked".into()))
            })
            .collect()
    });
    let mut out = String::new();
    let mut failed = Vec::new();
    for (&m, r) in models.iter().zip(results) {
        let _ = writeln!(
            out,
            "\n### Cycle model: {}\n\n{}",
            m.name(),
            reference_loop(m)
        );
        match r {
            Ok(s) => out.push_str(&s),
            Err(e) => {
                out.push_str(&e);
                failed.push(m.name());
            }
        }
    }
    if failed.is_empty() {
        Ok(out)
    } else {
        Err(format!(
            "{out}\nfailed under the {} model",
            failed.join(" and ")
        ))
    }
}

/// The model against the one published F103 measurement that could be found: a
/// 5-instruction loop at 12.03 cycles per turn at 72 MHz, from flash with 2 wait
/// states. Its code was not published; assumed here: a volatile counter
/// (`ldr r3, [sp]; adds r3, #1; str r3, [sp]; cmp r3, r2; bne`, 16-bit, aligned).
pub fn reference_loop(m: CpuModel) -> String {
    let code: Vec<u8> = [0x9B00u16, 0x3301, 0x9300, 0x4293, 0xD1FA]
        .iter()
        .flat_map(|h| h.to_le_bytes())
        .collect();
    let a = 0x0800_1000;
    let c = crate::cpu_model::block_cost(&code, a, m, 2);
    let turn = crate::cpu_model::block_total(&c, a + 10, Some(a), m, 2);
    // And `subs r0, #1; cmp r0, #0; bne`, measured at 6 cycles a turn on an
    // STM32F103ZET6 and a VET6 at 72 MHz (MarlinFirmware/Marlin pull request 19059).
    let code: Vec<u8> = [0x3801u16, 0x2800, 0xD1FC]
        .iter()
        .flat_map(|h| h.to_le_bytes())
        .collect();
    let c = crate::cpu_model::block_cost(&code, a, m, 2);
    let turn3 = crate::cpu_model::block_total(&c, a + 6, Some(a), m, 2);
    format!(
        "Reference loops (flash, 2 wait states): 5 instructions, {turn} cycles per turn against 12.03 measured ({:+.1} %); `subs; cmp; bne`, {turn3} against 6 measured ({:+.1} %).\n",
        (f64::from(turn) / 12.03 - 1.0) * 100.0,
        (f64::from(turn3) / 6.0 - 1.0) * 100.0
    )
}

/// The LCD task's CPU budget while drawing star.nc and at idle, percent (issue 20).
const LCD_DRAWING_MAX: f64 = 3.0;
const LCD_IDLE_MAX: f64 = 1.0;

/// The share of the CPU, percent, of the task named `lcd_refresh` in src/main.rs;
/// an error when it did not run (a renamed task must not pass unmeasured).
fn lcd_share(l: &Load, tasks: &[(String, String)]) -> Result<f64, String> {
    l.tasks
        .iter()
        .find(|&&(e, _, _)| task_name(e, tasks).starts_with("lcd_refresh "))
        .map(|t| 100.0 * t.1 as f64 / l.span.max(1) as f64)
        .ok_or_else(|| "the bench found no lcd_refresh task running".to_string())
}

fn run_model(elf: &Path) -> Result<String, String> {
    let tasks = rtic_tasks();
    let mut out = String::new();
    let idle = idle_load(elf, 3)?;
    let draw = drawing(elf)?;
    load_table(
        &mut out,
        "CPU load at idle (menu on the LCD)",
        &idle,
        &tasks,
    );
    load_table(
        &mut out,
        "CPU load drawing bench/star.nc (streamed over USB, `?` every 50 ms, first to last step)",
        &draw.load,
        &tasks,
    );
    // Issue 20: the LCD costs what it draws (its power-up, off the tick, is over
    // before the first step).
    let (lcd_idle, lcd_draw) = (lcd_share(&idle, &tasks)?, lcd_share(&draw.load, &tasks)?);
    let _ = writeln!(
        out,
        "
The LCD task: {lcd_draw:.2} % of the CPU while drawing star.nc (at most {LCD_DRAWING_MAX:.0} %), {lcd_idle:.2} % at idle (under {LCD_IDLE_MAX:.0} %)."
    );
    if lcd_draw > LCD_DRAWING_MAX || lcd_idle >= LCD_IDLE_MAX {
        return Err(format!(
            "{out}
the LCD task is over its CPU budget"
        ));
    }
    let a = &draw.answers;
    if a.is_empty() {
        return Err("no ? was answered".into());
    }
    let mean = a.iter().sum::<u64>() as f64 / a.len() as f64;
    let _ = writeln!(
        out,
        "\n| figure | value |\n|---|---|\n| `?` answer, OUT packet to IN packet ({} questions while streaming star.nc) | min {:.0} µs, mean {:.0} µs, max {:.0} µs |",
        a.len(),
        us(*a.iter().min().unwrap_or(&0)),
        mean / T_PER_US as f64,
        us(*a.iter().max().unwrap_or(&0)),
    );
    let saving = &draw.answers_during_save;
    let _ = writeln!(
        out,
        "| `?` answer while a settings save writes the flash (the `$` lines at the top of star.nc; the CPU stalls on flash writes) | {} of the {} questions, max {:.0} µs |",
        saving.len(),
        saving.len() + a.len(),
        us(*saving.iter().max().unwrap_or(&0)),
    );
    let (off, after) = estop_latency(elf, 8)?;
    let _ = writeln!(
        out,
        "| e-stop latency, pin edge to drivers off (/EN), worst of 8 at cruise (F3000) | {:.2} µs |\n| step edges after the e-stop pin edge, in those 8 | {after} |",
        us(off),
    );
    let l = &draw.lateness;
    let _ = writeln!(
        out,
        "| cycle model: interrupts taken after their event (block boundaries), while drawing | {} interrupts, mean {:.3} µs, max {:.3} µs late; longest block {} instructions |",
        l.count,
        if l.count > 0 { us(l.total) / l.count as f64 } else { 0.0 },
        us(l.max),
        l.longest_block
    );
    let _ = writeln!(
        out,
        "\n`?` answer time during character-counting streams (OUT packet to IN packet, a `?` every 10 ms; `cargo emu latency --lines N` for longer ones):\n\n{}",
        crate::latency::TABLE_HEAD
    );
    for (load, lines) in [
        (crate::latency::Load::OneStep, 3_000),
        (crate::latency::Load::Ordinary, 1_000),
        (crate::latency::Load::Arcs, 300),
    ] {
        let l = crate::latency::measure(elf, load, lines, 10 * T_PER_MS, false)?;
        let _ = writeln!(out, "{}", l.row(load));
    }
    let _ = writeln!(
        out,
        "\nSustained step-event rate (X moves in 2 mm segments streamed with character counting, `?` every 100 ms, LCD running):\n\n| requested events/s | planned (capped) | at cruise | worst interval / median | sustained |\n|---:|---:|---:|---:|---|"
    );
    let (mut best, mut all) = (0.0f64, true);
    let along_x = (1..=9)
        .map(|k| (10_000.0 * k as f64, Pattern::AlongX))
        .chain([(99_000.0, Pattern::AlongX)]);
    let diagonal = [80_000.0, 120_000.0, 195_000.0].map(|r| (r, Pattern::ClassicDiagonal));
    for (rate, pattern) in along_x.chain(diagonal) {
        let t = rate_trial(elf, rate, pattern)?;
        let _ = writeln!(
            out,
            "| {:.0}{} | {:.0} | {:.0} | {:.2} | {} |",
            t.requested,
            if pattern == Pattern::AlongX {
                ""
            } else {
                " (diagonal, point by point)"
            },
            t.planned(),
            t.achieved,
            t.worst_gap,
            if t.sustained() { "yes" } else { "no" }
        );
        if t.sustained() {
            best = t.planned().max(best);
        } else {
            all = false;
        }
    }
    let cap = f64::from(inkstep_core::stepper::MAX_STEP_RATE);
    let _ = writeln!(
        out,
        "\nHighest sustained: {best:.0} step events/s; every trial {}. The planner caps every move at {cap:.0} events/s (inkstep_core::stepper::MAX_STEP_RATE), so a request above the cap runs at the cap, without gaps (worst interval / median at most 1.5); along one axis the settings allow at most 100 kHz.",
        if all { "sustained its planned rate" } else { "NOT sustained: see the table" }
    );
    if !all {
        // The table is the evidence: print it, and fail.
        return Err(format!(
            "{out}\na rate trial left gaps or fell short of its planned rate"
        ));
    }
    let _ = writeln!(
        out,
        "\nEvery pulse counted (realistic lines streamed with character counting, `?` every 100 ms, the LCD drawing, about 0.5 s at cruise; rising edges on the step pins signed by the direction pins, against the commanded end point and `MPos`; `$100=$101=160`):\n\n| course | asked events/s | lines (bytes) | `?` sent / answered | cruise events/s | commanded X / Y | pulses X / Y | `MPos` X / Y (steps) | added (+) or lost (-) | late step armings |\n|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
    );
    let mut exact = true;
    for (course, rate) in [
        (crate::count_trial::Course::AlongX, 30_000.0),
        (crate::count_trial::Course::AlongX, 60_000.0),
        (crate::count_trial::Course::AlongX, cap),
        (crate::count_trial::Course::Diagonal, 60_000.0),
        (crate::count_trial::Course::Diagonal, cap),
    ] {
        let c = crate::count_trial::run(elf, course, rate, 0.5)?;
        let off = c.off_by();
        let _ = writeln!(
            out,
            "| {} | {:.0} | {} ({}-{}) | {} / {} | {:.0} | {} / {} | {} / {} | {} / {} | {:+} / {:+} | {} |",
            course.name(),
            rate,
            c.lines,
            c.line_bytes.0,
            c.line_bytes.1,
            c.questions,
            c.reports,
            c.cruise,
            c.commanded[0],
            c.commanded[1],
            c.pulses[0],
            c.pulses[1],
            c.reported[0],
            c.reported[1],
            off[0],
            off[1],
            c.late.map_or("not counted".to_string(), |n| n.to_string()),
        );
        exact &= c.exact();
    }
    if !exact {
        return Err(format!("{out}\na pulse was added or lost"));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Tasks are found by the vector they bind in src/main.rs, whichever it is.
    #[test]
    fn tasks_map_to_their_exception_numbers() {
        assert_eq!(task_exception("tick"), Some(15));
        assert_eq!(task_exception("step"), Some(16 + 28));
        assert_eq!(task_exception("keypad_scan"), Some(16 + 39));
        assert_eq!(task_exception("no_such_task"), None);
    }
}
