//! What a derivation needs from outside the rules: randomness, limits, external rules.

use pge_engine::random::uniform;
use rand_mt::Mt;

use crate::error::LsError;
use crate::module_string::ModuleString;

/// What the derivation needs from its environment: randomness, limits, rules written in
/// another language (Lua functions) and the interpretation of new modules.
pub trait Host {
    /// The error type of the host; engine errors convert into it.
    type Error: From<LsError>;

    /// A uniform draw in `[0, 1)` from the instance's generator.
    fn random(&mut self) -> f64;

    /// Called every 65 536 modules: an error stops the step (time limit, cancellation).
    fn check(&mut self) -> Result<(), Self::Error> {
        Ok(())
    }

    /// Applies external rule `rule` (the id given to
    /// [`System::add_external`](crate::System::add_external)) to the modules
    /// `matched` of `src` (left context, predecessor, right context, brackets excluded),
    /// appending its successor to `out`. Returns false when the rule does not apply.
    fn apply(
        &mut self,
        rule: u32,
        matched: &[usize],
        src: &ModuleString,
        out: &mut ModuleString,
    ) -> Result<bool, Self::Error>;

    /// Interprets the modules `out[from..]` just produced (streaming interpretation).
    fn interpret(&mut self, out: &ModuleString, from: usize) -> Result<(), Self::Error> {
        let _ = (out, from);
        Ok(())
    }
}

/// A host for systems without external rules: randomness from a Mersenne Twister.
pub struct NativeHost<'a> {
    /// The instance's generator.
    pub rng: &'a mut Mt,
}

impl Host for NativeHost<'_> {
    type Error = LsError;
    fn random(&mut self) -> f64 {
        uniform(self.rng)
    }
    fn apply(
        &mut self,
        rule: u32,
        _: &[usize],
        _: &ModuleString,
        _: &mut ModuleString,
    ) -> Result<bool, LsError> {
        Err(LsError::Syntax {
            text: format!("external rule {rule}"),
            message: "this host runs no external rules".into(),
        })
    }
}
