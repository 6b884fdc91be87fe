//! `FakeGroup`: a HEBI group behind the same seam as libhebi's, for what an imitation
//! group does not model: IMU data and the module's orientation, modules that stop
//! answering, a feedback stream that stalls, the command lifetime, gains. It answers
//! every command with group feedback at once, on the caller's thread.

use std::sync::atomic::{AtomicBool, AtomicU32, Ordering::Relaxed};
use std::sync::{Arc, Mutex};

use super::gains::ModuleSettings;
use super::group::Group;
use super::mailbox::FeedbackWriter;
use super::message::{Sample, absent_feedback};
use crate::module::{Command, Feedback};

/// What a test sets and reads while the bus owns the group.
#[derive(Debug, Default)]
pub struct FakeControl {
    /// Stop publishing feedback (a stalled stream).
    pub stalled: AtomicBool,
    /// Modules (body order) absent from every group feedback from now on.
    pub lost: Vec<AtomicBool>,
    /// Modules whose IMU is missing (NaN).
    pub no_imu: Vec<AtomicBool>,
    pub lifetime_ms: AtomicU32,
    pub feedback_rate_hz: AtomicU32,
    /// What the group was told: settings at start-up, the last commands, whether it
    /// was released, the time (monotonic ns) of the last command.
    pub log: Mutex<FakeLog>,
}

#[derive(Debug, Default, Clone)]
pub struct FakeLog {
    pub settings: Vec<ModuleSettings>,
    pub last_commands: Vec<Command>,
    pub commands: u64,
    pub limp_commands: u64,
    pub last_command_ns: u64,
    pub released: bool,
}

impl FakeControl {
    /// Whether a module would still act on the last command at `now_ns`: a module
    /// drops a command older than its lifetime (0 = never).
    pub fn acting(&self, now_ns: u64) -> bool {
        let log = self.log.lock().unwrap();
        let ms = self.lifetime_ms.load(Relaxed);
        log.commands > 0 && (ms == 0 || now_ns - log.last_command_ns <= ms as u64 * 1_000_000)
    }
}

pub struct FakeGroup {
    writer: FeedbackWriter,
    control: Arc<FakeControl>,
    /// Positions in group order; `body_of[g]` is group module g's body position.
    positions: Vec<f32>,
    body_of: Vec<usize>,
    order: Vec<usize>,
    time_us: u64,
}

impl FakeGroup {
    /// A group of `writer.len()` modules (the writer's order is the body order).
    pub fn new(writer: FeedbackWriter) -> (Self, Arc<FakeControl>) {
        let n = writer.len();
        let order = writer.order().to_vec();
        let mut body_of = vec![0; n];
        for (i, &g) in order.iter().enumerate() {
            body_of[g] = i;
        }
        let control = Arc::new(FakeControl {
            lost: (0..n).map(|_| AtomicBool::new(false)).collect(),
            no_imu: (0..n).map(|_| AtomicBool::new(false)).collect(),
            ..FakeControl::default()
        });
        let me = Self {
            writer,
            control: control.clone(),
            positions: vec![0.0; n],
            body_of,
            order,
            time_us: 0,
        };
        (me, control)
    }

    fn publish(&mut self) {
        let c = &self.control;
        if c.stalled.load(Relaxed) {
            return;
        }
        self.time_us += 1000;
        let (positions, body_of, t) = (&self.positions, &self.body_of, self.time_us);
        self.writer.publish(super::mailbox::monotonic_ns(), |g| {
            if c.lost[body_of[g]].load(Relaxed) {
                return Sample::default();
            }
            let imu = !c.no_imu[body_of[g]].load(Relaxed);
            let nan = absent_feedback();
            Sample {
                present: true,
                feedback: Feedback {
                    module_time_us: t,
                    position_rad: positions[g],
                    velocity_rad_s: 0.0,
                    torque_nm: 0.0,
                    deflection_rad: 0.0,
                    // At rest, level: the accelerometer reads gravity's reaction.
                    accel_m_s2: if imu {
                        [0.0, 0.0, 9.81]
                    } else {
                        nan.accel_m_s2
                    },
                    gyro_rad_s: if imu { [0.0; 3] } else { nan.gyro_rad_s },
                    temperature_c: 30.0,
                    voltage_v: 24.0,
                    ..Feedback::default()
                },
                orientation: if imu {
                    [1.0, 0.0, 0.0, 0.0]
                } else {
                    [f32::NAN; 4]
                },
                receive_time_us: Some(t),
            }
        });
    }
}

impl Group for FakeGroup {
    fn len(&self) -> usize {
        self.positions.len()
    }

    fn send(&mut self, commands: &[Command]) -> bool {
        {
            let mut log = self.control.log.lock().unwrap();
            log.commands += 1;
            log.limp_commands += u64::from(commands.iter().all(Command::is_limp));
            log.last_command_ns = super::mailbox::monotonic_ns();
            log.last_commands.clear();
            log.last_commands.extend_from_slice(commands);
        }
        for (&g, c) in self.order.iter().zip(commands) {
            if c.position_rad.is_finite() {
                self.positions[g] = c.position_rad;
            }
        }
        self.publish();
        true
    }

    fn set_command_lifetime_ms(&mut self, ms: i32) -> Result<(), String> {
        self.control.lifetime_ms.store(ms.max(0) as u32, Relaxed);
        Ok(())
    }

    fn set_feedback_rate_hz(&mut self, hz: f32) -> Result<(), String> {
        self.control.feedback_rate_hz.store(hz as u32, Relaxed);
        Ok(())
    }

    fn configure(&mut self, settings: &[ModuleSettings]) -> Result<(), String> {
        self.control.log.lock().unwrap().settings = settings.to_vec();
        Ok(())
    }

    fn release(&mut self) {
        self.control.log.lock().unwrap().released = true;
    }
}
