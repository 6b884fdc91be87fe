//! The recorder's side in the loop: each cycle it copies what it read and sent into a
//! preallocated [`CycleRecord`] and pushes it into the recorder's ring (never blocking
//! in the daemon; a full ring drops and counts), plus events as they happen (mode
//! changes, requests, takeovers and hand-backs, set-point faults) and the statistics
//! once a second of loop time. Nothing here allocates after construction.

use super::{
    CycleRecord, JointSample, RECORD_MAX_LINKS, RECORD_MAX_MODULES, RecordEvent, RecordItem,
    RecordTx,
};
use crate::emu::sim_bus::SimBus;
use crate::gait::GaitKind;
use crate::rt::messages::LoopRequest;
use crate::rt::observer::{CycleObserver, CycleView};
use crate::safety::failsafe::{Mode, Reason};

/// How the loop hands items to the recorder.
#[derive(Clone)]
pub struct LoopRecording {
    pub tx: RecordTx,
    /// Wait for room instead of dropping: only for offline (lockstep) runs such as the
    /// lab's, never for the real-time daemon.
    pub wait_when_full: bool,
}

/// The loop's recorder: the [`CycleObserver`] the loop is given when it records.
pub struct LoopRecorder {
    out: LoopRecording,
    scratch: Box<CycleRecord>,
    last_mode: Option<(Mode, Reason)>,
    last_engaged: Option<(GaitKind, u64)>,
    last_stats_s: u64,
}

impl LoopRecorder {
    pub fn new(out: LoopRecording) -> Self {
        Self {
            out,
            scratch: Box::new(CycleRecord::EMPTY),
            last_mode: None,
            last_engaged: None,
            last_stats_s: 0,
        }
    }

    fn push(&self, item: &RecordItem) {
        if self.out.wait_when_full {
            self.out.tx.push_wait(item);
        } else {
            self.out.tx.push(item);
        }
    }

    fn event(&self, t_ns: u64, event: RecordEvent) {
        self.push(&RecordItem::Event { t_ns, event });
    }

    /// Records the cycle just run, and the events its state shows.
    fn record_cycle(&mut self, v: &CycleView<'_>) {
        if self.last_mode != Some((v.mode, v.reason)) {
            self.last_mode = Some((v.mode, v.reason));
            let event = RecordEvent::Mode {
                mode: v.mode,
                reason: v.reason,
            };
            self.event(v.t_ns, event);
        }
        let engaged = v.slots.engaged().map(|g| (g, v.slots.id(g)));
        if engaged != self.last_engaged {
            if let Some((gait, controller_id)) = self.last_engaged {
                self.event(
                    v.t_ns,
                    RecordEvent::Released {
                        gait,
                        controller_id,
                    },
                );
            }
            if let Some((gait, controller_id)) = engaged {
                self.event(
                    v.t_ns,
                    RecordEvent::Engaged {
                        gait,
                        controller_id,
                    },
                );
            }
            self.last_engaged = engaged;
        }
        self.fill(v);
        self.push(&RecordItem::Cycle(*self.scratch));
        let second = v.t_ns / 1_000_000_000;
        if second != self.last_stats_s {
            self.last_stats_s = second;
            let stats = *v.stats;
            self.push(&RecordItem::Stats {
                t_ns: v.t_ns,
                stats,
            });
        }
    }

    fn fill(&mut self, v: &CycleView<'_>) {
        let r = &mut *self.scratch;
        r.cycle = v.cycle;
        r.t_ns = v.t_ns;
        r.mode = v.mode;
        r.reason = v.reason;
        r.gait = v.gait;
        r.controller_id = v.slots.id(v.gait);
        let report = v.slots.report();
        r.engaged = report.is_some();
        r.body = *v.body;
        r.progress = v.progress;
        r.navigator = v.navigator;
        match report {
            Some((_, rep)) => r.report = *rep,
            None => r.report.clear(),
        }
        r.modules = v.group.len();
        for ((j, m), c) in r
            .joints
            .iter_mut()
            .zip(&v.group.modules)
            .zip(v.commands)
            .take(RECORD_MAX_MODULES)
        {
            let f = &m.feedback;
            *j = JointSample {
                position_rad: f.position_rad,
                velocity_rad_s: f.velocity_rad_s,
                torque_nm: f.torque_nm,
                cmd_position_rad: c.position_rad,
                cmd_velocity_rad_s: c.velocity_rad_s,
                accel_m_s2: f.accel_m_s2,
                gyro_rad_s: f.gyro_rad_s,
            };
        }
        r.links = 0;
        if let Some(plant) = SimBus::of(v.bus).map(SimBus::plant) {
            let links = plant.link_count().min(RECORD_MAX_LINKS);
            for (k, pose) in r.link_poses.iter_mut().enumerate().take(links) {
                *pose = plant.link_pose(k);
            }
            r.links = links;
        }
    }
}

impl CycleObserver for LoopRecorder {
    fn cycle(&mut self, view: &CycleView<'_>) {
        self.record_cycle(view);
    }

    fn request(
        &mut self,
        t_ns: u64,
        ticket: u64,
        request: LoopRequest,
        result: crate::rt::messages::LoopResult,
    ) {
        let event = RecordEvent::Request {
            ticket,
            request,
            result,
        };
        self.event(t_ns, event);
    }

    fn setpoint_fault(&mut self, t_ns: u64, joint: usize, controller_id: u64) {
        let event = RecordEvent::SetpointFault {
            joint,
            controller_id,
        };
        self.event(t_ns, event);
    }

    /// Items the ring has dropped.
    fn dropped(&self) -> u64 {
        self.out.tx.dropped()
    }
}
