//! The last two steps of a derivation taken depth first, piece by piece: each piece of the
//! string before them is rewritten once, and what it becomes rewritten (or only counted)
//! at once, so that the string between the two steps is never kept whole. Only for systems
//! whose result cannot depend on the order: rules without contexts (a piece rewrites alone)
//! that draw no random numbers (the draws would interleave), without rule functions, and
//! not made of fixed strings only (those have a pass of their own).

use super::derive::{Context, Deriver, Scratch, StepOptions};
use super::host::Host;
use crate::module_string::ModuleString;

/// Modules of the string before the two steps rewritten per piece.
const PIECE: usize = 1 << 12;

impl Deriver<'_> {
    /// Whether two steps may be taken depth first (see the module's note).
    pub(super) fn depth_first(&self, first: &StepOptions, second: &StepOptions) -> bool {
        let t = self.tables;
        // Systems of fixed strings have their own pass (which counts a step before making it).
        !t.all_plain
            && !t.uses_context
            && !t.random
            && !t.growth.is_empty()
            && !first.stream
            && !second.stream
    }

    /// The number of modules the steps `first` and `second` make of `src`, the second
    /// counted without being kept. The errors are those of the two steps taken one after
    /// the other: an error of the second step is reported only once the first has been
    /// taken to its end without one.
    pub(super) fn count_two<H: Host>(
        &self,
        src: &ModuleString,
        host: &mut H,
        first: &StepOptions,
        second: &StepOptions,
    ) -> Result<(u64, u64), H::Error> {
        let mut counting = Scratch::default();
        let mut successors = ModuleString::new();
        let mut counted = 0u64;
        let mut deferred = None;
        let made = self.first_step_pieces(src, host, first, |between, host| {
            if deferred.is_none() {
                match self.count_after(
                    between,
                    &[],
                    counted,
                    host,
                    second,
                    &mut counting,
                    &mut successors,
                ) {
                    Ok(n) => counted += n,
                    Err(e) => deferred = Some(e),
                }
            }
            Ok(())
        })?;
        match deferred {
            Some(e) => Err(e),
            None => Ok((made, counted)),
        }
    }

    /// The steps `first` and `second` of `src` delivered in pieces: the second step's
    /// successors of every `chunk` modules between them are appended to `buf` (cleared
    /// before each piece) and handed to `sink`. Returns the number of modules produced by
    /// the second step.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn step_chunks_two<H: Host>(
        &self,
        src: &ModuleString,
        buf: &mut ModuleString,
        host: &mut H,
        first: &StepOptions,
        second: &StepOptions,
        chunk: usize,
        sink: &mut dyn FnMut(&ModuleString) -> Result<(), H::Error>,
    ) -> Result<u64, H::Error> {
        let chunk = chunk.max(1);
        let mut writing = Scratch::default();
        let mut written = 0u64;
        self.first_step_pieces(src, host, first, |between, host| {
            for from in (0..between.len()).step_by(chunk) {
                let to = (from + chunk).min(between.len());
                buf.clear();
                self.step_range(
                    between,
                    from..to,
                    &Context::NONE,
                    written,
                    buf,
                    host,
                    second,
                    &mut writing,
                )?;
                written += buf.len() as u64;
                sink(buf)?;
            }
            Ok(())
        })?;
        Ok(written)
    }

    /// Takes the step `first` of `src` one piece of [`PIECE`] modules at a time, handing
    /// each piece's successors to `then`. Returns the number of modules the step made.
    fn first_step_pieces<H: Host>(
        &self,
        src: &ModuleString,
        host: &mut H,
        first: &StepOptions,
        mut then: impl FnMut(&ModuleString, &mut H) -> Result<(), H::Error>,
    ) -> Result<u64, H::Error> {
        let mut between = ModuleString::new();
        let mut scratch = Scratch::default();
        let mut made = 0u64;
        for start in (0..src.len()).step_by(PIECE) {
            let end = (start + PIECE).min(src.len());
            between.clear();
            self.step_range(
                src,
                start..end,
                &Context::NONE,
                made,
                &mut between,
                host,
                first,
                &mut scratch,
            )?;
            made += between.len() as u64;
            then(&between, host)?;
        }
        Ok(made)
    }
}
