//! The partner: a thread that owns the second part of the points for the colonization's
//! length and applies the new nodes' updates to it beside the calling thread.
//!
//! A flush hands the partner its nodes and bumps a counter; the partner, which waits on that
//! counter (spinning, then yielding, then parked), updates its grid and lists the changes,
//! which the calling thread applies to the state's per-point arrays in their order. The part
//! stays on one thread, so its grid stays in that core's cache, and a hand-over costs a few
//! cache lines where the pool's scope cost a worker's wake-up (some 10 us an iteration). A
//! flush the partner has not started when the calling thread is done with its own part is
//! done by the calling thread, so a partner kept off its core delays nothing.

use std::sync::atomic::{AtomicBool, AtomicU32, Ordering};
use std::sync::{Arc, Mutex, MutexGuard, PoisonError, TryLockError};
use std::thread::JoinHandle;

use glam::Vec3;

use super::state::Part;

/// Rounds the partner spins for the next flush before it yields its core (some 0.1-0.3 ms:
/// the calling thread's pulls and growth between two flushes of a small tree take some
/// 20-40 us).
const SPIN: u32 = 1 << 12;

/// Rounds the partner then yields before it parks until the next hand-over.
const YIELDS: u32 = 1 << 6;

/// Rounds the calling thread waits for a flush the partner has not started before doing it
/// itself.
const STEAL_AFTER: u32 = 1 << 6;

/// What the partner works on: its part, the nodes of the last hand-over and the changes
/// they made.
pub(super) struct Work {
    pub(super) part: Part,
    nodes: Vec<(u32, Vec3)>,
    influence: f32,
    k2: f32,
    /// The hand-over whose updates were applied last.
    applied: u32,
    /// Each change of the last updates, in order: the point (numbered within the part),
    /// its new nearest node ([`super::state::NONE`]: the point died) and its squared
    /// distance to it.
    pub(super) changes: Vec<(u32, u32, f32)>,
}

impl Work {
    /// Applies the updates of hand-over `flush`, unless they were applied already.
    fn run(&mut self, flush: u32) {
        if self.applied == flush {
            return;
        }
        let Work {
            part,
            nodes,
            influence,
            k2,
            changes,
            ..
        } = self;
        part.update(nodes, *influence, *k2, |i, node, d2| {
            changes.push((i as u32, node, d2));
        });
        self.applied = flush;
    }
}

/// What the calling thread and the partner share. Each thread spins on a line that the
/// other writes once a flush: when the flags shared a line with the work, each change the
/// partner listed took the line from the calling thread's spin (its updates 2-3x slower).
struct Shared {
    asked: Line<Asked>,
    answered: Line<Answered>,
    work: Mutex<Work>,
}

/// A value on cache lines of its own (two: the adjacent-line prefetcher fetches pairs).
#[repr(align(128))]
struct Line<T>(T);

/// What the calling thread writes.
struct Asked {
    /// Hand-overs so far.
    flushes: AtomicU32,
    stop: AtomicBool,
}

/// What the partner writes.
struct Answered {
    /// The last hand-over the partner took up.
    started: AtomicU32,
    /// The last hand-over the partner finished.
    done: AtomicU32,
}

impl Shared {
    /// The work, locked (no one else holds it when the partner is idle; a panic that
    /// poisoned it left it as consistent as the updates it had made).
    fn lock(&self) -> MutexGuard<'_, Work> {
        self.work.lock().unwrap_or_else(PoisonError::into_inner)
    }
}

/// The partner thread and its part; dropping it stops the thread.
pub(super) struct Partner {
    shared: Arc<Shared>,
    thread: Option<JoinHandle<()>>,
}

impl Partner {
    /// Starts a partner for `part`, or gives the part back when no thread can start.
    pub(super) fn start(part: Part) -> Result<Partner, Box<Part>> {
        let shared = Arc::new(Shared {
            asked: Line(Asked {
                flushes: AtomicU32::new(0),
                stop: AtomicBool::new(false),
            }),
            answered: Line(Answered {
                started: AtomicU32::new(0),
                done: AtomicU32::new(0),
            }),
            work: Mutex::new(Work {
                part,
                nodes: Vec::new(),
                influence: 0.0,
                k2: 0.0,
                applied: 0,
                changes: Vec::new(),
            }),
        });
        let theirs = Arc::clone(&shared);
        let thread = std::thread::Builder::new()
            .name("pge-colonize".into())
            .spawn(move || serve(&theirs));
        match thread {
            Ok(thread) => Ok(Partner {
                shared,
                thread: Some(thread),
            }),
            // The closure, and its reference to the part, went with the failed spawn.
            Err(_) => Err(Box::new(into_part(shared))),
        }
    }

    /// The partner's part and work, for the calling thread between flushes.
    pub(super) fn lock(&self) -> MutexGuard<'_, Work> {
        self.shared.lock()
    }

    /// Hands the updates of `nodes` (for the influence radius and the squared kill distance
    /// `k2`) to the partner.
    pub(super) fn hand_over(&self, nodes: &[(u32, Vec3)], influence: f32, k2: f32) {
        {
            let mut work = self.lock();
            work.nodes.clear();
            work.nodes.extend_from_slice(nodes);
            (work.influence, work.k2) = (influence, k2);
            work.changes.clear();
        }
        self.shared.asked.0.flushes.fetch_add(1, Ordering::Release);
        if let Some(thread) = &self.thread {
            thread.thread().unpark();
        }
    }

    /// Waits for the last hand-over's updates, doing them here if the partner has not
    /// started them, and returns the work with their changes.
    pub(super) fn wait(&self) -> MutexGuard<'_, Work> {
        let shared = &*self.shared;
        let flush = shared.asked.0.flushes.load(Ordering::Relaxed);
        let mut round = 0u32;
        loop {
            if shared.answered.0.done.load(Ordering::Acquire) == flush {
                return self.lock();
            }
            if round >= STEAL_AFTER && shared.answered.0.started.load(Ordering::Relaxed) != flush {
                let taken = match shared.work.try_lock() {
                    Ok(work) => Some(work),
                    Err(TryLockError::Poisoned(e)) => Some(e.into_inner()),
                    Err(TryLockError::WouldBlock) => None,
                };
                if let Some(mut work) = taken {
                    work.run(flush);
                    return work;
                }
            }
            round = round.saturating_add(1);
            if round < SPIN {
                std::hint::spin_loop();
            } else {
                std::thread::yield_now();
            }
        }
    }

    /// Stops the partner and takes its part back.
    pub(super) fn end(self) -> Part {
        let shared = Arc::clone(&self.shared);
        drop(self);
        into_part(shared)
    }
}

impl Drop for Partner {
    fn drop(&mut self) {
        self.shared.asked.0.stop.store(true, Ordering::Release);
        if let Some(thread) = self.thread.take() {
            thread.thread().unpark();
            // A partner that panicked has nothing more to say.
            let _ = thread.join();
        }
    }
}

/// The part of a partner whose thread has ended (or never started).
fn into_part(shared: Arc<Shared>) -> Part {
    match Arc::try_unwrap(shared) {
        Ok(shared) => {
            shared
                .work
                .into_inner()
                .unwrap_or_else(PoisonError::into_inner)
                .part
        }
        Err(shared) => shared.lock().part.clone(),
    }
}

/// The partner's loop: waits for a hand-over, applies it, says so; until stopped.
fn serve(shared: &Shared) {
    let mut seen = 0u32;
    loop {
        let mut round = 0u32;
        let flush = loop {
            if shared.asked.0.stop.load(Ordering::Acquire) {
                return;
            }
            let asked = shared.asked.0.flushes.load(Ordering::Acquire);
            if asked != seen {
                break asked;
            }
            round = round.saturating_add(1);
            if round < SPIN {
                std::hint::spin_loop();
            } else if round < SPIN + YIELDS {
                std::thread::yield_now();
            } else {
                std::thread::park();
            }
        };
        seen = flush;
        let mut work = shared.lock();
        shared.answered.0.started.store(flush, Ordering::Relaxed);
        work.run(flush);
        drop(work);
        shared.answered.0.done.store(flush, Ordering::Release);
    }
}
