//! Work a layer still holds that goes on without an outside event (a byte from the
//! host, an input pin's edge, a key): each layer names the first such work it holds
//! ([`Machine::pending`](crate::machine::Machine::pending),
//! [`Protocol::pending`](crate::protocol::Protocol::pending),
//! [`Hmi::pending`](crate::hmi::Hmi::pending)), and
//! [`Controller::pending`](crate::controller::Controller::pending) combines them into
//! the one answer the service loop sleeps on. A layer that gains a new kind of work
//! adds a variant here and reports it; the controller's test builds every kind and
//! checks that the combination sees it.

/// One kind of pending work, named after the layer that holds it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Work {
    // The motion (the pipeline, through the machine's motion trait).
    /// Commands are queued or the machine is not at rest.
    Motion,
    // The machine.
    /// The homing cycle runs.
    Homing,
    /// A soft-limit alarm or the keypad's abort waits for rest to drop the queue.
    StopThenClear,
    /// A jog cancel waits for rest to drop the jog queue.
    JogCancel,
    /// A jog runs until its queue is empty.
    Jogging,
    /// M2/M30 waits for the queue to run empty to finish the job.
    JobEnding,
    /// An event (alarm, message) is still to be told.
    Events,
    // The protocol.
    /// A reply is still to be read out.
    Output,
    /// A complete line waits to run.
    LineReady,
    /// Received bytes wait to be framed.
    Received,
    /// A status report was asked for.
    StatusRequested,
    /// The welcome line is due.
    Welcome,
    /// A listing (`$$`, `$#`, ...) is under way.
    Listing,
    /// A startup line (`$N`) is still to run.
    StartupLine,
    /// The power-up notice waits for a listener.
    PendingWelcome,
    /// A G4's `ok` waits for the queue to run empty.
    OkWhenIdle,
    // The HMI.
    /// The boot screen or a message is still to be taken down.
    HmiTimer,
    /// A job is followed on the run page.
    HmiJob,
    // The controller.
    /// Host bytes wait in the receive ring.
    HostBytes,
    /// Settings, coordinates or the startup lines wait to be saved.
    Saves,
}

#[cfg(test)]
impl Work {
    /// Every kind, for the tests that build each one. The match makes a new variant
    /// a compile error here until it is listed.
    pub(crate) const ALL: [Work; 20] = {
        use Work::*;
        let all = [
            Motion,
            Homing,
            StopThenClear,
            JogCancel,
            Jogging,
            JobEnding,
            Events,
            Output,
            LineReady,
            Received,
            StatusRequested,
            Welcome,
            Listing,
            StartupLine,
            PendingWelcome,
            OkWhenIdle,
            HmiTimer,
            HmiJob,
            HostBytes,
            Saves,
        ];
        match all[0] {
            Motion | Homing | StopThenClear | JogCancel | Jogging | JobEnding | Events | Output
            | LineReady | Received | StatusRequested | Welcome | Listing | StartupLine
            | PendingWelcome | OkWhenIdle | HmiTimer | HmiJob | HostBytes | Saves => all,
        }
    };
}
