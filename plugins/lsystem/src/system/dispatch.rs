//! What a symbol turns into, found once per symbol when a system is compiled
//! ([`super::compile`]) and read by every derivation path.

/// What a symbol turns into: itself, a fixed string of symbols (`plain_pool[start..]`), the
/// first applicable of some rules (`rule_lists[start..]`), or the successor of its one
/// classic rule without contexts or alternatives when the condition holds (`Direct`:
/// applied without the general matching).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Dispatch {
    Copy,
    Plain { start: u32, len: u32 },
    Rules { start: u32, len: u32 },
    Direct { rule: u32 },
}
