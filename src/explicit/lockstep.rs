//! Two threads in lock-step for the explicit pair's phases.
//!
//! A pair step hands work to a second thread three times: the two gears' drifts, the two
//! gears' element forces with the contact beside them, and the two gears' accelerations;
//! a few hundred microseconds a step, 1.5 million steps a run. With `rayon::join` the second
//! task went to a pool worker that had fallen asleep in the step's serial middle (rayon's
//! workers sleep after about 32 idle yields), and waking it was a system call at every join:
//! 40 s of system time in a 116 s run (validation/performance, "The threads' wake-ups").
//! [`Lockstep`] keeps one partner thread for the integrator's lifetime that waits for its next
//! task by spinning, then yielding, and parks only after a pause far longer than a step, so a
//! hand-over in the time loop costs two cache-line transfers instead of a wake-up.
//!
//! The arithmetic of each task is the same whichever thread runs it, so results stay
//! byte-identical across thread counts; with one thread ([`Lockstep::for_current_pool`] in a
//! one-thread rayon pool, `RAYON_NUM_THREADS=1`) the two tasks run one after the other.

use std::any::Any;
use std::cell::UnsafeCell;
use std::panic::{catch_unwind, resume_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicBool, AtomicU8, Ordering};
use std::sync::Arc;
use std::thread::{self, JoinHandle};
use std::time::{Duration, Instant};

/// Pure spinning before a waiting thread starts to yield its core. Yielding keeps the thread
/// awake (no wake-up system call when the next task comes), and gives the core away where
/// more threads than cores run (tests side by side): with 200 µs of pure spinning
/// tests/explicit_pair.rs took 190 s against 140 s, and a run alone was no faster.
const SPIN: Duration = Duration::from_micros(20);
/// Yielding before the partner parks: a pause this long is not the time loop (a checkpoint,
/// a history write, a stability check, the end of the run).
const YIELD: Duration = Duration::from_millis(5);

const IDLE: u8 = 0;
const POSTED: u8 = 1;
const DONE: u8 = 2;
const STOP: u8 = 3;

/// A task with its lifetime erased; valid from POSTED until the partner sets DONE.
type Task = *mut (dyn FnMut() + Send + 'static);

/// State shared by the owner and its partner. The owner writes `task` only while the state is
/// IDLE and the partner reads it only after POSTED; the partner writes `panic` only before
/// DONE and the owner reads it only after: the state's release/acquire pairs order them.
struct Shared {
    state: AtomicU8,
    task: UnsafeCell<Option<Task>>,
    panic: UnsafeCell<Option<Box<dyn Any + Send>>>,
    partner_parked: AtomicBool,
}

// SAFETY: the cells are accessed only under the hand-over protocol above (one side at a time),
// and the task they carry is `Send` (checked where `join` makes it), so calling it on the
// partner is allowed.
unsafe impl Sync for Shared {}
unsafe impl Send for Shared {}

/// The partner thread and its hand-over.
struct Partner {
    shared: Arc<Shared>,
    thread: Option<JoinHandle<()>>,
}

/// Runs two tasks side by side, the second on a persistent partner thread (or one after the
/// other without one).
pub struct Lockstep {
    partner: Option<Partner>,
}

impl Lockstep {
    /// A partner thread when the current rayon pool has two threads or more, none otherwise.
    pub fn for_current_pool() -> Self {
        if rayon::current_num_threads() >= 2 {
            Self::with_partner()
        } else {
            Self::serial()
        }
    }

    /// Both tasks on the calling thread, one after the other.
    pub fn serial() -> Self {
        Lockstep { partner: None }
    }

    /// A partner thread, whatever the pool.
    pub fn with_partner() -> Self {
        let shared = Arc::new(Shared {
            state: AtomicU8::new(IDLE),
            task: UnsafeCell::new(None),
            panic: UnsafeCell::new(None),
            partner_parked: AtomicBool::new(false),
        });
        let theirs = Arc::clone(&shared);
        let thread = thread::Builder::new()
            .name("geardyn-lockstep".into())
            .spawn(move || partner_loop(&theirs));
        match thread {
            Ok(thread) => Lockstep {
                partner: Some(Partner {
                    shared,
                    thread: Some(thread),
                }),
            },
            // No thread to be had: the same results, one task after the other.
            Err(_) => Self::serial(),
        }
    }

    /// Whether the tasks run on two threads.
    pub fn is_parallel(&self) -> bool {
        self.partner.is_some()
    }

    /// Runs `a` here and `b` on the partner, and returns when both are done. A panic in either
    /// is resumed here after both have finished (the tasks borrow the caller's data).
    pub fn join<RA, RB>(
        &mut self,
        a: impl FnOnce() -> RA,
        b: impl FnOnce() -> RB + Send,
    ) -> (RA, RB)
    where
        RB: Send,
    {
        let Some(partner) = &mut self.partner else {
            let ra = a();
            return (ra, b());
        };
        let shared = &*partner.shared;
        let mut b = Some(b);
        let mut rb: Option<RB> = None;
        let mut call = || rb = b.take().map(|b| b());
        let task: *mut (dyn FnMut() + Send + '_) = &mut call;
        // SAFETY: only the lifetime is erased. The partner calls the task between POSTED and
        // DONE, and this function does not return (nor unwind: `a` runs under catch_unwind)
        // before it has seen DONE, so every borrow the task holds outlives its use.
        let task: Task = unsafe { std::mem::transmute(task) };
        // SAFETY: the state is IDLE (every join ends there), so the partner does not read the
        // cell now.
        unsafe { *shared.task.get() = Some(task) };
        shared.state.store(POSTED, Ordering::SeqCst);
        // With the store above, SeqCst on both sides: either the partner sees POSTED before it
        // parks, or this sees it parked and unparks it (an unpark before the park is kept).
        if shared.partner_parked.load(Ordering::SeqCst) {
            if let Some(thread) = &partner.thread {
                thread.thread().unpark();
            }
        }
        let ra = catch_unwind(AssertUnwindSafe(a));
        wait(&shared.state, |s| s == DONE, None);
        // SAFETY: after DONE the partner no longer touches the cells.
        let panic = unsafe { (*shared.panic.get()).take() };
        unsafe { *shared.task.get() = None };
        shared.state.store(IDLE, Ordering::Release);
        match (ra, panic) {
            (Err(payload), _) | (Ok(_), Some(payload)) => resume_unwind(payload),
            (Ok(ra), None) => (ra, rb.expect("the partner ran the task")),
        }
    }
}

impl Drop for Partner {
    fn drop(&mut self) {
        self.shared.state.store(STOP, Ordering::SeqCst);
        if let Some(thread) = self.thread.take() {
            thread.thread().unpark();
            // A panicking task was already reported through `join`.
            let _ = thread.join();
        }
    }
}

fn partner_loop(shared: &Shared) {
    loop {
        let state = wait(
            &shared.state,
            |s| s == POSTED || s == STOP,
            Some(&shared.partner_parked),
        );
        if state == STOP {
            return;
        }
        // SAFETY: POSTED: the owner has written the task and waits for DONE before it reuses
        // the cell or lets the task's borrows go.
        let task = unsafe { (*shared.task.get()).expect("a posted task") };
        // SAFETY: the task is alive until DONE (see `join`).
        let result = catch_unwind(AssertUnwindSafe(|| unsafe { (*task)() }));
        if let Err(payload) = result {
            // SAFETY: the owner reads the cell only after DONE.
            unsafe { *shared.panic.get() = Some(payload) };
        }
        shared.state.store(DONE, Ordering::Release);
    }
}

/// Waits until `ready(state)`: spins for [`SPIN`], then yields, and with a `parked` flag parks
/// after [`YIELD`] (the flag tells the owner to unpark). Returns the state that ended the wait.
fn wait(state: &AtomicU8, ready: impl Fn(u8) -> bool, parked: Option<&AtomicBool>) -> u8 {
    let start = Instant::now();
    let mut round = 0u32;
    loop {
        let s = state.load(Ordering::Acquire);
        if ready(s) {
            return s;
        }
        round = round.wrapping_add(1);
        if !round.is_multiple_of(64) {
            std::hint::spin_loop();
            continue;
        }
        let waited = start.elapsed();
        if waited < SPIN {
            std::hint::spin_loop();
        } else if waited < YIELD || parked.is_none() {
            thread::yield_now();
        } else if let Some(flag) = parked {
            flag.store(true, Ordering::SeqCst);
            if !ready(state.load(Ordering::SeqCst)) {
                thread::park_timeout(Duration::from_millis(100));
            }
            flag.store(false, Ordering::SeqCst);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Both tasks run, each once, the second on the partner thread; their results come back,
    /// and the partner's writes to the caller's data are seen after the join; many joins in a
    /// row with pauses long enough to park the partner in between. Without a partner both run
    /// here.
    #[test]
    fn joins_run_both_tasks_and_return_their_results() {
        for (mut lockstep, parallel) in [
            (Lockstep::with_partner(), true),
            (Lockstep::serial(), false),
        ] {
            assert_eq!(lockstep.is_parallel(), parallel);
            let here = thread::current().id();
            let mut left = vec![0u64; 1000];
            let mut right = vec![0u64; 1000];
            for round in 0..2000u64 {
                let (a, (b, there)) = lockstep.join(
                    || {
                        left.iter_mut().for_each(|v| *v += round);
                        left[0]
                    },
                    || {
                        right.iter_mut().for_each(|v| *v += 2 * round);
                        (right[999], thread::current().id())
                    },
                );
                assert_eq!((a, b), (left[0], right[999]));
                assert_eq!(there != here, parallel, "round {round}");
                if round % 500 == 0 {
                    thread::sleep(YIELD + Duration::from_millis(2));
                }
            }
            let sum: u64 = (0..2000).sum();
            assert!(left.iter().all(|&v| v == sum));
            assert!(right.iter().all(|&v| v == 2 * sum));
        }
    }

    /// A panic on either side reaches the caller only after both tasks are done (the partner's
    /// slow task has finished writing the caller's data when the panic arrives), and the
    /// partner takes the next task.
    #[test]
    fn a_panic_is_resumed_by_the_caller_after_both_tasks() {
        let mut lockstep = Lockstep::with_partner();
        let mut ran = false;
        let caught = catch_unwind(AssertUnwindSafe(|| {
            lockstep.join(|| ran = true, || panic!("partner task failed"))
        }));
        assert!(ran);
        let payload = caught.expect_err("the panic reaches the caller");
        assert_eq!(payload.downcast_ref::<&str>(), Some(&"partner task failed"));
        let mut written = false;
        let caught = catch_unwind(AssertUnwindSafe(|| {
            lockstep.join(
                || panic!("caller task failed"),
                || {
                    thread::sleep(Duration::from_millis(30));
                    written = true;
                },
            )
        }));
        let payload = caught.expect_err("the panic reaches the caller");
        assert_eq!(payload.downcast_ref::<&str>(), Some(&"caller task failed"));
        assert!(
            written,
            "the join unwound before the partner's task was done"
        );
        assert_eq!(lockstep.join(|| 1, || 2), (1, 2));
    }
}
