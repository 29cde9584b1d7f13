//! 1000 instantiate/free cycles through the C entry points leak nothing: the test
//! binary counts every byte its global allocator hands out and takes back (the FMU
//! code is linked in, so every allocation it makes is counted), and the live count
//! must come back to where it was. Full cycles (initialisation builds the whole
//! lockstep: planner, controller, rapier world) and refused calls are included.
//! Run alone in its own binary so no other test allocates meanwhile.

use std::alloc::{GlobalAlloc, Layout, System};
use std::ffi::{CString, c_int};
use std::sync::atomic::{AtomicIsize, Ordering};

use plamo_fmu::ffi::*;

struct Counting;

static LIVE: AtomicIsize = AtomicIsize::new(0);

// SAFETY: forwards to the system allocator and only counts sizes.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, l: Layout) -> *mut u8 {
        LIVE.fetch_add(l.size() as isize, Ordering::SeqCst);
        // SAFETY: same layout contract as the caller's.
        unsafe { System.alloc(l) }
    }
    unsafe fn dealloc(&self, p: *mut u8, l: Layout) {
        LIVE.fetch_sub(l.size() as isize, Ordering::SeqCst);
        // SAFETY: p was allocated by `alloc` with layout l.
        unsafe { System.dealloc(p, l) }
    }
    unsafe fn alloc_zeroed(&self, l: Layout) -> *mut u8 {
        LIVE.fetch_add(l.size() as isize, Ordering::SeqCst);
        // SAFETY: as in alloc.
        unsafe { System.alloc_zeroed(l) }
    }
    unsafe fn realloc(&self, p: *mut u8, l: Layout, new: usize) -> *mut u8 {
        LIVE.fetch_add(new as isize - l.size() as isize, Ordering::SeqCst);
        // SAFETY: p was allocated with layout l.
        unsafe { System.realloc(p, l, new) }
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

const CO_SIMULATION: c_int = 1;

/// One instance's life: instantiate, optionally initialise and step `steps` times
/// (1/30 s each), with a few refused calls on the way, then free.
fn cycle(name: &CString, guid: &CString, steps: usize) {
    // SAFETY: valid NUL-terminated strings; null callbacks and resource location are
    // accepted by plamo's fmi2Instantiate; the instance is freed once below.
    unsafe {
        let before = LIVE.load(Ordering::SeqCst);
        let c = fmi2Instantiate(
            name.as_ptr(),
            CO_SIMULATION,
            guid.as_ptr(),
            std::ptr::null(),
            std::ptr::null(),
            0,
            0,
        );
        assert!(!c.is_null(), "fmi2Instantiate refused {guid:?}");
        // The counter sees the FMU's own allocations (else this test proves nothing).
        assert!(LIVE.load(Ordering::SeqCst) > before);
        // Refused on the way: wrong state, unknown value reference, NaN input.
        assert_eq!(fmi2DoStep(c, 0.0, 0.1, 1), 3);
        let mut x = 0.0;
        assert_eq!(fmi2GetReal(c, [99_999].as_ptr(), 1, &mut x), 3);
        if steps > 0 {
            assert_eq!(fmi2SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0), 0);
            assert_eq!(fmi2EnterInitializationMode(c), 0);
            assert_eq!(fmi2ExitInitializationMode(c), 0);
            let h = 1.0 / 30.0;
            for k in 0..steps {
                assert_eq!(fmi2DoStep(c, k as f64 * h, h, 1), 0);
            }
            assert_eq!(fmi2Terminate(c), 0);
        }
        fmi2FreeInstance(c);
    }
}

#[test]
fn a_thousand_instantiate_free_cycles_leak_nothing() {
    let name = CString::new("leak-check").unwrap();
    let humanoid = CString::new(plamo_fmu::HUMANOID_GUID).unwrap();
    let planner = CString::new(plamo_fmu::PLANNER_GUID).unwrap();
    // Warm-up: one-time statics (variable tables, built-in scenes, thread-locals).
    cycle(&name, &humanoid, 2);
    cycle(&name, &planner, 2);
    let before = LIVE.load(Ordering::SeqCst);
    for i in 0..1000 {
        let guid = if i % 2 == 0 { &humanoid } else { &planner };
        cycle(&name, guid, 0);
    }
    let after_bare = LIVE.load(Ordering::SeqCst);
    for _ in 0..5 {
        cycle(&name, &humanoid, 3);
        cycle(&name, &planner, 3);
    }
    let after_full = LIVE.load(Ordering::SeqCst);
    assert_eq!(
        after_bare - before,
        0,
        "1000 instantiate/free cycles left {} bytes live",
        after_bare - before
    );
    assert_eq!(
        after_full - after_bare,
        0,
        "10 initialise/step/terminate/free cycles left {} bytes live",
        after_full - after_bare
    );
}
