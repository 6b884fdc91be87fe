//! Every transition of the failsafe, table-driven, plus randomised invariants.
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64;

use super::*;

const TICK: f64 = 0.001;
const OK: Health = Health {
    oldest_feedback_age_s: 0.002,
    non_finite: false,
};
const STALE: Health = Health {
    oldest_feedback_age_s: 0.2,
    non_finite: false,
};
const NAN: Health = Health {
    oldest_feedback_age_s: 0.002,
    non_finite: true,
};
const NEVER: Health = Health {
    oldest_feedback_age_s: f64::INFINITY,
    non_finite: false,
};
const AT_TIMEOUT: Health = Health {
    oldest_feedback_age_s: 0.05,
    non_finite: false,
};

#[derive(Debug, Clone, Copy)]
enum Step {
    /// One 1 ms cycle with this health.
    Tick(Health),
    /// Cycles for this many seconds with this health.
    For(f64, Health),
    /// Cycles for this many seconds, stale and healthy alternating every 10 ms.
    Flicker(f64),
    Request(Event),
    Resynced,
}
use Step::*;

#[derive(Debug, Clone, Copy)]
enum Start {
    Startup,
    Resyncing,
    Running,
    FaultHold,
    OperatorHold,
    FaultLimp,
    OperatorLimp,
    EStop,
    ShutdownHold,
    Finished,
}

struct Sim {
    fs: Failsafe,
    t: f64,
    out: Option<Output>,
    result: Option<Result<(), Refusal>>,
    /// Every output seen by `run`.
    seen: Vec<Output>,
}

impl Sim {
    fn new(auto_resume: bool) -> Self {
        let config = FailsafeConfig {
            auto_resume,
            ..FailsafeConfig::default()
        };
        Sim {
            fs: Failsafe::new(config),
            t: 0.0,
            out: None,
            result: None,
            seen: Vec::new(),
        }
    }

    fn tick(&mut self, h: Health) {
        self.t += TICK;
        let out = self.fs.update(self.t, &h);
        self.out = Some(out);
        self.seen.push(out);
    }

    fn run(&mut self, steps: &[Step]) {
        for &step in steps {
            match step {
                Tick(h) => self.tick(h),
                For(secs, h) => {
                    for _ in 0..(secs / TICK).round() as usize {
                        self.tick(h);
                    }
                }
                Flicker(secs) => {
                    for k in 0..(secs / TICK).round() as usize {
                        self.tick(if (k / 10) % 2 == 0 { STALE } else { OK });
                    }
                }
                Request(e) => self.result = Some(self.fs.request(self.t, e)),
                Resynced => self.fs.resynced(self.t),
            }
        }
    }

    fn reach(start: Start, auto_resume: bool) -> Self {
        let mut sim = Sim::new(auto_resume);
        let running = [Tick(OK), Resynced, Tick(OK)];
        let steps: Vec<Step> = match start {
            Start::Startup => vec![],
            Start::Resyncing => vec![Tick(OK)],
            Start::Running => running.to_vec(),
            Start::FaultHold => [&running[..], &[Tick(STALE)]].concat(),
            Start::OperatorHold => [&running[..], &[Request(Event::Hold)]].concat(),
            Start::FaultLimp => [&running[..], &[For(0.6, STALE)]].concat(),
            Start::OperatorLimp => [&running[..], &[Request(Event::Limp)]].concat(),
            Start::EStop => [&running[..], &[Request(Event::EStop)]].concat(),
            Start::ShutdownHold => [&running[..], &[Request(Event::Shutdown)]].concat(),
            Start::Finished => [&running[..], &[Request(Event::Shutdown), For(0.3, OK)]].concat(),
        };
        sim.run(&steps);
        sim.out = None;
        sim.result = None;
        sim
    }
}

struct Row {
    name: &'static str,
    start: Start,
    auto_resume: bool,
    steps: &'static [Step],
    /// Result of the last request, if the row expects one.
    result: Option<Result<(), Refusal>>,
    /// Output of the last update, if the row expects one.
    out: Option<Output>,
    mode: Mode,
    reason: Reason,
}

const fn row(
    name: &'static str,
    start: Start,
    steps: &'static [Step],
    result: Option<Result<(), Refusal>>,
    out: Option<Output>,
    mode: Mode,
    reason: Reason,
) -> Row {
    Row {
        name,
        start,
        auto_resume: false,
        steps,
        result,
        out,
        mode,
        reason,
    }
}

const fn auto(mut r: Row) -> Row {
    r.auto_resume = true;
    r
}

use Event as E;
use Output as O;
use Reason as R;
use Refusal as X;
const OK_: Option<Result<(), Refusal>> = Some(Ok(()));
const fn err(x: Refusal) -> Option<Result<(), Refusal>> {
    Some(Err(x))
}

#[rustfmt::skip]
const TABLE: &[Row] = &[
    // Startup: limp until feedback is healthy, then resync and run.
    row("startup waits for feedback", Start::Startup, &[For(0.5, NEVER)], None, Some(O::Limp), Mode::Limp, R::Startup),
    row("startup healthy asks for resync", Start::Startup, &[Tick(OK)], None, Some(O::Resync), Mode::Limp, R::Startup),
    row("startup resynced runs", Start::Startup, &[Tick(OK), Resynced, Tick(OK)], None, Some(O::Run), Mode::Running, R::Startup),
    row("startup arm refused before feedback", Start::Startup, &[Request(E::Arm)], err(X::FeedbackUnhealthy), None, Mode::Limp, R::Startup),
    row("startup hold refused before feedback", Start::Startup, &[Tick(STALE), Request(E::Hold)], err(X::FeedbackUnhealthy), None, Mode::Limp, R::Startup),
    row("startup limp stays limp", Start::Startup, &[Request(E::Limp), For(0.5, OK)], OK_, Some(O::Limp), Mode::Limp, R::Operator),
    row("startup estop", Start::Startup, &[Request(E::EStop), For(0.5, OK)], OK_, Some(O::Limp), Mode::EStop, R::EStop),
    row("startup shutdown finishes", Start::Startup, &[Request(E::Shutdown), Tick(OK)], OK_, Some(O::Finished), Mode::Limp, R::Shutdown),
    // Waiting for the loop to resync.
    row("resync repeats until confirmed", Start::Resyncing, &[Tick(OK), Tick(OK)], None, Some(O::Resync), Mode::Limp, R::Startup),
    row("resync fault falls back to startup", Start::Resyncing, &[Tick(STALE)], None, Some(O::Limp), Mode::Limp, R::Startup),
    row("resync fault then healthy resyncs again", Start::Resyncing, &[Tick(STALE), Tick(OK)], None, Some(O::Resync), Mode::Limp, R::Startup),
    row("resync confirmed runs", Start::Resyncing, &[Resynced], None, None, Mode::Running, R::Startup),
    row("resync changed by a request must be asked again", Start::Resyncing, &[Request(E::Hold), Resynced, Tick(OK)], OK_, Some(O::Resync), Mode::Limp, R::Startup),
    row("resync hold then confirmed holds", Start::Resyncing, &[Request(E::Hold), Tick(OK), Resynced, Tick(OK)], OK_, Some(O::Hold), Mode::Hold, R::Operator),
    row("resynced without being asked is ignored", Start::OperatorLimp, &[Tick(OK), Request(E::Arm), Resynced, Tick(OK)], OK_, Some(O::Resync), Mode::Limp, R::Operator),
    row("resync estop", Start::Resyncing, &[Request(E::EStop), Tick(OK)], OK_, Some(O::Limp), Mode::EStop, R::EStop),
    row("resync limp", Start::Resyncing, &[Request(E::Limp), Tick(OK)], OK_, Some(O::Limp), Mode::Limp, R::Operator),
    // Running.
    row("running stays running", Start::Running, &[For(1.0, OK)], None, Some(O::Run), Mode::Running, R::Startup),
    row("running age at timeout is healthy", Start::Running, &[Tick(AT_TIMEOUT)], None, Some(O::Run), Mode::Running, R::Startup),
    row("running timeout holds", Start::Running, &[Tick(STALE)], None, Some(O::Hold), Mode::Hold, R::FeedbackTimeout),
    row("running module never reported holds", Start::Running, &[Tick(NEVER)], None, Some(O::Hold), Mode::Hold, R::FeedbackTimeout),
    row("running non-finite holds", Start::Running, &[Tick(NAN)], None, Some(O::Hold), Mode::Hold, R::NonFiniteFeedback),
    row("running operator hold", Start::Running, &[Request(E::Hold), Tick(OK)], OK_, Some(O::Hold), Mode::Hold, R::Operator),
    row("running operator limp", Start::Running, &[Request(E::Limp), Tick(OK)], OK_, Some(O::Limp), Mode::Limp, R::Operator),
    row("running estop", Start::Running, &[Request(E::EStop), Tick(OK)], OK_, Some(O::Limp), Mode::EStop, R::EStop),
    row("running arm is a no-op", Start::Running, &[Request(E::Arm), Tick(OK)], OK_, Some(O::Run), Mode::Running, R::Startup),
    row("running stray resynced is ignored", Start::Running, &[Resynced, Tick(OK)], None, Some(O::Run), Mode::Running, R::Startup),
    row("running shutdown holds", Start::Running, &[Request(E::Shutdown), Tick(OK)], OK_, Some(O::Hold), Mode::Hold, R::Shutdown),
    // Failsafe hold.
    row("fault hold short fault keeps holding", Start::FaultHold, &[For(0.4, STALE)], None, Some(O::Hold), Mode::Hold, R::FeedbackTimeout),
    row("fault hold persisting goes limp", Start::FaultHold, &[For(0.6, STALE)], None, Some(O::Limp), Mode::Limp, R::FeedbackTimeout),
    row("fault hold non-finite persisting goes limp", Start::FaultHold, &[For(0.6, NAN)], None, Some(O::Limp), Mode::Limp, R::NonFiniteFeedback),
    row("fault hold cleared waits for arm", Start::FaultHold, &[For(2.0, OK)], None, Some(O::Hold), Mode::Hold, R::FeedbackTimeout),
    row("fault hold flicker goes limp", Start::FaultHold, &[Flicker(1.0)], None, Some(O::Limp), Mode::Limp, R::FeedbackTimeout),
    auto(row("auto: fault hold not yet trusted", Start::FaultHold, &[For(0.3, OK)], None, Some(O::Hold), Mode::Hold, R::FeedbackTimeout)),
    auto(row("auto: fault hold cleared resyncs", Start::FaultHold, &[For(0.6, OK)], None, Some(O::Resync), Mode::Hold, R::FeedbackTimeout)),
    auto(row("auto: fault hold resumes", Start::FaultHold, &[For(0.6, OK), Resynced, Tick(OK)], None, Some(O::Run), Mode::Running, R::AutoResume)),
    auto(row("auto: flicker never resumes", Start::FaultHold, &[Flicker(2.0)], None, Some(O::Limp), Mode::Limp, R::FeedbackTimeout)),
    auto(row("auto: fault again before resync holds", Start::FaultHold, &[For(0.6, OK), Tick(STALE)], None, Some(O::Hold), Mode::Hold, R::FeedbackTimeout)),
    row("fault hold arm refused while faulty", Start::FaultHold, &[Request(E::Arm)], err(X::FeedbackUnhealthy), None, Mode::Hold, R::FeedbackTimeout),
    row("fault hold arm resyncs", Start::FaultHold, &[Tick(OK), Request(E::Arm), Tick(OK)], OK_, Some(O::Resync), Mode::Hold, R::FeedbackTimeout),
    row("fault hold arm runs", Start::FaultHold, &[Tick(OK), Request(E::Arm), Tick(OK), Resynced, Tick(OK)], OK_, Some(O::Run), Mode::Running, R::Operator),
    auto(row("auto: operator takes over a fault hold", Start::FaultHold, &[Request(E::Hold), For(2.0, OK)], OK_, Some(O::Hold), Mode::Hold, R::Operator)),
    row("fault hold estop", Start::FaultHold, &[Request(E::EStop), Tick(STALE)], OK_, Some(O::Limp), Mode::EStop, R::EStop),
    row("fault hold shutdown goes limp at once", Start::FaultHold, &[Request(E::Shutdown), Tick(STALE)], OK_, Some(O::Limp), Mode::Limp, R::Shutdown),
    // Operator hold.
    row("operator hold persisting fault goes limp", Start::OperatorHold, &[For(0.6, STALE)], None, Some(O::Limp), Mode::Limp, R::FeedbackTimeout),
    auto(row("auto: operator hold never resumes", Start::OperatorHold, &[For(0.3, STALE), For(2.0, OK)], None, Some(O::Hold), Mode::Hold, R::Operator)),
    row("operator hold arm runs", Start::OperatorHold, &[Tick(OK), Request(E::Arm), Tick(OK), Resynced, Tick(OK)], OK_, Some(O::Run), Mode::Running, R::Operator),
    row("operator hold again is a no-op", Start::OperatorHold, &[Request(E::Hold), Tick(OK)], OK_, Some(O::Hold), Mode::Hold, R::Operator),
    // Limp.
    row("operator limp stays limp", Start::OperatorLimp, &[For(2.0, OK)], None, Some(O::Limp), Mode::Limp, R::Operator),
    row("operator limp hold resyncs first", Start::OperatorLimp, &[Tick(OK), Request(E::Hold), Tick(OK)], OK_, Some(O::Resync), Mode::Limp, R::Operator),
    row("operator limp hold then holds", Start::OperatorLimp, &[Tick(OK), Request(E::Hold), Tick(OK), Resynced, Tick(OK)], OK_, Some(O::Hold), Mode::Hold, R::Operator),
    row("operator limp arm refused when faulty", Start::OperatorLimp, &[Tick(STALE), Request(E::Arm)], err(X::FeedbackUnhealthy), None, Mode::Limp, R::Operator),
    row("operator limp arm runs", Start::OperatorLimp, &[Tick(OK), Request(E::Arm), Tick(OK), Resynced, Tick(OK)], OK_, Some(O::Run), Mode::Running, R::Operator),
    auto(row("auto: fault limp needs arm", Start::FaultLimp, &[For(2.0, OK)], None, Some(O::Limp), Mode::Limp, R::FeedbackTimeout)),
    row("fault limp arm runs", Start::FaultLimp, &[Tick(OK), Request(E::Arm), Tick(OK), Resynced, Tick(OK)], OK_, Some(O::Run), Mode::Running, R::Operator),
    row("arm then fault before resync falls back to limp", Start::OperatorLimp, &[Tick(OK), Request(E::Arm), Tick(STALE)], OK_, Some(O::Limp), Mode::Limp, R::FeedbackTimeout),
    row("hold-arm then fault before resync holds", Start::OperatorHold, &[Tick(OK), Request(E::Arm), Tick(NAN)], OK_, Some(O::Hold), Mode::Hold, R::NonFiniteFeedback),
    // E-stop latches.
    row("estop latched against hold", Start::EStop, &[Request(E::Hold)], err(X::EStopLatched), None, Mode::EStop, R::EStop),
    row("estop latched against limp", Start::EStop, &[Request(E::Limp)], err(X::EStopLatched), None, Mode::EStop, R::EStop),
    row("estop latched with healthy feedback", Start::EStop, &[For(2.0, OK)], None, Some(O::Limp), Mode::EStop, R::EStop),
    auto(row("auto: estop latched", Start::EStop, &[For(2.0, OK)], None, Some(O::Limp), Mode::EStop, R::EStop)),
    row("estop again", Start::EStop, &[Request(E::EStop), Tick(OK)], OK_, Some(O::Limp), Mode::EStop, R::EStop),
    row("estop arm refused when faulty", Start::EStop, &[Tick(STALE), Request(E::Arm)], err(X::FeedbackUnhealthy), None, Mode::EStop, R::EStop),
    row("estop arm resyncs", Start::EStop, &[Tick(OK), Request(E::Arm), Tick(OK)], OK_, Some(O::Resync), Mode::EStop, R::EStop),
    row("estop arm runs", Start::EStop, &[Tick(OK), Request(E::Arm), Tick(OK), Resynced, Tick(OK)], OK_, Some(O::Run), Mode::Running, R::Operator),
    row("estop shutdown finishes latched", Start::EStop, &[Request(E::Shutdown), Tick(OK)], OK_, Some(O::Finished), Mode::EStop, R::EStop),
    // Shutdown.
    row("shutdown holds first", Start::ShutdownHold, &[For(0.15, OK)], None, Some(O::Hold), Mode::Hold, R::Shutdown),
    row("shutdown then limp", Start::ShutdownHold, &[For(0.2, OK)], None, Some(O::Limp), Mode::Limp, R::Shutdown),
    row("shutdown then finished", Start::ShutdownHold, &[For(0.2, OK), Tick(OK)], None, Some(O::Finished), Mode::Limp, R::Shutdown),
    row("shutdown fault goes limp early", Start::ShutdownHold, &[Tick(STALE)], None, Some(O::Limp), Mode::Limp, R::Shutdown),
    row("shutdown refuses arm", Start::ShutdownHold, &[Request(E::Arm)], err(X::ShuttingDown), None, Mode::Hold, R::Shutdown),
    row("shutdown refuses hold", Start::ShutdownHold, &[Request(E::Hold)], err(X::ShuttingDown), None, Mode::Hold, R::Shutdown),
    row("shutdown refuses limp", Start::ShutdownHold, &[Request(E::Limp)], err(X::ShuttingDown), None, Mode::Hold, R::Shutdown),
    row("shutdown refuses shutdown", Start::ShutdownHold, &[Request(E::Shutdown)], err(X::ShuttingDown), None, Mode::Hold, R::Shutdown),
    row("shutdown estop cuts the hold", Start::ShutdownHold, &[Request(E::EStop), Tick(OK)], OK_, Some(O::Finished), Mode::EStop, R::EStop),
    row("finished stays finished", Start::Finished, &[For(0.1, OK)], None, Some(O::Finished), Mode::Limp, R::Shutdown),
    row("finished refuses estop", Start::Finished, &[Request(E::EStop)], err(X::ShuttingDown), None, Mode::Limp, R::Shutdown),
    row("finished refuses arm", Start::Finished, &[Tick(OK), Request(E::Arm)], err(X::ShuttingDown), None, Mode::Limp, R::Shutdown),
];

#[test]
fn every_transition_in_the_table() {
    for r in TABLE {
        let mut sim = Sim::reach(r.start, r.auto_resume);
        sim.run(r.steps);
        if let Some(expected) = r.result {
            assert_eq!(sim.result, Some(expected), "{}: request result", r.name);
        }
        if let Some(expected) = r.out {
            assert_eq!(sim.out, Some(expected), "{}: output", r.name);
        }
        assert_eq!(sim.fs.mode(), r.mode, "{}: mode", r.name);
        assert_eq!(sim.fs.reason(), r.reason, "{}: reason", r.name);
    }
}

#[test]
fn starting_states_are_what_their_names_say() {
    let cases = [
        (Start::Startup, Mode::Limp, Reason::Startup),
        (Start::Running, Mode::Running, Reason::Startup),
        (Start::FaultHold, Mode::Hold, Reason::FeedbackTimeout),
        (Start::OperatorHold, Mode::Hold, Reason::Operator),
        (Start::FaultLimp, Mode::Limp, Reason::FeedbackTimeout),
        (Start::OperatorLimp, Mode::Limp, Reason::Operator),
        (Start::EStop, Mode::EStop, Reason::EStop),
        (Start::ShutdownHold, Mode::Hold, Reason::Shutdown),
        (Start::Finished, Mode::Limp, Reason::Shutdown),
    ];
    for (start, mode, reason) in cases {
        let sim = Sim::reach(start, false);
        assert_eq!(
            (sim.fs.mode(), sim.fs.reason()),
            (mode, reason),
            "{start:?}"
        );
    }
    assert!(Sim::reach(Start::Finished, false).fs.is_finished());
}

#[test]
fn limp_comes_limp_after_s_after_the_fault_began() {
    let mut sim = Sim::reach(Start::Running, false);
    let t_fault = sim.t + TICK;
    sim.run(&[Tick(STALE)]);
    assert_eq!(sim.fs.since_s(), t_fault);
    while sim.fs.mode() == Mode::Hold {
        sim.tick(STALE);
    }
    assert_eq!(sim.fs.mode(), Mode::Limp);
    let held_for = sim.fs.since_s() - t_fault;
    assert!((held_for - 0.5).abs() < 1.5 * TICK, "held {held_for} s");
}

#[test]
fn running_is_never_reached_without_a_resync() {
    let events = [E::Hold, E::Limp, E::EStop, E::Arm, E::Shutdown];
    let healths = [OK, OK, OK, STALE, NAN, NEVER];
    let mut entered_running = 0;
    for seed in 0..40u64 {
        let mut rng = Pcg64::seed_from_u64(seed);
        let mut sim = Sim::new(seed % 2 == 0);
        let mut resync_asked = false;
        for _ in 0..3000 {
            let before = sim.fs.mode();
            let mut confirmed = false;
            match rng.random_range(0..100) {
                0..3 => {
                    let _ = sim
                        .fs
                        .request(sim.t, events[rng.random_range(0..events.len())]);
                }
                3..8 => {
                    sim.fs.resynced(sim.t);
                    confirmed = resync_asked;
                }
                _ => {
                    let h = healths[rng.random_range(0..healths.len())];
                    sim.tick(h);
                    resync_asked = sim.out == Some(O::Resync);
                    if sim.out == Some(O::Run) {
                        assert_eq!(sim.fs.mode(), Mode::Running, "seed {seed}");
                        assert!(
                            h.fault(sim.fs.config()).is_none(),
                            "seed {seed}: ran on a fault"
                        );
                    }
                }
            }
            if sim.fs.mode() == Mode::Running && before != Mode::Running {
                assert!(confirmed, "seed {seed}: running without a resync");
                entered_running += 1;
            }
            if sim.fs.is_finished() {
                break;
            }
        }
    }
    assert!(
        entered_running > 20,
        "the walk rarely ran: {entered_running}"
    );
}

#[test]
fn non_finite_age_counts_as_a_timeout() {
    let cfg = FailsafeConfig::default();
    let h = Health {
        oldest_feedback_age_s: f64::NAN,
        non_finite: false,
    };
    assert_eq!(h.fault(&cfg), Some(Reason::FeedbackTimeout));
    let both = Health {
        oldest_feedback_age_s: 1.0,
        non_finite: true,
    };
    assert_eq!(both.fault(&cfg), Some(Reason::NonFiniteFeedback));
    assert_eq!(OK.fault(&cfg), None);
}

#[test]
fn config_defaults_and_validation() {
    let c = FailsafeConfig::default();
    assert_eq!(c.feedback_timeout_s, 0.05);
    assert_eq!(c.limp_after_s, 0.5);
    assert!(!c.auto_resume);
    assert_eq!(c.shutdown_hold_s, 0.2);
    assert_eq!(c.validate(), Ok(()));
    for bad in [
        FailsafeConfig {
            feedback_timeout_s: 0.0,
            ..c
        },
        FailsafeConfig {
            limp_after_s: f64::NAN,
            ..c
        },
        FailsafeConfig {
            shutdown_hold_s: -1.0,
            ..c
        },
    ] {
        assert!(bad.validate().is_err(), "{bad:?}");
    }
    // TOML with unknown fields is refused; missing fields take defaults.
    let parsed: FailsafeConfig = toml::from_str("auto_resume = true").unwrap();
    assert!(parsed.auto_resume);
    assert_eq!(parsed.limp_after_s, 0.5);
    assert!(toml::from_str::<FailsafeConfig>("limp_after = 1.0").is_err());
}
