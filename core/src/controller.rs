//! The controller: the shell logic the firmware's tasks and the simulator share, so
//! that neither decides anything the other does not (docs/architecture.md).
//!
//! It ties the Grbl [`Protocol`] (and through it the [`Machine`](crate::machine::Machine))
//! to the keypad scanner and the standalone [`Hmi`], all driving one planner through
//! the [`MotionControl`] trait. Its methods are the entry points of the shell's tasks,
//! at the periods below: [`Controller::boot_in`] at power-up, [`Controller::service`]
//! once per protocol tick (the host's bytes both ways, the input pins with their
//! polarities, the port's open/close, the settings' effects and their persistence
//! at rest), [`Controller::set_pins`] from the input interrupts,
//! [`Controller::key_scan`] once per keypad column, and [`Controller::refresh_view`]
//! for the LCD. The HMI's [`Action`]s are carried out here, in order, through the
//! machine state so that keypad motion obeys the same rules as G-code.
//!
//! Kept small on purpose: no decision of the protocol, the planner or the HMI is made
//! here, only their wiring and the shell's own rules (what to save, and when).

use crate::gcode::interpreter::{Jog, JogFrame};
use crate::gcode::STARTUP_LINES;
use crate::halt::HaltLatch;
use crate::hmi::{self, Action, Beep, Hmi, MachineState};
use crate::keypad::{Keypad, KeypadConfig};
use crate::machine::state::Prompt;
use crate::machine::{InputPolarity, MotionControl, PinLevels, RunState};
use crate::motion::{Command, StepPos, X, Y, Z};
use crate::pending::Work;
pub use crate::protocol::is_realtime;
use crate::protocol::Protocol;
use crate::ring::{ByteRx, ByteTx};
use crate::settings::{PenMode, Settings};
use crate::settings_store::SettingsStore;
use crate::stepper::idle::{Activity, IdleOutputs, Levels};
use crate::stepper::output::OutputConfig;
use core::mem::MaybeUninit;
use embedded_storage::nor_flash::NorFlash;

/// The protocol tick, ms: the protocol and segment preparation run once per tick.
pub const SERVICE_PERIOD_MS: u32 = 1;
/// One keypad column is scanned per this many ms; the buzzer pattern advances by it.
pub const KEYPAD_SCAN_MS: u32 = 5;
/// The LCD refresh period, ms.
pub const LCD_REFRESH_MS: u32 = 100;

/// The byte ring from the host to the protocol (USB receive on the board): it holds
/// Grbl's whole 128-byte character-counting window (two USB packets). The window
/// itself is the protocol's receive buffer (`Bf:`); a full ring only NAKs the host
/// (back-pressure, nothing is dropped).
pub const HOST_RX_RING: usize = 128;
/// The byte ring from the protocol to the host: two USB packets. Responses wait in the
/// protocol's output buffer, which only hands out what this ring has room for.
pub const HOST_TX_RING: usize = 128;
/// Bytes handed to the host ring per tick at most: one USB packet (64 KB/s, far above
/// what Grbl's protocol needs).
const TX_PER_TICK: usize = 64;

/// A session's first byte from the host that comes this long (ms) or longer after
/// the port opened gets the welcome line again, ahead of its answer. Senders wait
/// for the welcome to learn the version, and some throw away what came before they
/// looked: bCNC raises DTR, waits a second (an Arduino's reset) and flushes its
/// input, and so never saw the welcome sent the moment DTR rose. A sender that read
/// it and sends at once (UGS, cncjs: within milliseconds) gets it once; one that
/// waited has nothing in flight for a second welcome to disturb.
pub const WELCOME_REPEAT_MS: u32 = 500;

/// The flash the image is linked for, KB: the STM32F103CB's.
pub const NEEDED_FLASH_KB: u32 = 128;
/// What a board with less flash says (with every welcome, and to every command that
/// would unlock or change something).
pub const WRONG_CHIP: &str = "Wrong chip: this image needs an STM32F103CB (128 KB flash)";

/// Keypad jogs run this far (1 m, in nanometres) unless stopped; key release stops them.
const JOG_REACH_NM: i64 = 1_000_000_000;

/// What the shell hands the controller each protocol tick.
pub struct HostLink<'a, 'r> {
    /// Bytes from the host; only those the protocol takes leave the ring.
    pub rx: &'a mut ByteRx<'r, HOST_RX_RING>,
    /// Bytes to the host; only what fits is written.
    pub tx: &'a mut ByteTx<'r, HOST_TX_RING>,
    /// The host has the port open (USB CDC's DTR; a pty that cannot tell: true).
    pub port_open: bool,
}

/// What the shell must do after a protocol tick.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Serviced {
    /// The settings changed: apply this output configuration.
    pub outputs: Option<OutputConfig>,
    /// A new pulse width for the pen servo, us: only when the pen is a servo
    /// (`$201=1`) and the width differs from the last one handed out (the shell
    /// writes the timer only then).
    pub servo_pulse_us: Option<u32>,
    /// The machine is in alarm: a halted step engine stays halted.
    pub alarmed: bool,
    /// How the input pins are read now (the halt latch's release reads the e-stop
    /// pin with it, [`HaltLatch::release`]).
    pub polarity: InputPolarity,
    /// A line ran and another may run at once: call again (the shell lets other
    /// work in between, see [`Controller::service`]).
    pub more: bool,
    /// Nothing changes until an outside event: a byte or the port's opening from the
    /// host, an input pin's edge, a key. The shell need not call again before one
    /// (the firmware's protocol task sleeps at idle); calling anyway is harmless.
    pub quiet: bool,
}

impl Serviced {
    /// The shell calls [`Controller::service`] again at once: another line may run,
    /// and the run that began at `started_ms` has not reached the next service
    /// period yet (`now_ms`; from then on the next period's run goes on).
    pub fn again(&self, started_ms: u32, now_ms: u32) -> bool {
        self.more && now_ms == started_ms
    }

    /// The machine lets the halt latch go ([`crate::halt::HaltLatch::release`]): it is
    /// not in alarm, and the e-stop is not active on `pins_now`, read just before.
    pub fn allows_release(&self, pins_now: PinLevels) -> bool {
        !self.alarmed && !self.polarity.decode(pins_now).estop
    }
}

/// What waits to be written to flash, at rest.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct Saves {
    settings: bool,
    coords: bool,
    startup: bool,
}

/// Outputs of the controller that the keypad task drives (the buzzer; the busy LED
/// and the motors' power follow [`Controller::outputs_now`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Outputs {
    /// The latest beep to play, taken by the buzzer task.
    pub beep: Option<Beep>,
}

pub struct Controller {
    protocol: Protocol,
    keypad: Keypad,
    hmi: Hmi,
    outputs: Outputs,
    /// Latest step direction on X and Y (-1, 0, +1), for the teaching view.
    dir: [i8; 2],
    /// The position at the last [`Controller::refresh_view`].
    view_pos: StepPos,
    /// The host had the port open at the last tick.
    port_open: bool,
    /// When the port opened, while the session's first byte has not come yet.
    session_quiet_since: Option<u32>,
    /// A message from power-up for the host (a corrupt store), said once it listens.
    notice: Option<&'static str>,
    saves: Saves,
    /// The status and power outputs' memory (when the motors last needed power).
    idle: IdleOutputs,
    /// The pen servo's pulse width as last handed to the shell.
    servo_us: Option<u32>,
    /// The input pins as the last call of `service` read them.
    pins: PinLevels,
}

/// The HMI's view of the machine's configuration, from the settings.
pub fn hmi_config(s: &Settings) -> hmi::Config {
    hmi::Config {
        steps_per_mm: [s.steps_per_mm(X), s.steps_per_mm(Y), s.steps_per_mm(Z)],
        pen_up_mm: s.pen_z_up(),
        pen_down_mm: s.pen_z_down(),
        ..hmi::Config::default()
    }
}

impl Controller {
    pub fn new(settings: Settings, now_ms: u32) -> Controller {
        crate::in_place::build(|slot| Controller::init_in(slot, &settings, now_ms))
    }

    /// [`Controller::new`] built in `slot`, the firmware's static cell: field by field,
    /// so that no whole controller, protocol or machine is built on init's stack
    /// and copied.
    #[allow(unsafe_code)]
    pub fn init_in<'a>(
        slot: &'a mut MaybeUninit<Controller>,
        settings: &Settings,
        now_ms: u32,
    ) -> &'a mut Controller {
        crate::init_fields!(slot => Controller {
            protocol in |cell| Protocol::init_in(cell, settings),
            keypad = Keypad::new(KeypadConfig::default()),
            hmi = Hmi::new(hmi_config(settings), now_ms),
            outputs = Outputs::default(),
            dir = [0, 0],
            view_pos = [0; 3],
            port_open = false,
            session_quiet_since = None,
            notice = None,
            saves = Saves::default(),
            idle = IdleOutputs::new(),
            servo_us = None,
            pins = PinLevels::default(),
        })
    }

    /// The chip's flash size (its F_SIZE register), KB, checked at boot: a chip with
    /// less than the image needs (a C8's 64 KB) does not run it. The board stays
    /// visibly alive instead of looking dead: the LED blinks its code, USB answers
    /// with the alarm and [`WRONG_CHIP`], the motors stay off.
    pub fn check_chip(&mut self, flash_kb: u32) {
        if flash_kb < NEEDED_FLASH_KB {
            self.protocol.machine_mut().refuse_to_run(WRONG_CHIP);
        }
    }

    /// The busy LED, the busy output and the motors' power at `now_ms`: the shell
    /// calls this every millisecond, moving or not, and drives the pins from it
    /// ([`crate::stepper::idle`]).
    pub fn outputs_now<M: MotionControl>(&mut self, m: &M, now_ms: u32) -> Levels {
        let machine = self.protocol.machine();
        // Busy while anything is queued or moves (a hold or a dwell with the job not
        // done included): a second controller waiting on the busy output waits for
        // the end of the job, and the motors keep their position meanwhile.
        let busy = !m.is_idle() || machine.state(m) == RunState::Home;
        let a = Activity {
            busy,
            needs_power: busy,
            released: machine.motors_released(),
            refused: machine.refusal().is_some(),
        };
        let delay = machine.settings().step_idle_delay_ms();
        self.idle.update(a, delay, now_ms)
    }

    /// Power-up from the store: the settings (the defaults if the store has none or
    /// they are unusable: the host is told once it listens), the coordinate data and
    /// the startup lines, with the controller built in `slot`.
    pub fn boot_in<'a, F: NorFlash>(
        slot: &'a mut MaybeUninit<Controller>,
        store: &mut SettingsStore<F>,
        now_ms: u32,
    ) -> &'a mut Controller {
        let mut settings = Settings::default();
        let load = store.load_settings(&mut settings);
        let ctl = Controller::init_in(slot, &settings, now_ms);
        ctl.notice = load.message();
        #[cfg(feature = "defmt")]
        if let Some(msg) = ctl.notice {
            defmt::warn!("settings: {}", msg);
        }
        let (coords, _) = store.load_coords();
        ctl.protocol.machine_mut().set_coords(coords);
        for i in 0..STARTUP_LINES {
            let (line, _) = store.load_startup(i);
            ctl.protocol.set_startup_line(i, line);
        }
        ctl
    }

    pub fn protocol(&self) -> &Protocol {
        &self.protocol
    }
    pub fn protocol_mut(&mut self) -> &mut Protocol {
        &mut self.protocol
    }
    pub fn hmi(&self) -> &Hmi {
        &self.hmi
    }
    pub fn keypad(&self) -> &Keypad {
        &self.keypad
    }

    /// Takes the outputs: the beep is handed out once.
    pub fn take_outputs(&mut self) -> Outputs {
        let o = self.outputs;
        self.outputs.beep = None;
        o
    }

    /// The settings changed (the caller saw `take_settings_dirty`): the HMI takes the
    /// new steps/mm and pen heights, keeping the draw speed the user chose.
    pub fn settings_changed(&mut self) {
        let cfg = hmi::Config {
            draw_feed_mm_min: self.hmi.draw_feed(),
            ..hmi_config(self.protocol.machine().settings())
        };
        self.hmi.set_config(cfg);
    }

    /// The LCD task's view of the machine. The teaching view's feed directions are
    /// the way each axis moved since the last call (the step interrupt keeps no
    /// bookkeeping for it).
    pub fn refresh_view<M: MotionControl>(&mut self, m: &M) -> hmi::Snapshot {
        let pos = m.position();
        if pos != self.view_pos {
            let sign = |a: usize| pos[a].cmp(&self.view_pos[a]) as i8;
            self.dir = [sign(X), sign(Y)];
            self.view_pos = pos;
        }
        self.status(m)
    }

    /// New levels of the input pins (from the input interrupts, and every tick): read
    /// with the settings' polarities ($5, $215) into the machine.
    pub fn set_pins<M: MotionControl>(&mut self, pins: PinLevels, m: &mut M, now_ms: u32) {
        let polarity = InputPolarity::from(self.protocol.machine().settings());
        self.protocol.set_inputs(polarity.decode(pins), m, now_ms);
    }

    /// One protocol run: the port's opening (the session starts with the welcome
    /// line; while it is closed, output is dropped), the input pins (with every input
    /// that tripped the halt latch since the last run shown active), the host's bytes
    /// (only those the protocol takes; real-time bytes act at once), at most one line
    /// with the protocol's and the HMI's periodic work, the replies, the settings'
    /// effects on the HMI and the outputs, and what changed to flash at rest. While
    /// [`Serviced::more`] says so, the shell calls it again (in the same tick),
    /// giving the USB and the step preparation their turn in between: so a `?` waits
    /// for one line at most, never for a whole receive window of them.
    pub fn service<M: MotionControl, F: NorFlash>(
        &mut self,
        host: HostLink<'_, '_>,
        pins: PinLevels,
        halt: &HaltLatch,
        store: &mut SettingsStore<F>,
        m: &mut M,
        now_ms: u32,
    ) -> Serviced {
        self.port(host.port_open, now_ms);
        self.greet_late(host.rx.is_empty(), now_ms);
        let polarity = InputPolarity::from(self.protocol.machine().settings());
        let pins = halt.take_tripped().fold(pins, polarity);
        self.pins = pins;
        self.protocol.set_inputs(polarity.decode(pins), m, now_ms);
        let said = self.protocol.output_len();
        host.rx.pop_while(|b| self.protocol.take_byte(b, m, now_ms));
        // A real-time byte that answered (a `?`'s report) goes out before the next
        // line runs: this call ends here and the shell calls again.
        let answered = self.protocol.output_len() > said;
        let more = answered || self.poll_one(m, now_ms);
        self.reply(host.tx, host.port_open, TX_PER_TICK);
        // The planner took new settings when they changed (at rest, before the next
        // line); what is left is the HMI, the outputs and the save.
        let changed = self.protocol.machine_mut().take_settings_dirty();
        if changed {
            self.settings_changed();
            // A new polarity ($5, $215) applies to the levels at once: a real-time
            // byte handled before the next call (a soft reset, which raises the
            // e-stop alarm if the e-stop reads active) must not read them as the old
            // polarity decoded them.
            let polarity = InputPolarity::from(self.protocol.machine().settings());
            self.protocol
                .set_inputs(polarity.decode(self.pins), m, now_ms);
        }
        self.persist(changed, store, m);
        let s = self.protocol.machine().settings();
        let servo = (s.pen_mode() == PenMode::Servo)
            .then(|| s.pen_servo_pulse_us(m.pen_level()))
            .filter(|&us| self.servo_us != Some(us));
        if servo.is_some() {
            self.servo_us = servo;
        }
        Serviced {
            outputs: changed.then(|| OutputConfig::from(s)),
            servo_pulse_us: servo,
            alarmed: self.protocol.machine().alarm().is_some(),
            polarity: InputPolarity::from(s),
            more,
            quiet: !more && self.pending(host.rx.is_empty(), m).is_none(),
        }
    }

    /// The host's bytes taken between two runs of the protocol task, by the shell's
    /// USB task when a packet brought a real-time byte ([`is_realtime`]): a `?`'s
    /// report (and a `!`, `~` or override) then goes out at once instead of after the
    /// segment preparation and the protocol task's next run, which can be 2 ms on the
    /// board (issue 20). What [`Controller::service`] does with the bytes, and
    /// nothing more: the session and the late welcome, the bytes into the protocol
    /// (lines wait there for `service`), the replies out. The report is the one
    /// `service` would give at this point: the machine's inputs as `service` last
    /// read them.
    pub fn take_realtime<M: MotionControl>(
        &mut self,
        host: HostLink<'_, '_>,
        m: &mut M,
        now_ms: u32,
    ) {
        self.port(host.port_open, now_ms);
        self.greet_late(host.rx.is_empty(), now_ms);
        host.rx.pop_while(|b| self.protocol.take_byte(b, m, now_ms));
        // The whole report if the ring has room: its tail must not wait for `service`.
        self.reply(host.tx, host.port_open, HOST_TX_RING);
    }

    /// A session's first byte after a quiet start gets the welcome again
    /// ([`WELCOME_REPEAT_MS`]).
    fn greet_late(&mut self, rx_empty: bool, now_ms: u32) {
        if let (Some(since), false) = (self.session_quiet_since, rx_empty) {
            self.session_quiet_since = None;
            if now_ms.wrapping_sub(since) >= WELCOME_REPEAT_MS {
                self.protocol.repeat_welcome();
            }
        }
    }

    /// The replies into the host's ring, `max` bytes at most (dropped with the port
    /// closed).
    fn reply(&mut self, tx: &mut ByteTx<'_, HOST_TX_RING>, port_open: bool, max: usize) {
        if !port_open {
            self.protocol.discard_output();
        }
        tx.push_from(max, || self.protocol.pop_output());
    }

    /// The first work any layer still holds, which goes on without an outside event:
    /// host bytes not yet taken (`rx_empty` false), saves waiting for rest, the
    /// HMI's timed work ([`Hmi::pending`]), the protocol's with the machine's and the
    /// motion's ([`Protocol::pending`]). `None`: [`Serviced::quiet`].
    pub fn pending<M: MotionControl>(&self, rx_empty: bool, m: &M) -> Option<Work> {
        if !rx_empty {
            Some(Work::HostBytes)
        } else if self.saves != Saves::default() {
            Some(Work::Saves)
        } else {
            self.hmi.pending().or_else(|| self.protocol.pending(m))
        }
    }

    /// The port's state this tick: opening it starts a session; the power-up notice
    /// waits for a listener.
    fn port(&mut self, open: bool, now_ms: u32) {
        if open && !self.port_open {
            self.protocol.start_session();
            self.session_quiet_since = Some(now_ms);
        }
        if !open {
            self.session_quiet_since = None;
        }
        self.port_open = open;
        if open {
            if let Some(msg) = self.notice.take() {
                self.protocol.notify(msg);
            }
        }
    }

    /// What changed goes to flash, at rest only: flash writes stall the CPU (its
    /// instruction fetch waits), which a step in flight must not see. A save that fails
    /// leaves the value in force until power-off and tells the host so: the `ok` of the
    /// `$n=v`, `G10` or `$Nx=` that changed it has gone out already, so the report is a
    /// `[MSG:...]` line (docs/grbl.md).
    fn persist<M: MotionControl, F: NorFlash>(
        &mut self,
        settings_changed: bool,
        store: &mut SettingsStore<F>,
        m: &M,
    ) {
        self.saves.settings |= settings_changed;
        self.saves.coords |= self.protocol.machine_mut().take_coords_dirty();
        self.saves.startup |= self.protocol.take_startup_dirty();
        if self.protocol.machine().busy(m) || self.saves == Saves::default() {
            return;
        }
        let saves = core::mem::take(&mut self.saves);
        let machine = self.protocol.machine();
        let settings_ok = !saves.settings || store.save_settings(machine.settings()).is_ok();
        let coords_ok = !saves.coords || store.save_coords(machine.interpreter().coords()).is_ok();
        let mut startup_ok = true;
        if saves.startup {
            for i in 0..STARTUP_LINES {
                let line = self.protocol.startup_line(i).unwrap_or("");
                startup_ok &= store.save_startup(i, line).is_ok();
            }
        }
        for (ok, msg) in [
            (settings_ok, "Settings not saved: flash write failed"),
            (coords_ok, "Offsets not saved: flash write failed"),
            (startup_ok, "Startup lines not saved: flash write failed"),
        ] {
            if !ok {
                #[cfg(feature = "defmt")]
                defmt::warn!("{}", msg);
                self.protocol.notify(msg);
            }
        }
    }

    /// The machine as the HMI sees it.
    pub fn status<M: MotionControl>(&self, m: &M) -> hmi::Snapshot {
        let state = match self.protocol.machine().state(m) {
            RunState::Idle | RunState::Check | RunState::Sleep => MachineState::Idle,
            RunState::Run => MachineState::Run,
            RunState::Hold { .. } | RunState::Door { .. } => MachineState::Hold,
            RunState::Jog => MachineState::Jog,
            RunState::Home => MachineState::Homing,
            RunState::Alarm => {
                MachineState::Alarm(self.protocol.machine().alarm().map_or(0, |a| a.code()))
            }
        };
        hmi::Snapshot {
            state,
            pos: m.position(),
            feed_mm_min: m.speed(),
            queue_empty: m.queued() == 0,
            dir: self.dir,
        }
    }

    /// One keypad column scan: `rows` read while [`Keypad::column`] was driven; each
    /// key event goes through the HMI and its actions through the machine. True when
    /// a key event came (a quiet protocol task has to look again, see
    /// [`Serviced::quiet`]).
    pub fn key_scan<M: MotionControl>(&mut self, rows: u8, m: &mut M, now_ms: u32) -> bool {
        let mut any = false;
        for ev in self.keypad.feed(rows, now_ms) {
            let st = self.status(m);
            let actions = self.hmi.key(ev, &st, now_ms);
            self.apply(&actions, m, now_ms);
            any = true;
        }
        any
    }

    /// Background work with at most one line: the protocol's lines and messages, then
    /// the HMI's timers (the completion of a keypad abort); true when another line
    /// may run now.
    fn poll_one<M: MotionControl>(&mut self, m: &mut M, now_ms: u32) -> bool {
        let more = self.protocol.poll_one(m, now_ms);
        let machine = self.protocol.machine_mut();
        if machine.take_message_new() {
            self.hmi.show_message(machine.message(), now_ms);
        }
        let pen = |p| match p {
            Prompt::Paused => None,
            Prompt::PenChange(n) => Some(n),
        };
        let machine = self.protocol.machine();
        self.hmi
            .set_prompt(machine.prompt().map(|p| (pen(p), machine.message())));
        let st = self.status(m);
        let actions = self.hmi.tick(&st, now_ms);
        self.apply(&actions, m, now_ms);
        more
    }

    fn apply<M: MotionControl>(&mut self, actions: &[Action], m: &mut M, now_ms: u32) {
        for a in actions {
            self.apply_one(a, m, now_ms);
        }
    }

    fn apply_one<M: MotionControl>(&mut self, a: &Action, m: &mut M, now_ms: u32) {
        let machine = self.protocol.machine_mut();
        // A refused action is shown as an error beep.
        let refused = match *a {
            // Through the machine state: the same locks and soft limits as G-code, and
            // the interpreter continues from the move's end. The HMI only starts a job
            // that fits the queue.
            Action::Queue(mv) => machine.queue(Command::Move(mv), m, now_ms).is_err(),
            Action::JogStart { dir, feed_mm_min } => {
                // A jog as a value, as `$J=G91 X.. Y.. F..` would make it: the keypad
                // holds the key, the jog reaches far and is cancelled on release.
                let reach = |d: i8| (d != 0).then(|| i64::from(d) * JOG_REACH_NM);
                let jog = Jog {
                    axes: [reach(dir[X]), reach(dir[Y]), None],
                    frame: JogFrame::Incremental,
                    feed_mm_min,
                };
                machine.jog(&jog, m).is_err()
            }
            Action::JogStop => {
                machine.jog_cancel(m);
                false
            }
            Action::FeedHold => {
                machine.feed_hold(m);
                false
            }
            Action::Resume => {
                machine.cycle_start(m);
                false
            }
            Action::Abort => {
                machine.stop_and_clear(m);
                false
            }
            Action::Home => machine.start_homing(m).is_err(),
            Action::SetOrigin => {
                machine.zero_xy_here(m);
                false
            }
            Action::Unlock => {
                let _ = machine.unlock();
                false
            }
            Action::Beep(b) => {
                self.outputs.beep = Some(b);
                false
            }
        };
        if refused {
            self.outputs.beep = Some(Beep::Error);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::machine::{MotionState, QueueFull};

    /// Motion that is either at rest with nothing queued or busy with one command.
    struct Motion(bool);

    impl MotionControl for Motion {
        fn push(&mut self, _: Command) -> Result<(), QueueFull> {
            Err(QueueFull)
        }
        fn queued(&self) -> usize {
            usize::from(self.0)
        }
        fn capacity(&self) -> usize {
            1
        }
        fn hold(&mut self) {}
        fn resume(&mut self) {}
        fn motion(&self) -> MotionState {
            if self.0 {
                MotionState::Running
            } else {
                MotionState::Idle
            }
        }
        fn clear(&mut self) {}
        fn set_overrides(&mut self, _: u8, _: u8) {}
        fn position(&self) -> StepPos {
            [0; 3]
        }
        fn set_position(&mut self, _: StepPos) {}
        fn speed(&self) -> f32 {
            0.0
        }
    }

    /// Every kind of work any layer can hold, built one at a time on a controller
    /// with nothing else to do: the service loop's combination names it, so the
    /// protocol task never sleeps with it waiting. A layer's new kind of work that
    /// the combination does not see fails here (each kind must be built by its
    /// layer's `set_work`, and found).
    #[test]
    fn every_kind_of_pending_work_keeps_the_service_loop_awake() {
        let mut c = Controller::new(Settings::default(), 0);
        let clear = |c: &mut Controller| {
            for w in Work::ALL {
                c.hmi.set_work(w, false);
                c.protocol.set_work(w, false);
            }
            c.saves = Saves::default();
        };
        clear(&mut c);
        assert_eq!(c.pending(true, &Motion(false)), None, "nothing to do");
        for w in Work::ALL {
            clear(&mut c);
            let (rx_empty, motion) = match w {
                Work::HostBytes => (false, false),
                Work::Motion => (true, true),
                Work::Saves => {
                    c.saves.settings = true;
                    (true, false)
                }
                _ => {
                    let built = c.hmi.set_work(w, true) || c.protocol.set_work(w, true);
                    assert!(built, "{w:?}: no layer builds it");
                    (true, false)
                }
            };
            assert_eq!(c.pending(rx_empty, &Motion(motion)), Some(w), "{w:?}");
        }
    }
}
