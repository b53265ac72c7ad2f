//! Errors of the rewriting engine.

/// What can go wrong while building or deriving an L-system.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum LsError {
    /// A rule is malformed or cannot be applied.
    #[error("rule '{rule}': {message}")]
    Rule {
        /// The host's tag for the rule (where it was defined).
        origin: u32,
        /// The rule's text.
        rule: String,
        /// What is wrong.
        message: String,
    },
    /// A string of modules (an axiom, a successor) does not parse.
    #[error("'{text}': {message}")]
    Syntax {
        /// The text.
        text: String,
        /// What is wrong.
        message: String,
    },
    /// The string grew past the module cap.
    #[error("step {step}: the string reached {count} modules, more than maxModules ({max})")]
    TooManyModules {
        /// The derivation step (1-based).
        step: u32,
        /// How many modules the step produced (or had produced when it stopped).
        count: u64,
        /// The cap.
        max: usize,
    },
}
