//! The engine's clock: the time limit's deadlines and the phases' timings read it.
//!
//! On the desktop it is the operating system's monotonic clock (`std::time::Instant`). A host
//! without a usable one (a browser, where the page knows the time) installs its own with
//! [`set_clock`] before its first session; everything in the engine and its plugins that
//! measures time reads [`Instant::now`], so nothing else changes.

use std::ops::Add;
use std::sync::OnceLock;
use std::time::Duration;

/// A clock: the time since an origin of the clock's own choosing (fixed for the process),
/// never going backwards.
pub type ClockFn = fn() -> Duration;

static CLOCK: OnceLock<ClockFn> = OnceLock::new();

/// Installs the process's clock: `false` (and nothing changes) when a clock was installed, or
/// the default one read, before. Call it once, before the first session.
pub fn set_clock(clock: ClockFn) -> bool {
    CLOCK.set(clock).is_ok()
}

/// The default clock: `std::time::Instant` since the first reading.
fn system() -> Duration {
    static ORIGIN: OnceLock<std::time::Instant> = OnceLock::new();
    ORIGIN.get_or_init(std::time::Instant::now).elapsed()
}

/// A reading of the engine's clock, with the part of `std::time::Instant`'s interface the
/// engine uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Instant(Duration);

impl Instant {
    /// Now, on the installed clock (or the system's).
    #[must_use]
    pub fn now() -> Instant {
        Instant(CLOCK.get_or_init(|| system)())
    }

    /// The time since this reading (zero if the clock has not moved on).
    #[must_use]
    pub fn elapsed(&self) -> Duration {
        Instant::now().duration_since(*self)
    }

    /// The time from `earlier` to this reading (zero if `earlier` is later).
    #[must_use]
    pub fn duration_since(&self, earlier: Instant) -> Duration {
        self.0.saturating_sub(earlier.0)
    }
}

impl Add<Duration> for Instant {
    type Output = Instant;

    /// Saturating: a limit too far ahead never comes.
    fn add(self, d: Duration) -> Instant {
        Instant(self.0.saturating_add(d))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn readings_move_forward_and_deadlines_compare() {
        let a = Instant::now();
        std::thread::sleep(Duration::from_millis(2));
        let b = Instant::now();
        assert!(b > a);
        assert!(b.duration_since(a) >= Duration::from_millis(2));
        assert_eq!(a.duration_since(b), Duration::ZERO);
        assert!(a + Duration::from_secs(3600) > b);
        assert!(a + Duration::MAX > b);
        assert!(a.elapsed() >= Duration::from_millis(2));
    }
}
