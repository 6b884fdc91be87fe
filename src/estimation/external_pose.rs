//! The daemon's pose input: where the body is according to something outside it
//! (motion capture, a total station), as such drivers publish it: a stamped position
//! and orientation in their own frame. One source writes ([`PoseWriter`]: the ROS 2
//! node's subscription); the newest pose waits in a triple buffer for the reader
//! ([`PoseReader`]), which takes it without waiting, locking or allocating (the loop
//! can), and counters anyone may read. Poses that are not finite, or whose orientation
//! is not a rotation, are refused and counted, never stored.

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering::Relaxed};

/// One pose from outside.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExternalPose {
    /// The source's stamp, ns since the Unix epoch.
    pub stamp_unix_ns: u64,
    /// When it arrived, ns since the Unix epoch.
    pub received_unix_ns: u64,
    /// In the source's frame, m.
    pub position_m: [f64; 3],
    /// Normalised (w, x, y, z).
    pub orientation_wxyz: [f64; 4],
    /// How many poses the writer had stored, this one included (0: none yet).
    pub number: u64,
}

impl ExternalPose {
    pub const NONE: ExternalPose = ExternalPose {
        stamp_unix_ns: 0,
        received_unix_ns: 0,
        position_m: [0.0; 3],
        orientation_wxyz: [1.0, 0.0, 0.0, 0.0],
        number: 0,
    };
}

/// What the input counts.
#[derive(Debug, Default)]
pub struct PoseCounters {
    pub received: AtomicU64,
    pub refused: AtomicU64,
    /// The newest stored pose's arrival, ns since the Unix epoch (0: none).
    pub last_unix_ns: AtomicU64,
}

/// The writing end.
pub struct PoseWriter {
    input: triple_buffer::Input<ExternalPose>,
    counters: Arc<PoseCounters>,
}

/// The reading end.
pub struct PoseReader {
    output: triple_buffer::Output<ExternalPose>,
}

/// A pose input: its writer, its reader, its counters.
pub fn pose_input() -> (PoseWriter, PoseReader, Arc<PoseCounters>) {
    let (input, output) = triple_buffer::triple_buffer(&ExternalPose::NONE);
    let counters = Arc::new(PoseCounters::default());
    (
        PoseWriter {
            input,
            counters: counters.clone(),
        },
        PoseReader { output },
        counters,
    )
}

impl PoseWriter {
    /// Stores a pose (the orientation normalised), or refuses it with the reason.
    pub fn write(
        &mut self,
        stamp_unix_ns: u64,
        received_unix_ns: u64,
        position_m: [f64; 3],
        orientation_wxyz: [f64; 4],
    ) -> Result<(), String> {
        let norm = orientation_wxyz.iter().map(|x| x * x).sum::<f64>().sqrt();
        let refused = if !position_m
            .iter()
            .chain(&orientation_wxyz)
            .all(|x| x.is_finite())
        {
            Some("not finite".to_owned())
        } else if (norm - 1.0).abs() > 0.1 {
            Some(format!("the orientation's norm is {norm:.3}, not 1"))
        } else {
            None
        };
        if let Some(why) = refused {
            self.counters.refused.fetch_add(1, Relaxed);
            return Err(why);
        }
        let number = self.counters.received.fetch_add(1, Relaxed) + 1;
        self.input.write(ExternalPose {
            stamp_unix_ns,
            received_unix_ns,
            position_m,
            orientation_wxyz: orientation_wxyz.map(|x| x / norm),
            number,
        });
        self.counters.last_unix_ns.store(received_unix_ns, Relaxed);
        Ok(())
    }
}

impl PoseReader {
    /// The newest pose (`number` 0: none yet).
    pub fn latest(&mut self) -> ExternalPose {
        *self.output.read()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_newest_pose_is_read_and_a_bad_one_refused() {
        let (mut w, mut r, c) = pose_input();
        assert_eq!(r.latest().number, 0);
        w.write(1, 2, [1.0, 2.0, 0.0], [1.0, 0.0, 0.0, 0.0])
            .unwrap();
        w.write(3, 4, [1.5, 2.0, 0.0], [1.0, 0.0, 0.0, 0.0])
            .unwrap();
        let p = r.latest();
        assert_eq!((p.number, p.stamp_unix_ns, p.position_m[0]), (2, 3, 1.5));
        assert!(
            w.write(5, 6, [f64::NAN, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0])
                .is_err()
        );
        assert!(w.write(5, 6, [0.0; 3], [0.0; 4]).is_err());
        assert_eq!(r.latest().number, 2, "the refused ones are not stored");
        assert_eq!(c.received.load(Relaxed), 2);
        assert_eq!(c.refused.load(Relaxed), 2);
        assert_eq!(c.last_unix_ns.load(Relaxed), 4);
        // A normalised orientation is stored.
        w.write(7, 8, [0.0; 3], [0.0, 0.0, 0.0, 2.0]).unwrap_err();
        w.write(7, 8, [0.0; 3], [0.0, 0.0, 0.0, 1.05]).unwrap();
        assert_eq!(r.latest().orientation_wxyz, [0.0, 0.0, 0.0, 1.0]);
    }
}
