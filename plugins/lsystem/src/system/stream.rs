//! Steps taken depth first, piece by piece: each piece of a step's string is rewritten by
//! the next step at once, down to the last step, which is counted or handed out; no step's
//! string is ever kept whole, only one piece of each. Only for systems whose result cannot
//! depend on the order ([`Prepared::derives_in_pieces`](super::Prepared::derives_in_pieces)):
//! rules without contexts (a piece rewrites alone) that draw no random numbers (the draws
//! would interleave) and call no rule functions.
//!
//! The errors are those of the steps taken one after the other: a step's pieces are
//! rewritten in order, so its first error is the one it would raise whole; an error is
//! held while the steps before it go on (one of them may fail first), and the steps after
//! it stop.

use super::derive::{Context, Deriver, Scratch, StepOptions};
use super::host::Host;
use crate::module_string::ModuleString;

/// Modules of a step's string rewritten per piece by the next step.
const PIECE: usize = 1 << 10;

/// Where the last step's pieces go.
type Sink<'s, E> = &'s mut dyn FnMut(&ModuleString) -> Result<(), E>;

/// One step's buffer and state.
#[derive(Default)]
struct Level {
    /// The piece of the step's string being passed down.
    buf: ModuleString,
    scratch: Scratch,
    /// The modules the step made so far (for the module cap).
    made: u64,
}

/// The state of a depth-first derivation.
struct Run<'s, E> {
    levels: Vec<Level>,
    /// The earliest step that failed, and its first error.
    held: Option<(usize, E)>,
    /// Where the last step's pieces go (`None`: counted).
    sink: Option<Sink<'s, E>>,
    /// The successors of counted rules (see [`Deriver::count_after`]).
    successors: ModuleString,
    /// The module caps were checked by a count of the same steps: a system of fixed
    /// strings expands its pieces without checking them again.
    checked: bool,
}

impl Deriver<'_> {
    /// The steps `steps` (at least one) of `src` taken depth first: the last one's string
    /// counted (`sink` `None`) or handed to `sink` in pieces. `checked`: the caps were
    /// checked by a count (see [`Deriver::plain_counts`]). Returns the number of modules of
    /// the last step.
    pub(super) fn depth_first<H: Host>(
        &self,
        src: &ModuleString,
        steps: &[StepOptions],
        host: &mut H,
        sink: Option<Sink<'_, H::Error>>,
        checked: bool,
    ) -> Result<u64, H::Error> {
        let mut run = Run {
            levels: steps.iter().map(|_| Level::default()).collect(),
            held: None,
            sink,
            successors: ModuleString::new(),
            checked: checked && self.tables.all_plain,
        };
        self.descend(&mut run, 0, src, steps, host)?;
        match run.held {
            Some((_, e)) => Err(e),
            None => Ok(run.levels.last().map_or(0, |l| l.made)),
        }
    }

    /// Rewrites `piece` (of the string before step `k`) by step `k` and passes what it
    /// becomes down to the next step. An `Err` stops the whole derivation (a sink failed);
    /// the steps' own errors are held in `run`.
    fn descend<H: Host>(
        &self,
        run: &mut Run<'_, H::Error>,
        k: usize,
        piece: &ModuleString,
        steps: &[StepOptions],
        host: &mut H,
    ) -> Result<(), H::Error> {
        let opts = &steps[k];
        let last = k + 1 == steps.len();
        if last && run.sink.is_none() {
            if run.held.as_ref().is_none_or(|(h, _)| *h > k) {
                let level = &mut run.levels[k];
                match self.count_after(
                    piece,
                    &[],
                    level.made,
                    host,
                    opts,
                    &mut level.scratch,
                    &mut run.successors,
                ) {
                    Ok(n) => level.made += n,
                    Err(e) => run.held = Some((k, e)),
                }
            }
            return Ok(());
        }
        let mut buf = std::mem::take(&mut run.levels[k].buf);
        let mut scratch = std::mem::take(&mut run.levels[k].scratch);
        let mut result = Ok(());
        for from in (0..piece.len()).step_by(PIECE) {
            if run.held.as_ref().is_some_and(|(h, _)| *h <= k) {
                break;
            }
            let to = (from + PIECE).min(piece.len());
            buf.clear();
            let made = run.levels[k].made;
            let step = if run.checked && piece.is_flat() {
                host.check()
                    .map(|()| self.expand_plain(&piece.raw_syms()[from..to], &mut buf))
            } else {
                self.step_range(
                    piece,
                    from..to,
                    &Context::NONE,
                    made,
                    &mut buf,
                    host,
                    opts,
                    &mut scratch,
                )
            };
            if let Err(e) = step {
                run.held = Some((k, e));
                break;
            }
            run.levels[k].made += buf.len() as u64;
            result = match (last, run.sink.as_mut()) {
                (true, Some(sink)) => sink(&buf),
                _ => self.descend(run, k + 1, &buf, steps, host),
            };
            if result.is_err() {
                break;
            }
        }
        run.levels[k].buf = buf;
        run.levels[k].scratch = scratch;
        result
    }
}
