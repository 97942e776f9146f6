//! Runs a machine's SPUs quantum by quantum on several host threads. A quantum is short
//! (tens of microseconds of host work per SPU), so the threads live for the whole run and
//! meet at each quantum's end on atomics: a thread that finished its share spins briefly
//! for the others, then sleeps until woken. The calling thread runs a share itself and,
//! between quanta, has every SPU and main memory to itself.
//!
//! Each SPU reads main memory and keeps its writes during a quantum, so how the SPUs are
//! spread over threads changes no result. A panic on any thread ends every thread and goes
//! on from the caller, as with one thread, rather than leaving the others waiting.

use std::any::Any;
use std::cell::UnsafeCell;
use std::panic::{catch_unwind, resume_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::sync::Mutex;
use std::thread::Thread;
use std::time::{Duration, Instant};

use spu_isa::machine::{MainMemory, Spu, StopReason};

/// What to do after a quantum (or before the first).
pub enum Next {
    /// Run the SPUs marked `true` until cycle `until`.
    Run {
        until: u64,
        running: Vec<bool>,
    },
    Done,
}

/// How long a thread that finished its share waits awake for the others: spinning, then
/// yielding. A sleeping thread takes tens of microseconds to wake (longer in a virtual
/// machine), as long as a quantum's work; these were the fastest of the values tried
/// for 2 and 16 SPEs on 2 host threads (docs/timing.md).
const SPIN: Duration = Duration::from_micros(10);
const YIELD: Duration = Duration::from_micros(500);

/// Runs quanta until `next` says done. `next` gets the SPUs, main memory and each SPU's
/// outcome of the quantum just run (`None` before the first), applies the quantum and
/// says what comes next. `threads` host threads (the caller's among them) share the
/// running SPUs: each takes the next SPU not taken yet in the quantum until none is left,
/// so a thread whose SPUs ran fast takes more of them.
pub fn run_quanta<E>(
    spus: &mut [Spu],
    memory: &mut MainMemory,
    threads: usize,
    mut next: impl FnMut(
        &mut [Spu],
        &mut MainMemory,
        Option<Vec<Option<StopReason>>>,
    ) -> Result<Next, E>,
) -> Result<(), E> {
    let helpers = threads.clamp(1, spus.len().max(1)) - 1;
    let mut plan = next(spus, memory, None)?;
    if helpers == 0 {
        while let Next::Run { until, running } = plan {
            let outcomes = spus
                .iter_mut()
                .zip(&running)
                .map(|(spu, &run)| {
                    if run {
                        spu.run_quantum(memory, until)
                    } else {
                        None
                    }
                })
                .collect();
            plan = next(spus, memory, Some(outcomes))?;
        }
        return Ok(());
    }
    let shared = Shared {
        spus: spus.as_mut_ptr(),
        count: spus.len(),
        memory: memory as *mut MainMemory,
        slots: (0..spus.len()).map(|_| Slot::default()).collect(),
        quantum: AtomicU64::new(0),
        until: AtomicU64::new(0),
        quit: AtomicBool::new(false),
        pending: AtomicUsize::new(0),
        next_spu: AtomicUsize::new(0),
        main: std::thread::current(),
        panicked: Mutex::new(None),
    };
    std::thread::scope(|scope| {
        let handles: Vec<Thread> = (0..helpers)
            .map(|_| {
                let shared = &shared;
                scope.spawn(move || shared.helper()).thread().clone()
            })
            .collect();
        let result = catch_unwind(AssertUnwindSafe(|| {
            while let Next::Run { until, running } = plan {
                let outcomes = shared.quantum(until, &running, &handles);
                // SAFETY: every helper finished the quantum; until the next one the
                // SPUs and memory are this thread's alone.
                let (spus, memory) = unsafe { shared.all() };
                plan = next(spus, memory, Some(outcomes))?;
            }
            Ok(())
        }));
        shared.quit.store(true, Ordering::Release);
        for t in &handles {
            t.unpark();
        }
        result.unwrap_or_else(|panic| resume_unwind(panic))
    })
}

/// One SPU's share of a quantum, handed from the caller to the thread running it.
#[derive(Default)]
struct Slot {
    run: UnsafeCell<bool>,
    outcome: UnsafeCell<Option<StopReason>>,
}

/// What the threads share. Phases alternate: during a quantum, a thread touches only the
/// SPUs it took from `next_spu` (and their slots), and memory only to read it; between
/// quanta, only the caller touches anything. The `quantum` counter (release, acquire)
/// opens a quantum, `pending` reaching 0 (release, acquire) closes it.
struct Shared {
    spus: *mut Spu,
    count: usize,
    memory: *mut MainMemory,
    slots: Vec<Slot>,
    quantum: AtomicU64,
    until: AtomicU64,
    quit: AtomicBool,
    /// Helpers still running the current quantum.
    pending: AtomicUsize,
    /// The next SPU a thread takes in the current quantum.
    next_spu: AtomicUsize,
    main: Thread,
    /// A helper's panic, for the caller to go on with.
    panicked: Mutex<Option<Box<dyn Any + Send>>>,
}

// SAFETY: the raw SPU pointer and the cells are only used under the phase protocol above.
unsafe impl Sync for Shared {}
unsafe impl Send for Shared {}

impl Shared {
    /// Runs one quantum on all threads; the outcomes of the SPUs that ran.
    fn quantum(&self, until: u64, running: &[bool], helpers: &[Thread]) -> Vec<Option<StopReason>> {
        for (slot, &run) in self.slots.iter().zip(running) {
            // SAFETY: between quanta the caller alone touches the slots.
            unsafe {
                *slot.run.get() = run;
                *slot.outcome.get() = None;
            }
        }
        self.until.store(until, Ordering::Relaxed);
        self.pending.store(helpers.len(), Ordering::Relaxed);
        self.next_spu.store(0, Ordering::Relaxed);
        self.quantum.fetch_add(1, Ordering::Release);
        for t in helpers {
            t.unpark();
        }
        // SAFETY: thread 0's share, during the quantum.
        unsafe { self.run_share(until) };
        wait_until(|| self.pending.load(Ordering::Acquire) == 0);
        if let Some(panic) = self
            .panicked
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .take()
        {
            resume_unwind(panic);
        }
        self.slots
            .iter()
            // SAFETY: the quantum is over.
            .map(|slot| unsafe { (*slot.outcome.get()).take() })
            .collect()
    }

    /// Runs SPUs not taken yet in the quantum until none is left.
    ///
    /// # Safety
    /// Only during a quantum.
    unsafe fn run_share(&self, until: u64) {
        // SAFETY: during a quantum memory is only read.
        let memory = unsafe { &*self.memory };
        loop {
            let i = self.next_spu.fetch_add(1, Ordering::Relaxed);
            if i >= self.count {
                break;
            }
            let slot = &self.slots[i];
            // SAFETY: SPU `i` and its slot are this thread's during the quantum: it took
            // `i` from `next_spu`, which hands each index out once per quantum.
            unsafe {
                if *slot.run.get() {
                    *slot.outcome.get() = (*self.spus.add(i)).run_quantum(memory, until);
                }
            }
        }
    }

    /// A helper thread: each quantum, its share.
    fn helper(&self) {
        let mut seen = 0;
        loop {
            wait_until(|| {
                self.quit.load(Ordering::Acquire) || self.quantum.load(Ordering::Acquire) != seen
            });
            if self.quit.load(Ordering::Acquire) {
                return;
            }
            seen = self.quantum.load(Ordering::Acquire);
            let until = self.until.load(Ordering::Relaxed);
            // SAFETY: a quantum is open.
            let run = catch_unwind(AssertUnwindSafe(|| unsafe { self.run_share(until) }));
            if let Err(panic) = run {
                *self.panicked.lock().unwrap_or_else(|e| e.into_inner()) = Some(panic);
            }
            if self.pending.fetch_sub(1, Ordering::AcqRel) == 1 {
                self.main.unpark();
            }
        }
    }

    /// Every SPU and main memory.
    ///
    /// # Safety
    /// Only between quanta, by the caller.
    #[allow(clippy::mut_from_ref)]
    unsafe fn all(&self) -> (&mut [Spu], &mut MainMemory) {
        // SAFETY: as the caller promises.
        unsafe {
            (
                std::slice::from_raw_parts_mut(self.spus, self.count),
                &mut *self.memory,
            )
        }
    }
}

/// Waits until `done` holds: spinning for [`SPIN`], then yielding the processor until
/// [`YIELD`] (another thread of this process, the block compiler's say, may want it),
/// then sleeping until unparked (the thread that makes `done` hold unparks the waiter; a
/// spurious or timed-out wake-up just looks again).
fn wait_until(done: impl Fn() -> bool) {
    let start = Instant::now();
    let mut spins = 0u32;
    while !done() {
        spins += 1;
        if spins < 64 {
            std::hint::spin_loop();
            continue;
        }
        let waited = start.elapsed();
        if waited < SPIN {
            std::hint::spin_loop();
        } else if waited < YIELD {
            std::thread::yield_now();
        } else {
            std::thread::park_timeout(Duration::from_millis(1));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A panic between quanta (here in `next`) ends the helper threads and reaches the
    /// caller, instead of leaving them waiting for the next quantum.
    #[test]
    fn a_panic_between_quanta_ends_every_thread() {
        let (done, finished) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            let mut spus: Vec<Spu> = (0..3).map(Spu::new).collect();
            let mut memory = MainMemory::zeroed(4096);
            let mut quanta = 0;
            let result = catch_unwind(AssertUnwindSafe(|| {
                run_quanta(&mut spus, &mut memory, 3, |_, _, outcomes| {
                    if outcomes.is_some() {
                        quanta += 1;
                        if quanta == 2 {
                            panic!("between quanta");
                        }
                    }
                    Ok::<_, ()>(Next::Run {
                        until: 100 * (quanta + 1),
                        running: vec![true; 3],
                    })
                })
            }));
            let message = result
                .err()
                .and_then(|p| p.downcast_ref::<&str>().map(|s| s.to_string()));
            let _ = done.send((message, quanta));
        });
        let got = finished
            .recv_timeout(Duration::from_secs(30))
            .expect("run_quanta returned (no thread left waiting)");
        assert_eq!(got, (Some("between quanta".to_string()), 2));
    }
}
