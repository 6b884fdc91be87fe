//! Starting a recording and owning its writer thread.

use std::net::SocketAddr;
use std::sync::Arc;
use std::sync::atomic::Ordering;
use std::thread::JoinHandle;

use super::error::RecordError;
use super::options::{RecordOptions, RecordState, RecordSummary, RecorderStatus, RecordingInfo};
use super::ring::{CloseOnDrop, RecordTx, Ring};
use super::writer::{Shared, Writer};
use crate::live::Latch;

/// Starts recording: allocates the ring, creates the file (if asked), starts the live
/// view (if asked) and the writer thread `snaked-record`. Errors (a path that cannot be
/// written, a port in use, a bad option) are returned here, before anything is pushed.
pub fn start(
    opts: RecordOptions,
    info: RecordingInfo,
) -> Result<(RecordTx, Recorder), RecordError> {
    start_with(opts, info, None)
}

/// Something else the writer thread hands every recorded cycle to (the ROS 2 node's
/// sink), with its wall-clock stamp, ns since the Unix epoch. It must not wait.
pub trait CycleSink: Send {
    fn cycle(&mut self, rec: &super::cycle::CycleRecord, unix_ns: u64);
    /// The recording's context, once, before any cycle (for channels of its own).
    fn attach(&mut self, _ctx: &Arc<foxglove::Context>) {}
}

/// [`start`], with every cycle also handed to `sink`.
pub fn start_with(
    opts: RecordOptions,
    info: RecordingInfo,
    sink: Option<Box<dyn CycleSink>>,
) -> Result<(RecordTx, Recorder), RecordError> {
    validate(&opts)?;
    let ring = Ring::new(opts.ring_capacity);
    let shared = Arc::new(Shared::new(ring.clone()));
    let (setup_tx, setup_rx) = std::sync::mpsc::sync_channel(1);
    let thread_shared = shared.clone();
    let thread = std::thread::Builder::new()
        .name("snaked-record".into())
        .spawn(move || {
            let _close = CloseOnDrop(thread_shared.ring.clone());
            // Set up on this thread: the live view's runtime then never meets the
            // caller's (a runtime cannot be started or dropped inside another).
            let (mut writer, setup) = Writer::open(&opts, info, thread_shared)?;
            let mut sink = sink;
            if let Some(sink) = &mut sink {
                sink.attach(writer.context());
            }
            writer.sink = sink;
            let _ = setup_tx.send(setup);
            writer.run()
        })
        .map_err(RecordError::Thread)?;
    let Ok(setup) = setup_rx.recv() else {
        // The thread ended without setting up: its result is the reason.
        return Err(match thread.join() {
            Ok(Err(e)) => e,
            Ok(Ok(_)) => RecordError::Finished,
            Err(_) => RecordError::Panicked,
        });
    };
    let recorder = Recorder {
        shared,
        thread: Some(thread),
        live_addr: setup.live_addr,
        latch: setup.latch,
    };
    Ok((RecordTx::new(ring), recorder))
}

fn validate(opts: &RecordOptions) -> Result<(), RecordError> {
    if opts.ring_capacity == 0 {
        return Err(RecordError::InvalidOption(
            "ring_capacity must be at least 1",
        ));
    }
    if !(opts.scene_rate_hz.is_finite() && opts.scene_rate_hz > 0.0) {
        return Err(RecordError::InvalidOption(
            "scene_rate_hz must be positive and finite",
        ));
    }
    opts.mcap.as_ref().map_or(Ok(()), |m| m.check())
}

/// The running recording. [`Recorder::finish`] (or dropping it) drains the ring,
/// writes the summary and index, stops the live view and joins the thread.
pub struct Recorder {
    shared: Arc<Shared>,
    thread: Option<JoinHandle<Result<RecordSummary, RecordError>>>,
    live_addr: Option<SocketAddr>,
    latch: Option<Arc<Latch>>,
}

impl Recorder {
    /// Finishes the recording; later pushes are refused.
    pub fn finish(mut self) -> Result<RecordSummary, RecordError> {
        self.finish_inner()
    }

    fn finish_inner(&mut self) -> Result<RecordSummary, RecordError> {
        let thread = self.thread.take().ok_or(RecordError::Finished)?;
        self.shared.ring.close();
        self.shared.stop.store(true, Ordering::Release);
        thread.thread().unpark();
        thread.join().map_err(|_| RecordError::Panicked)?
    }

    /// Where the live view listens (the bound port when 0 was asked for).
    pub fn live_addr(&self) -> Option<SocketAddr> {
        self.live_addr
    }

    pub fn status(&self) -> RecorderStatus {
        self.probe().status()
    }

    /// A handle that reads [`Recorder::status`] from anywhere, for as long as it is
    /// held (after [`Recorder::finish`] too).
    pub fn probe(&self) -> RecorderProbe {
        RecorderProbe {
            shared: self.shared.clone(),
            latch: self.latch.clone(),
        }
    }
}

/// Reads a recorder's [`RecorderStatus`] (the control socket's `record`).
#[derive(Clone)]
pub struct RecorderProbe {
    shared: Arc<Shared>,
    latch: Option<Arc<Latch>>,
}

impl RecorderProbe {
    pub fn status(&self) -> RecorderStatus {
        let s = &self.shared;
        let (file, capped) = (s.file(), s.capped());
        RecorderStatus {
            state: RecordState::of(file, capped),
            path: s.path.get().cloned(),
            error: s.error.get().cloned(),
            lost: s.lost.load(Ordering::Relaxed),
            items: s.items.load(Ordering::Relaxed),
            messages_written: s.written.load(Ordering::Relaxed),
            dropped: s.ring.dropped(),
            bytes: s.bytes.load(Ordering::Relaxed),
            capped,
            file,
            complete_s: s.complete_ns.load(Ordering::Relaxed) as f64 * 1e-9,
            live_clients: self.latch.as_ref().map_or(0, |l| l.clients()),
        }
    }
}

impl Drop for Recorder {
    fn drop(&mut self) {
        if self.thread.is_some()
            && let Err(e) = self.finish_inner()
        {
            tracing::warn!("recorder: {e}");
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_handles_cross_threads() {
        fn send<T: Send>() {}
        fn sync<T: Sync>() {}
        send::<RecordTx>();
        sync::<RecordTx>();
        send::<Recorder>();
        send::<RecordError>();
        send::<RecorderProbe>();
        sync::<RecorderProbe>();
    }
}
