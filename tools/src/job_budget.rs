//! Admits `spu paper`'s jobs against a memory budget (issue #35): each thread runs one job
//! at a time, and without a bound sixteen threads hold sixteen frames' main memories,
//! SPEs and outputs at once. A job waits for its turn (jobs are admitted in the order they
//! were taken, so a large one is not passed over by smaller ones) and for its estimated
//! bytes to fit beside those of the jobs in flight and of the scenes kept prepared; a job
//! larger than the whole budget waits until no other job runs and then runs alone. Results
//! do not depend on it: the report is assembled after every job has ended.

use std::sync::{Condvar, Mutex, MutexGuard};

/// The default `--memory-budget`, in MiB: with the prepared scenes and what the estimates
/// leave out, `spu paper` at 1024x1024 then peaks below 2 GB on any thread count
/// (docs/parallel.md, "Peak memory").
pub const DEFAULT_MIB: u64 = 1280;

/// The smallest and largest `--memory-budget` accepted, in MiB.
pub const MIB_RANGE: std::ops::RangeInclusive<u64> = 64..=1 << 30;

/// What every SPE of a frame holds besides main memory, in bytes: its local store and the
/// decoded copy of it, its compiled-block tables, its timing records and profile (a
/// measured upper bound, docs/parallel.md).
pub const SPE_BYTES: u64 = 12 << 20;

/// What a frame holds per pixel beyond the scene: the result blocks and colour buffer in
/// main memory, the decoded colours, the image and its encoding.
pub const PIXEL_BYTES: u64 = 40;

/// What a frame holds whatever its size: the program, the layout, the statistics.
pub const FRAME_BYTES: u64 = 8 << 20;

/// A frame's estimated memory: its main memory holds a copy of the scene's staged image
/// (`scene_bytes`), its pixels' buffers, and each of its SPEs its own state.
pub fn frame_estimate(scene_bytes: u64, pixels: u64, spes: u64) -> u64 {
    scene_bytes
        .saturating_add(pixels.saturating_mul(PIXEL_BYTES))
        .saturating_add(spes.saturating_mul(SPE_BYTES))
        .saturating_add(FRAME_BYTES)
}

/// The bytes admitted and kept, shared by the threads running jobs.
pub struct Budget {
    limit: u64,
    state: Mutex<State>,
    changed: Condvar,
}

#[derive(Debug, Default)]
struct State {
    /// The ticket admitted next.
    turn: usize,
    /// Bytes of the jobs in flight and how many they are.
    in_flight: u64,
    jobs: usize,
    /// Bytes of the scenes kept prepared.
    kept: u64,
    /// The most bytes ever in flight and kept at once, and whether a job ran alone past
    /// the budget (for the tests and the closing note).
    most: u64,
    alone: usize,
    /// The tickets in the order they were admitted.
    #[cfg(test)]
    order: Vec<usize>,
}

/// A job in flight: its bytes go back to the budget when it is dropped.
pub struct Admission<'a> {
    budget: &'a Budget,
    bytes: u64,
}

impl Drop for Admission<'_> {
    fn drop(&mut self) {
        // The job's memory is free now; give it back to the system before the next job
        // is admitted in its place.
        return_free_memory();
        let mut state = self.budget.lock();
        state.in_flight -= self.bytes;
        state.jobs -= 1;
        drop(state);
        self.budget.changed.notify_all();
    }
}

/// Hands the allocator's free pages back to the system. glibc keeps what a thread freed in
/// that thread's arena for its next allocations: sixteen threads would each keep their
/// largest job's timing records and SPE state, beside the jobs the budget admits, and the
/// process would grow past the budget (docs/parallel.md, "Peak memory").
fn return_free_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: malloc_trim takes no pointer and may be called at any time from any thread;
    // it only returns unused pages of glibc's arenas to the kernel.
    unsafe {
        libc::malloc_trim(0);
    }
}

impl Budget {
    /// A budget of `limit` bytes.
    pub fn new(limit: u64) -> Budget {
        Budget {
            limit,
            state: Mutex::new(State::default()),
            changed: Condvar::new(),
        }
    }

    fn lock(&self) -> MutexGuard<'_, State> {
        // a thread that panicked holding it left counts that are still whole
        self.state.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Waits until it is `ticket`'s turn (tickets 0, 1, 2 ... are admitted in order, each
    /// exactly once) and `bytes` fit beside the jobs in flight and the scenes kept, or no
    /// job is in flight; then holds `bytes` until the admission is dropped.
    pub fn admit(&self, ticket: usize, bytes: u64) -> Admission<'_> {
        let mut state = self.lock();
        loop {
            if state.turn == ticket {
                let fits = state
                    .in_flight
                    .saturating_add(state.kept)
                    .saturating_add(bytes)
                    <= self.limit;
                if fits || state.jobs == 0 {
                    state.turn += 1;
                    state.in_flight += bytes;
                    state.jobs += 1;
                    state.most = state.most.max(state.in_flight + state.kept);
                    state.alone += !fits as usize;
                    #[cfg(test)]
                    state.order.push(ticket);
                    drop(state);
                    self.changed.notify_all();
                    return Admission {
                        budget: self,
                        bytes,
                    };
                }
            }
            state = self.changed.wait(state).unwrap_or_else(|e| e.into_inner());
        }
    }

    /// A scene of `bytes` is kept prepared from now on (counted against the budget).
    pub fn keep(&self, bytes: u64) {
        let mut state = self.lock();
        state.kept = state.kept.saturating_add(bytes);
        state.most = state.most.max(state.in_flight + state.kept);
    }

    /// A scene of `bytes` kept before is no longer.
    pub fn release(&self, bytes: u64) {
        self.lock().kept -= bytes;
        self.changed.notify_all();
    }

    /// The budget in bytes.
    pub fn limit(&self) -> u64 {
        self.limit
    }

    /// The most bytes that were in flight and kept at once so far.
    pub fn most(&self) -> u64 {
        self.lock().most
    }

    /// The jobs that ran alone because they were larger than the budget.
    pub fn ran_alone(&self) -> usize {
        self.lock().alone
    }
}

/// `--memory-budget MIB` in bytes, checked: bad input (exit status 2) before any work.
pub fn parse_mib(mib: u64) -> Result<u64, String> {
    if !MIB_RANGE.contains(&mib) {
        return Err(format!(
            "--memory-budget {mib}: must be {} to {} MiB",
            MIB_RANGE.start(),
            MIB_RANGE.end()
        ));
    }
    Ok(mib << 20)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::{AtomicUsize, Ordering};

    /// Runs jobs of `sizes` on `threads` threads against `budget`, each job holding its
    /// admission a while; returns the largest bytes ever in flight, seen by the jobs
    /// themselves, and the order the budget admitted them in.
    fn run(sizes: &[u64], threads: usize, budget: &Budget) -> (u64, Vec<usize>) {
        let next = AtomicUsize::new(0);
        let in_flight = Mutex::new(0u64);
        let most = Mutex::new(0u64);
        std::thread::scope(|scope| {
            for _ in 0..threads {
                scope.spawn(|| loop {
                    let ticket = next.fetch_add(1, Ordering::Relaxed);
                    let Some(&bytes) = sizes.get(ticket) else {
                        break;
                    };
                    let admission = budget.admit(ticket, bytes);
                    let now = {
                        let mut f = in_flight.lock().unwrap();
                        *f += bytes;
                        *f
                    };
                    {
                        let mut m = most.lock().unwrap();
                        *m = (*m).max(now);
                    }
                    if bytes > budget.limit() {
                        assert_eq!(now, bytes, "a job over the budget runs alone");
                    }
                    std::thread::yield_now();
                    *in_flight.lock().unwrap() -= bytes;
                    drop(admission);
                });
            }
        });
        let order = std::mem::take(&mut budget.lock().order);
        (most.into_inner().unwrap(), order)
    }

    #[test]
    fn never_more_than_the_budget_in_flight_but_a_lone_big_job() {
        let sizes = [
            30, 50, 20, 70, 10, 10, 10, 60, 40, 40, 5, 95, 25, 25, 25, 25,
        ];
        for threads in [1, 2, 3, 8, 16] {
            let budget = Budget::new(100);
            let (most, order) = run(&sizes, threads, &budget);
            assert!(most <= 100, "{threads} threads: {most} in flight");
            assert!(budget.most() <= 100, "{threads} threads");
            // admitted in the order taken: none passed over
            assert_eq!(order, (0..sizes.len()).collect::<Vec<_>>(), "{threads}");
            assert_eq!(budget.ran_alone(), 0);
        }
    }

    #[test]
    fn a_job_larger_than_the_budget_runs_alone_and_the_others_still_run() {
        let sizes = [40, 40, 250, 40, 40, 100, 101, 40];
        for threads in [1, 2, 4, 16] {
            let budget = Budget::new(100);
            let (most, order) = run(&sizes, threads, &budget);
            // the lone jobs are the largest in flight; the others kept within the budget
            assert_eq!(most, 250, "{threads} threads");
            assert_eq!(budget.ran_alone(), 2, "{threads} threads");
            assert_eq!(order, (0..sizes.len()).collect::<Vec<_>>());
        }
    }

    #[test]
    fn kept_scenes_count_against_the_budget() {
        let budget = Budget::new(100);
        budget.keep(60);
        // 60 kept: one job of 30 at a time
        let (most, order) = run(&[30, 30, 30, 30], 4, &budget);
        assert_eq!((most, budget.most(), order), (30, 90, vec![0, 1, 2, 3]));
        budget.release(60);
        let (most, _) = run(&[30, 30, 30, 30], 4, &Budget::new(100));
        assert!(most <= 90);
        let _first = budget.admit(4, 50);
        let _second = budget.admit(5, 50);
        assert_eq!((budget.most(), budget.ran_alone()), (100, 0));
    }

    #[test]
    fn the_budget_option_is_checked() {
        assert_eq!(parse_mib(1536), Ok(1536 << 20));
        assert_eq!(parse_mib(64), Ok(64 << 20));
        assert_eq!(
            parse_mib(0).unwrap_err(),
            "--memory-budget 0: must be 64 to 1073741824 MiB"
        );
        assert_eq!(
            parse_mib(63).unwrap_err(),
            "--memory-budget 63: must be 64 to 1073741824 MiB"
        );
        assert!(parse_mib((1 << 30) + 1).is_err());
    }

    #[test]
    fn a_frame_is_estimated_from_its_scene_pixels_and_spes() {
        assert_eq!(
            frame_estimate(1000, 16, 2),
            1000 + 16 * PIXEL_BYTES + 2 * SPE_BYTES + FRAME_BYTES
        );
        assert_eq!(frame_estimate(u64::MAX, 1, 1), u64::MAX);
    }
}
