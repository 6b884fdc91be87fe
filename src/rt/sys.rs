//! Operating-system real-time settings. Each one may be refused (no privilege,
//! no CAP_SYS_NICE, a container); callers warn and carry on.
use std::io;

/// Run the calling thread under SCHED_FIFO at `priority` (1..=99).
pub fn set_fifo_priority(priority: i32) -> io::Result<()> {
    let param = libc::sched_param {
        sched_priority: priority,
    };
    // SAFETY: plain syscall on the calling thread (pid 0) with a valid parameter struct.
    let rc = unsafe { libc::sched_setscheduler(0, libc::SCHED_FIFO, &param) };
    if rc == 0 {
        Ok(())
    } else {
        Err(io::Error::last_os_error())
    }
}

/// Pin the calling thread to one CPU.
pub fn pin_to_cpu(cpu: usize) -> io::Result<()> {
    if cpu >= libc::CPU_SETSIZE as usize {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            "cpu index out of range",
        ));
    }
    // SAFETY: cpu_set_t is plain data; CPU_SET writes inside it for an index < CPU_SETSIZE.
    let rc = unsafe {
        let mut set: libc::cpu_set_t = std::mem::zeroed();
        libc::CPU_SET(cpu, &mut set);
        libc::sched_setaffinity(0, std::mem::size_of::<libc::cpu_set_t>(), &set)
    };
    if rc == 0 {
        Ok(())
    } else {
        Err(io::Error::last_os_error())
    }
}

/// Take `cpu` out of the calling thread's CPU set, so the threads it starts from now on
/// inherit a set without it (the loop's CPU stays the loop's). Returns false and changes
/// nothing when `cpu` is the only CPU the thread may use, or is not in its set.
pub fn avoid_cpu(cpu: usize) -> io::Result<bool> {
    if cpu >= libc::CPU_SETSIZE as usize {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            "cpu index out of range",
        ));
    }
    let size = std::mem::size_of::<libc::cpu_set_t>();
    // SAFETY: cpu_set_t is plain data; the CPU_* macros index inside it for indices
    // below CPU_SETSIZE; the syscalls get a valid pointer and its size.
    unsafe {
        let mut set: libc::cpu_set_t = std::mem::zeroed();
        if libc::sched_getaffinity(0, size, &mut set) != 0 {
            return Err(io::Error::last_os_error());
        }
        if !libc::CPU_ISSET(cpu, &set) || libc::CPU_COUNT(&set) < 2 {
            return Ok(false);
        }
        libc::CPU_CLR(cpu, &mut set);
        if libc::sched_setaffinity(0, size, &set) != 0 {
            return Err(io::Error::last_os_error());
        }
    }
    Ok(true)
}

/// A CPU wake-up latency limit (PM QoS), held while this lives: while it is held the
/// idle states of every CPU are those that wake within the limit (0: the CPUs poll when
/// idle instead of halting). cyclictest holds 0 the same way by default.
#[derive(Debug)]
pub struct CpuLatencyLimit(#[allow(dead_code)] std::fs::File);

/// Ask the kernel to keep every CPU's wake-up latency within `us` µs
/// (`/dev/cpu_dma_latency`; needs root). Released when the returned value is dropped.
pub fn limit_cpu_latency_us(us: i32) -> io::Result<CpuLatencyLimit> {
    use std::io::Write;
    let mut f = std::fs::OpenOptions::new()
        .write(true)
        .open("/dev/cpu_dma_latency")?;
    f.write_all(&us.to_ne_bytes())?;
    Ok(CpuLatencyLimit(f))
}

/// Lock current and future pages in memory so the loop never takes a page fault
/// to disk.
pub fn lock_memory() -> io::Result<()> {
    // SAFETY: plain syscall with constant flags.
    let rc = unsafe { libc::mlockall(libc::MCL_CURRENT | libc::MCL_FUTURE) };
    if rc == 0 {
        Ok(())
    } else {
        Err(io::Error::last_os_error())
    }
}

/// Timer slack of the calling thread, ns. Linux lets a normal thread's sleeps end up
/// to 50 µs late by default (to batch wake-ups); the loop wants its deadline.
pub fn set_timer_slack_ns(ns: u64) -> io::Result<()> {
    // SAFETY: prctl with PR_SET_TIMERSLACK takes one integer argument.
    let rc = unsafe { libc::prctl(libc::PR_SET_TIMERSLACK, ns as libc::c_ulong, 0, 0, 0) };
    if rc == 0 {
        Ok(())
    } else {
        Err(io::Error::last_os_error())
    }
}

/// CLOCK_MONOTONIC in nanoseconds.
pub fn monotonic_ns() -> u64 {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: valid pointer to a timespec; CLOCK_MONOTONIC always exists on Linux.
    unsafe { libc::clock_gettime(libc::CLOCK_MONOTONIC, &mut ts) };
    ts.tv_sec as u64 * 1_000_000_000 + ts.tv_nsec as u64
}

/// Sleep until the absolute CLOCK_MONOTONIC time `deadline_ns`
/// (`clock_nanosleep(TIMER_ABSTIME)`: no drift, no early wake-up accumulation).
pub fn sleep_until_ns(deadline_ns: u64) {
    let ts = libc::timespec {
        tv_sec: (deadline_ns / 1_000_000_000) as libc::time_t,
        tv_nsec: (deadline_ns % 1_000_000_000) as libc::c_long,
    };
    loop {
        // SAFETY: valid timespec; a null remainder is allowed with TIMER_ABSTIME.
        let rc = unsafe {
            libc::clock_nanosleep(
                libc::CLOCK_MONOTONIC,
                libc::TIMER_ABSTIME,
                &ts,
                std::ptr::null_mut(),
            )
        };
        if rc != libc::EINTR {
            return;
        }
    }
}

/// Spin on CLOCK_MONOTONIC until `deadline_ns` and return the first reading at or past
/// it (the caller has slept until shortly before).
pub fn spin_until_ns(deadline_ns: u64) -> u64 {
    loop {
        let now = monotonic_ns();
        if now >= deadline_ns {
            return now;
        }
        std::hint::spin_loop();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sleeping_until_a_past_deadline_returns() {
        let now = monotonic_ns();
        sleep_until_ns(now.saturating_sub(1_000_000));
        assert!(monotonic_ns() >= now);
    }

    #[test]
    fn timer_slack_can_be_tightened() {
        set_timer_slack_ns(1).unwrap();
        // SAFETY: PR_GET_TIMERSLACK takes no argument and returns the slack.
        let slack = unsafe { libc::prctl(libc::PR_GET_TIMERSLACK, 0, 0, 0, 0) };
        assert_eq!(slack, 1);
    }

    #[test]
    fn bad_cpu_index_is_refused() {
        assert!(pin_to_cpu(usize::MAX).is_err());
        assert!(avoid_cpu(usize::MAX).is_err());
    }

    #[test]
    fn spinning_returns_at_the_deadline() {
        let deadline = monotonic_ns() + 200_000;
        let woke = spin_until_ns(deadline);
        assert!(woke >= deadline && monotonic_ns() >= woke);
    }

    #[test]
    fn avoiding_a_cpu_leaves_the_others() {
        // In a thread of its own: the test harness's other threads keep their CPUs.
        std::thread::spawn(|| {
            let size = std::mem::size_of::<libc::cpu_set_t>();
            let count = || {
                // SAFETY: as in avoid_cpu.
                unsafe {
                    let mut set: libc::cpu_set_t = std::mem::zeroed();
                    assert_eq!(libc::sched_getaffinity(0, size, &mut set), 0);
                    (libc::CPU_COUNT(&set), libc::CPU_ISSET(0, &set))
                }
            };
            let (before, had_0) = count();
            let changed = avoid_cpu(0).unwrap();
            let (after, has_0) = count();
            assert_eq!(changed, had_0 && before >= 2);
            if changed {
                assert_eq!((after, has_0), (before - 1, false));
            } else {
                assert_eq!(after, before);
            }
        })
        .join()
        .unwrap();
    }
}
