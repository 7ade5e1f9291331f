//! What the machine tells a process about itself, through the POSIX calls the standard library
//! does not wrap: CPU time of the process and of the calling thread (`clock_gettime` with
//! `CLOCK_PROCESS_CPUTIME_ID` / `CLOCK_THREAD_CPUTIME_ID`) and the physical memory
//! (`sysconf`). Linux, macOS and the BSDs have them; elsewhere every function returns `None`
//! and callers fall back (wall time, no memory check).

/// CPU time (user + system) of the whole process in seconds, every thread together.
pub fn process_cpu_seconds() -> Option<f64> {
    clock_seconds(Clock::Process)
}

/// CPU time (user + system) of the calling thread in seconds.
pub fn thread_cpu_seconds() -> Option<f64> {
    clock_seconds(Clock::Thread)
}

/// Physical memory of the machine in bytes.
pub fn physical_memory_bytes() -> Option<u64> {
    #[cfg(unix)]
    {
        // SAFETY: sysconf only reads configuration values.
        let (pages, page) = unsafe {
            (
                libc::sysconf(libc::_SC_PHYS_PAGES),
                libc::sysconf(libc::_SC_PAGESIZE),
            )
        };
        (pages > 0 && page > 0).then(|| pages as u64 * page as u64)
    }
    #[cfg(not(unix))]
    {
        None
    }
}

/// Let a closed stdout end the process quietly, as it ends `ls` or `cat` (`manylights scenes |
/// head`): Rust ignores SIGPIPE, so a write to a closed pipe fails and `println!` panics.
/// Restores the default action (terminate) on Unix; elsewhere does nothing.
pub fn exit_quietly_on_closed_pipe() {
    #[cfg(unix)]
    // SAFETY: setting a signal's disposition to its default touches no memory of ours.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

#[derive(Clone, Copy)]
enum Clock {
    Process,
    Thread,
}

#[cfg(unix)]
fn clock_seconds(clock: Clock) -> Option<f64> {
    let id = match clock {
        Clock::Process => libc::CLOCK_PROCESS_CPUTIME_ID,
        Clock::Thread => libc::CLOCK_THREAD_CPUTIME_ID,
    };
    let mut t = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `t` is a valid, writable timespec; clock_gettime writes only into it.
    let rc = unsafe { libc::clock_gettime(id, &mut t) };
    (rc == 0).then(|| t.tv_sec as f64 + t.tv_nsec as f64 * 1e-9)
}

#[cfg(not(unix))]
fn clock_seconds(_: Clock) -> Option<f64> {
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Busy work advances both clocks by at most its duration; sleeping advances neither much.
    #[cfg(unix)]
    #[test]
    fn cpu_clocks_count_work_not_sleep() {
        let (p0, t0) = (
            process_cpu_seconds().unwrap(),
            thread_cpu_seconds().unwrap(),
        );
        let start = std::time::Instant::now();
        let mut x = 0u64;
        while start.elapsed().as_secs_f64() < 0.2 {
            x = std::hint::black_box(x.wrapping_mul(6364136223846793005).wrapping_add(1));
        }
        let (p1, t1) = (
            process_cpu_seconds().unwrap(),
            thread_cpu_seconds().unwrap(),
        );
        // On a loaded machine the thread gets less CPU than the wall time, never more.
        assert!(t1 - t0 > 0.01 && t1 - t0 < 0.3, "thread {}", t1 - t0);
        assert!(
            p1 - p0 >= t1 - t0 - 1e-3,
            "process {} < thread {}",
            p1 - p0,
            t1 - t0
        );
        std::thread::sleep(std::time::Duration::from_millis(200));
        let t2 = thread_cpu_seconds().unwrap();
        assert!(t2 - t1 < 0.05, "sleeping cost {} CPU-s", t2 - t1);
    }

    #[cfg(unix)]
    #[test]
    fn physical_memory_is_plausible() {
        let m = physical_memory_bytes().unwrap();
        assert!(m > 64 << 20 && m < 1 << 50, "{m}");
    }
}
