//! Keeping the processes of a multi-process run on one core.
//!
//! In lockstep only one process of a run computes at a time, and every control step
//! hands the turn on six times. When the next process sits on another core, each hand-
//! off is a cross-core wake-up (an interrupt to that core, on a VM an exit to the
//! hypervisor when it idles) and the woken process finds cold caches; on one core it is
//! a plain context switch. Measured on the shared 2-core machine at load ~4
//! (BENCHMARKS.md), multi-process / in-process wall: MuJoCo 1.23x pinned vs 1.28x not
//! (11 alternating rounds, full route), rapier 1.07x vs 1.33x (3 rounds, 60 s). Linux
//! only; elsewhere nothing is pinned.

/// The calling thread's CPU set before it was pinned; restored on drop. Processes and
/// threads the thread starts meanwhile inherit the pin (a thread pool first used
/// during a pinned run stays on that core).
#[derive(Debug)]
pub struct CorePin {
    #[cfg(target_os = "linux")]
    previous: Option<libc::cpu_set_t>,
    core: Option<usize>,
}

impl CorePin {
    /// Pin the calling thread to the core it runs on now (if `enabled`).
    pub fn here(enabled: bool) -> Self {
        #[cfg(target_os = "linux")]
        if enabled && let Some((previous, core)) = linux::pin_here() {
            return Self {
                previous: Some(previous),
                core: Some(core),
            };
        }
        let _ = enabled;
        Self {
            #[cfg(target_os = "linux")]
            previous: None,
            core: None,
        }
    }

    /// The core the thread (and what it spawns) is pinned to, if pinned.
    pub fn core(&self) -> Option<usize> {
        self.core
    }
}

impl Drop for CorePin {
    fn drop(&mut self) {
        #[cfg(target_os = "linux")]
        if let Some(previous) = self.previous.take() {
            linux::set(&previous);
        }
    }
}

#[cfg(target_os = "linux")]
mod linux {
    fn get() -> Option<libc::cpu_set_t> {
        // SAFETY: an all-zero cpu_set_t is a valid empty set; the kernel writes at most
        // its size; pid 0 is the calling thread.
        unsafe {
            let mut set: libc::cpu_set_t = std::mem::zeroed();
            (libc::sched_getaffinity(0, std::mem::size_of::<libc::cpu_set_t>(), &mut set) == 0)
                .then_some(set)
        }
    }

    pub(super) fn set(set: &libc::cpu_set_t) -> bool {
        // SAFETY: `set` is a valid cpu_set_t of the given size; pid 0 is the calling
        // thread.
        unsafe { libc::sched_setaffinity(0, std::mem::size_of::<libc::cpu_set_t>(), set) == 0 }
    }

    /// Pin the calling thread to its current core; the set before and the core.
    pub(super) fn pin_here() -> Option<(libc::cpu_set_t, usize)> {
        let previous = get()?;
        // SAFETY: sched_getcpu has no preconditions.
        let core = usize::try_from(unsafe { libc::sched_getcpu() }).ok()?;
        if core >= libc::CPU_SETSIZE as usize {
            return None;
        }
        // SAFETY: as in `get`; `core` is below CPU_SETSIZE.
        let one = unsafe {
            let mut one: libc::cpu_set_t = std::mem::zeroed();
            libc::CPU_SET(core, &mut one);
            one
        };
        set(&one).then_some((previous, core))
    }

    #[cfg(test)]
    pub(super) fn allowed() -> Option<usize> {
        // SAFETY: CPU_COUNT reads a valid set.
        get().map(|s| unsafe { libc::CPU_COUNT(&s) } as usize)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_pin_holds_one_core_and_is_undone_when_dropped() {
        #[cfg(target_os = "linux")]
        {
            let before = linux::allowed();
            {
                let pin = CorePin::here(true);
                if pin.core().is_some() {
                    assert_eq!(linux::allowed(), Some(1));
                }
            }
            assert_eq!(linux::allowed(), before);
        }
        assert_eq!(CorePin::here(false).core(), None);
    }
}
