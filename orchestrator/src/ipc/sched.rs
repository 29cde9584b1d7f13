//! A latency hint to the Linux scheduler for the threads of a multi-process lockstep.
//!
//! In lockstep every process sleeps while another computes, so each control step has
//! several wake-ups. On a loaded machine a woken process waits behind whatever holds
//! the core for the rest of that task's time slice (~3 ms by default), and those waits
//! made most of the multi-process overhead (see BENCHMARKS.md). Since Linux 6.12 a
//! SCHED_OTHER thread may ask for a shorter slice (`sched_attr.sched_runtime`); EEVDF
//! then gives it an earlier deadline on wake-up, so it preempts sooner. The thread's
//! share of the CPU is unchanged. Elsewhere (older kernels, other systems) the request
//! is refused or not made, and nothing else changes.

use std::time::Duration;

/// A slice requested for the calling thread; dropping it gives the thread the
/// kernel's default slice back.
#[derive(Debug)]
pub struct SliceHint {
    #[cfg(target_os = "linux")]
    previous: Option<linux::SchedAttr>,
}

impl SliceHint {
    /// Ask for `slice` as the calling thread's time slice; `None` leaves it alone.
    /// Whether the kernel took it is [`SliceHint::applied`].
    pub fn request(slice: Option<Duration>) -> Self {
        #[cfg(target_os = "linux")]
        {
            Self {
                previous: slice.and_then(linux::set_slice),
            }
        }
        #[cfg(not(target_os = "linux"))]
        {
            let _ = slice;
            Self {}
        }
    }

    /// Whether the thread runs with the requested slice.
    pub fn applied(&self) -> bool {
        #[cfg(target_os = "linux")]
        {
            self.previous.is_some()
        }
        #[cfg(not(target_os = "linux"))]
        {
            false
        }
    }
}

impl Drop for SliceHint {
    fn drop(&mut self) {
        #[cfg(target_os = "linux")]
        if let Some(prev) = self.previous.take() {
            linux::set_attr(&prev);
        }
    }
}

#[cfg(target_os = "linux")]
mod linux {
    use std::time::Duration;

    /// `struct sched_attr` of sched_setattr(2) (the fields up to `sched_period`).
    #[derive(Debug, Clone, Copy, Default)]
    #[repr(C)]
    pub(super) struct SchedAttr {
        size: u32,
        policy: u32,
        flags: u64,
        nice: i32,
        priority: u32,
        pub(super) runtime: u64,
        deadline: u64,
        period: u64,
    }

    const SCHED_OTHER: u32 = 0;

    pub(super) fn get_attr() -> Option<SchedAttr> {
        let mut attr = SchedAttr::default();
        let size = std::mem::size_of::<SchedAttr>() as u32;
        // SAFETY: `attr` is a valid, writable sched_attr of `size` bytes; pid 0 is the
        // calling thread.
        let r = unsafe {
            libc::syscall(
                libc::SYS_sched_getattr,
                0,
                &mut attr as *mut SchedAttr,
                size,
                0,
            )
        };
        (r == 0).then_some(attr)
    }

    pub(super) fn set_attr(attr: &SchedAttr) -> bool {
        let mut attr = *attr;
        attr.size = std::mem::size_of::<SchedAttr>() as u32;
        // SAFETY: `attr` is a valid sched_attr whose size field is its size; pid 0 is
        // the calling thread.
        unsafe { libc::syscall(libc::SYS_sched_setattr, 0, &attr as *const SchedAttr, 0) == 0 }
    }

    /// Set the calling SCHED_OTHER thread's slice; the attributes before, if it took.
    pub(super) fn set_slice(slice: Duration) -> Option<SchedAttr> {
        let before = get_attr()?;
        if before.policy != SCHED_OTHER {
            return None;
        }
        let attr = SchedAttr {
            runtime: slice.as_nanos().min(u64::MAX as u128) as u64,
            flags: 0,
            ..before
        };
        // Runtime 0 is "the kernel's default slice" when the hint is dropped.
        let default = SchedAttr {
            runtime: 0,
            flags: 0,
            ..before
        };
        if !set_attr(&attr) {
            return None;
        }
        // Kernels before 6.12 accept the call and ignore the runtime of SCHED_OTHER.
        if get_attr().is_some_and(|now| now.runtime == attr.runtime) {
            Some(default)
        } else {
            set_attr(&default);
            None
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_hint_is_undone_when_dropped() {
        let before = linux_runtime();
        if before.is_some_and(|r| r < 1_000_000) {
            return; // someone gave this test thread a slice of its own already
        }
        {
            let hint = SliceHint::request(Some(Duration::from_micros(200)));
            if hint.applied() {
                assert_eq!(linux_runtime(), Some(200_000));
            }
        }
        assert_eq!(linux_runtime(), before);
        assert!(!SliceHint::request(None).applied());
    }

    #[cfg(target_os = "linux")]
    fn linux_runtime() -> Option<u64> {
        linux::get_attr().map(|a| a.runtime)
    }

    #[cfg(not(target_os = "linux"))]
    fn linux_runtime() -> Option<u64> {
        None
    }
}
