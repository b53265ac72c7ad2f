//! The memory budget of a run: one per run, shared by its Lua states and by the Rust-side
//! buffers its work allocates (a forest's layout, a terrain mesh, a skeleton a script keeps),
//! across threads (variants grown in parallel charge the same budget).
//!
//! Plain Rust: algorithms receive it in their [`RunContext`](crate::RunContext) and check a
//! size before they allocate ([`Budget::check`]) or hold a [`Charge`] for as long as they
//! keep a buffer ([`Budget::charge`]). The engine keeps each Lua state's own use in the
//! budget too, so `--memory-limit` bounds the sum of everything a run holds.

use std::fmt;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

use crate::{Error, Location, Result};

/// A run's memory budget and its stop flags; cheap to clone (clones share the budget).
#[derive(Clone)]
pub struct Budget {
    memory: Arc<Memory>,
    /// Set when the part of the run this handle belongs to must stop (a sibling failed);
    /// a child's list holds its parents' flags first.
    stops: Arc<[Arc<AtomicBool>]>,
}

struct Memory {
    limit: usize,
    used: AtomicUsize,
}

impl fmt::Debug for Budget {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Budget")
            .field("limit", &self.limit())
            .field("used", &self.used())
            .field("stopped", &self.stopped())
            .finish()
    }
}

impl Default for Budget {
    /// The default limit of an engine ([`crate::Limits`]'s 4096 MiB).
    fn default() -> Self {
        Budget::new(4096 << 20)
    }
}

impl Budget {
    /// A budget of `limit` bytes, nothing charged.
    #[must_use]
    pub fn new(limit: usize) -> Budget {
        Budget {
            memory: Arc::new(Memory {
                limit,
                used: AtomicUsize::new(0),
            }),
            stops: Arc::from(vec![Arc::new(AtomicBool::new(false))]),
        }
    }

    /// The limit in bytes.
    #[must_use]
    pub fn limit(&self) -> usize {
        self.memory.limit
    }

    /// The bytes charged now, by every holder of the budget.
    #[must_use]
    pub fn used(&self) -> usize {
        self.memory.used.load(Ordering::Relaxed)
    }

    /// The bytes still free.
    #[must_use]
    pub fn available(&self) -> usize {
        self.limit().saturating_sub(self.used())
    }

    /// The error of a size past the budget: [`Error::MemoryLimit`] at `location`, `what`
    /// naming what needed it (and the option that asked for it).
    #[must_use]
    pub fn exceeded(&self, location: &Location, what: Option<String>) -> Error {
        Error::MemoryLimit {
            location: location.clone(),
            limit: self.limit(),
            what,
        }
    }

    /// An error unless `bytes` more would fit in the budget now, checked before a buffer is
    /// allocated (nothing is held: charge it with [`Budget::charge`] to keep it). `what`
    /// describes the buffer and the option that sized it, for the message.
    pub fn check(
        &self,
        bytes: u64,
        location: &Location,
        what: impl FnOnce() -> String,
    ) -> Result<()> {
        if bytes > self.available() as u64 {
            return Err(self.exceeded(location, Some(what())));
        }
        Ok(())
    }

    /// Charges `bytes` to the budget for as long as the returned [`Charge`] lives, or an
    /// error (nothing charged) when they would pass the limit.
    pub fn charge(
        &self,
        bytes: usize,
        location: &Location,
        what: impl FnOnce() -> String,
    ) -> Result<Charge> {
        let mut charge = Charge {
            budget: self.clone(),
            bytes: 0,
        };
        charge.resize(bytes, location, what)?;
        Ok(charge)
    }

    /// A charge of nothing, grown later ([`Charge::resize`]).
    #[must_use]
    pub fn empty_charge(&self) -> Charge {
        Charge {
            budget: self.clone(),
            bytes: 0,
        }
    }

    /// A handle on the same memory whose own stop flag ([`Budget::stop`]) stops it and its
    /// children but not this budget: the parts of a run that fail together (the variants of
    /// a forest) share one.
    #[must_use]
    pub fn child(&self) -> Budget {
        let mut stops: Vec<Arc<AtomicBool>> = self.stops.iter().cloned().collect();
        stops.push(Arc::new(AtomicBool::new(false)));
        Budget {
            memory: self.memory.clone(),
            stops: Arc::from(stops),
        }
    }

    /// Stops the work of this handle and of its children: their next check of the deadline
    /// is an [`Error::Cancelled`].
    pub fn stop(&self) {
        if let Some(own) = self.stops.last() {
            own.store(true, Ordering::Relaxed);
        }
    }

    /// Whether this handle or one of its parents was stopped.
    #[must_use]
    pub fn stopped(&self) -> bool {
        self.stops.iter().any(|s| s.load(Ordering::Relaxed))
    }

    fn add(&self, bytes: usize) -> bool {
        let memory = &self.memory;
        memory
            .used
            .fetch_update(Ordering::Relaxed, Ordering::Relaxed, |used| {
                used.checked_add(bytes).filter(|&u| u <= memory.limit)
            })
            .is_ok()
    }

    fn add_forced(&self, bytes: usize) {
        let _ = self
            .memory
            .used
            .fetch_update(Ordering::Relaxed, Ordering::Relaxed, |used| {
                Some(used.saturating_add(bytes))
            });
    }

    fn remove(&self, bytes: usize) {
        let _ = self
            .memory
            .used
            .fetch_update(Ordering::Relaxed, Ordering::Relaxed, |used| {
                Some(used.saturating_sub(bytes))
            });
    }
}

/// Bytes charged to a [`Budget`], given back when the charge is dropped (or resized down).
pub struct Charge {
    budget: Budget,
    bytes: usize,
}

impl fmt::Debug for Charge {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Charge")
            .field("bytes", &self.bytes)
            .finish()
    }
}

impl Charge {
    /// The bytes held.
    #[must_use]
    pub fn bytes(&self) -> usize {
        self.bytes
    }

    /// Holds `bytes` instead: an error (the charge unchanged) when the growth would pass the
    /// limit.
    pub fn resize(
        &mut self,
        bytes: usize,
        location: &Location,
        what: impl FnOnce() -> String,
    ) -> Result<()> {
        if bytes > self.bytes {
            if !self.budget.add(bytes - self.bytes) {
                return Err(self.budget.exceeded(location, Some(what())));
            }
        } else {
            self.budget.remove(self.bytes - bytes);
        }
        self.bytes = bytes;
        Ok(())
    }

    /// Holds `bytes` instead, past the limit if need be: for memory already allocated (a Lua
    /// state's), whose holder then finds the budget exceeded.
    pub fn set(&mut self, bytes: usize) {
        if bytes > self.bytes {
            self.budget.add_forced(bytes - self.bytes);
        } else {
            self.budget.remove(self.bytes - bytes);
        }
        self.bytes = bytes;
    }

    /// Moves `bytes` of this charge (all it holds at most) into a charge of their own, given
    /// back apart: one charge taken at once for several buffers that are freed one by one.
    #[must_use]
    pub fn split(&mut self, bytes: usize) -> Charge {
        let bytes = bytes.min(self.bytes);
        self.bytes -= bytes;
        Charge {
            budget: self.budget.clone(),
            bytes,
        }
    }

    /// The budget charged.
    #[must_use]
    pub fn budget(&self) -> &Budget {
        &self.budget
    }
}

impl Drop for Charge {
    fn drop(&mut self) {
        self.budget.remove(self.bytes);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn charges_share_one_limit_and_are_given_back() {
        let budget = Budget::new(1000);
        let here = Location::new("a.lua", 2);
        let a = budget.charge(600, &here, || "a".into()).expect("fits");
        let clone = budget.clone();
        let err = clone
            .charge(500, &here, || "the layout (density = 1)".into())
            .expect_err("past the limit");
        assert!(
            matches!(err, Error::MemoryLimit { limit: 1000, .. }),
            "{err:?}"
        );
        assert_eq!(
            err.to_string(),
            "a.lua:2: the layout (density = 1): memory limit of 0 MiB exceeded (see --memory-limit)"
        );
        assert_eq!(budget.used(), 600);
        assert!(budget.check(400, &here, String::new).is_ok());
        assert!(budget.check(401, &here, String::new).is_err());
        drop(a);
        assert_eq!(budget.used(), 0);
        let mut c = budget.empty_charge();
        c.resize(900, &here, String::new).expect("fits");
        c.set(2000);
        assert_eq!(budget.available(), 0);
        c.resize(10, &here, String::new).expect("shrinks");
        assert_eq!(budget.used(), 10);
        let mut whole = budget.charge(300, &here, String::new).expect("fits");
        let part = whole.split(100);
        assert_eq!(
            (whole.bytes(), part.bytes(), budget.used()),
            (200, 100, 310)
        );
        drop(whole);
        assert_eq!(budget.used(), 110);
        drop(part);
        assert_eq!(budget.used(), 10);
    }

    #[test]
    fn a_child_stops_without_its_parent() {
        let parent = Budget::new(10);
        let child = parent.child();
        let grandchild = child.child();
        child.stop();
        assert!(child.stopped() && grandchild.stopped());
        assert!(!parent.stopped());
        parent.stop();
        assert!(parent.child().stopped());
    }
}
