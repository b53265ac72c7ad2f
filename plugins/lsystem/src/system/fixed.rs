//! The pass over a string without parameters whose rules all have fixed successors and at
//! most one-symbol contexts: one linear pass in which each module's symbol is read through a
//! one-byte class, its neighbours are kept as small context codes (the left one as the
//! modules go by, the right ones from one backward pass) and a symbol with rules finds its
//! successor in a table indexed by those two codes, without testing its rules one by one.

use super::dispatch::Dispatch;
use crate::module_string::ModuleString;
use crate::symbol::Sym;

/// A module copied as it is.
const COPY: u8 = 0;
/// A module replaced by a fixed string (`Dispatch::Plain`).
const PLAIN: u8 = 1;
/// A module rewritten by the first of its rules whose contexts match (`Dispatch::Rules`).
const RULES: u8 = 2;
/// `[`: copied; the left neighbour is saved, the right one restored when going back.
const PUSH: u8 = 3;
/// `]`: copied; the left neighbour is restored, the right one saved when going back.
const POP: u8 = 4;
/// Flag: the symbol is ignored by contexts (it is nobody's neighbour).
const IGNORED: u8 = 8;
/// The most context codes (symbols named by contexts, and 0 for every other neighbour or
/// none): a symbol with rules has `codes * codes` entries in the table of successors.
const MAX_CODES: usize = 16;

/// What the pass reads of one symbol.
#[derive(Clone, Copy, Debug, Default)]
struct Entry {
    /// [`COPY`], [`PLAIN`], [`RULES`], [`PUSH`] or [`POP`], with [`IGNORED`].
    class: u8,
    /// Its context code: from 1 for the symbols some context names, else 0.
    code: u8,
    /// Its successor ([`PLAIN`], see [`Successor`]), or where its successors start in
    /// `successors` ([`RULES`]).
    at: u32,
}

/// A successor as the pass reads it: one symbol's raw word, or with [`MANY`] set the index
/// of its (start, length) in `spans` (the symbols in `pool`).
type Successor = u32;
/// Flag of a [`Successor`] of several symbols (raw symbol words of strings without
/// parameters never have the top bit set).
const MANY: u32 = 1 << 31;

/// What the backward pass reads of one symbol: its context code, or one of these flags.
const BACK_PUSH: u8 = 0x10;
const BACK_POP: u8 = 0x20;
const BACK_IGNORED: u8 = 0x40;

/// A rule with a fixed successor, as the pass over a string without parameters reads it.
#[derive(Clone, Copy, Debug)]
pub(super) struct FixedRule {
    /// The one-symbol left context ([`FixedRule::ANY`]: none).
    pub(super) left: u32,
    /// The one-symbol right context ([`FixedRule::ANY`]: none).
    pub(super) right: u32,
    /// The successor: `plain_pool[start..start + len]`.
    pub(super) start: u32,
    pub(super) len: u32,
}

impl FixedRule {
    /// No context on this side.
    pub(super) const ANY: u32 = u32::MAX;
}

/// The left context codes the pass keeps as the modules go by: the code of the symbol a
/// one-symbol left context of the next module matches (0: none or no context's symbol),
/// rather than found by walking back, and that code as each enclosing `[` found it,
/// restored at its `]`.
#[derive(Debug, Default)]
pub(super) struct LeftCodes {
    left: u32,
    stack: Vec<u32>,
}

/// The tables of the pass, built when every rule reached has a fixed successor.
#[derive(Clone, Debug, Default)]
pub(super) struct FixedTables {
    /// Every symbol's entry.
    entries: Vec<Entry>,
    /// Every symbol's context code with the flags of the backward pass.
    back: Vec<u8>,
    /// The number of context codes.
    codes: usize,
    /// For every symbol with rules and every (left code, right code): its successor
    /// (itself when no rule applies).
    successors: Vec<Successor>,
    /// Successors of several symbols: (start, length) in `pool`.
    spans: Vec<(u32, u32)>,
    /// The symbols of those successors.
    pool: Vec<u32>,
    /// Whether some rule has a right context (the backward pass is needed).
    pub(super) uses_right: bool,
}

impl FixedTables {
    /// The tables for `dispatch`, whose [`Dispatch::Rules`] lists are `lists` (successors in
    /// `pool`); `None` when a bracket has rules of its own or the contexts name more than
    /// [`MAX_CODES`] symbols (the general loop is then taken).
    pub(super) fn build(
        dispatch: &[Dispatch],
        ignored: &[bool],
        lists: &[FixedRule],
        pool: &[u32],
    ) -> Option<FixedTables> {
        let n = dispatch.len();
        let copied = |s: Sym| matches!(dispatch.get(s.index()), None | Some(Dispatch::Copy));
        if !copied(Sym::PUSH) || !copied(Sym::POP) {
            return None;
        }
        let mut code = vec![0u8; n];
        let mut codes = 1;
        for s in lists.iter().flat_map(|r| [r.left, r.right]) {
            if s == FixedRule::ANY {
                continue;
            }
            let slot = code.get_mut(s as usize)?;
            if *slot == 0 {
                if codes == MAX_CODES {
                    return None;
                }
                *slot = codes as u8;
                codes += 1;
            }
        }
        let mut t = FixedTables {
            entries: Vec::with_capacity(n),
            back: Vec::with_capacity(n),
            codes,
            successors: Vec::new(),
            spans: Vec::new(),
            pool: pool.to_vec(),
            uses_right: lists.iter().any(|r| r.right != FixedRule::ANY),
        };
        let fits =
            |side: u32, c: usize| side == FixedRule::ANY || usize::from(code[side as usize]) == c;
        for (s, d) in dispatch.iter().enumerate() {
            let mut e = Entry {
                code: code[s],
                ..Entry::default()
            };
            let kind = match *d {
                _ if s == Sym::PUSH.index() => PUSH,
                _ if s == Sym::POP.index() => POP,
                Dispatch::Copy => COPY,
                Dispatch::Plain { start, len } => {
                    e.at = t.successor(start, len);
                    PLAIN
                }
                Dispatch::Rules { start, len } => {
                    let list = &lists[start as usize..(start + len) as usize];
                    e.at = t.successors.len() as u32;
                    for left in 0..codes {
                        for right in 0..codes {
                            let rule = list
                                .iter()
                                .find(|r| fits(r.left, left) && fits(r.right, right));
                            let succ = match rule {
                                Some(r) => t.successor(r.start, r.len),
                                None => s as u32,
                            };
                            t.successors.push(succ);
                        }
                    }
                    RULES
                }
                Dispatch::Direct { .. } => return None,
            };
            e.class = kind | if ignored[s] { IGNORED } else { 0 };
            t.entries.push(e);
            t.back.push(if ignored[s] {
                BACK_IGNORED
            } else if kind == PUSH {
                BACK_PUSH
            } else if kind == POP {
                BACK_POP
            } else {
                code[s]
            });
        }
        Some(t)
    }

    /// The successor `pool[start..start + len]` as the pass reads it.
    fn successor(&mut self, start: u32, len: u32) -> Successor {
        match &self.pool[start as usize..(start + len) as usize] {
            [one] if one & MANY == 0 => *one,
            _ => {
                self.spans.push((start, len));
                (self.spans.len() - 1) as u32 | MANY
            }
        }
    }

    /// The entry of raw symbol word `s` (symbols interned after the tables were built have
    /// no rules and are nobody's context: copied).
    #[inline]
    fn entry(&self, s: u32) -> Entry {
        self.entries.get(s as usize).copied().unwrap_or_default()
    }

    /// For every module of `src`, the context code of the symbol a one-symbol right context
    /// of it matches (0 when none, or `]` at the end of the branch), as
    /// [`super::context::match_right`] walks (skipping branches and ignored symbols), in one
    /// backward pass: brackets pair up from the right as they do from the left.
    pub(super) fn right_codes(&self, src: &ModuleString) -> Vec<u8> {
        let syms = src.raw_syms();
        let mut rights = vec![0; syms.len()];
        // What a right context starting at the module after the current one sees, and the
        // same after each `]` still waiting for its `[`.
        let mut next = 0;
        let mut after_close: Vec<u8> = Vec::new();
        for (right, &raw) in rights.iter_mut().zip(syms).rev() {
            *right = next;
            // Brackets pair up whether ignored or not; an ignored symbol is skipped.
            let b = self.back.get(raw as usize).copied().unwrap_or(0);
            if b < BACK_PUSH {
                next = b;
            } else if raw == Sym::PUSH.0 {
                let after = after_close.pop().unwrap_or(0);
                if b != BACK_IGNORED {
                    next = after;
                }
            } else if raw == Sym::POP.0 {
                after_close.push(next);
                if b != BACK_IGNORED {
                    next = 0;
                }
            }
        }
        rights
    }

    /// Rewrites the modules `range` of `syms`, appending to `o`; `rights` holds their right
    /// codes (see [`FixedTables::right_codes`]; empty when no rule has a right context) and
    /// `lefts` the left code of the next module with those of the enclosing branches.
    /// Returns false as soon as `o` is longer than `limit`.
    #[inline]
    pub(super) fn run(
        &self,
        syms: &[u32],
        rights: &[u8],
        range: std::ops::Range<usize>,
        o: &mut Vec<u32>,
        limit: u64,
        lefts: &mut LeftCodes,
    ) -> bool {
        let mut left = lefts.left as usize;
        let stack = &mut lefts.stack;
        for (&s, k) in syms[range.clone()].iter().zip(range) {
            let e = self.entry(s);
            let kind = e.class & !IGNORED;
            if kind == RULES || kind == PLAIN {
                let succ = if kind == RULES {
                    let right = usize::from(rights.get(k).copied().unwrap_or(0));
                    self.successors[e.at as usize + left * self.codes + right]
                } else {
                    e.at
                };
                if succ & MANY == 0 {
                    o.push(succ);
                } else {
                    let (start, len) = self.spans[(succ & !MANY) as usize];
                    o.extend_from_slice(&self.pool[start as usize..(start + len) as usize]);
                }
                if e.class & IGNORED == 0 {
                    left = usize::from(e.code);
                }
            } else {
                o.push(s);
                if kind == PUSH {
                    stack.push(left as u32);
                } else if kind == POP {
                    left = stack.pop().unwrap_or(0) as usize;
                } else if e.class & IGNORED == 0 {
                    left = usize::from(e.code);
                }
            }
            if o.len() as u64 > limit {
                lefts.left = left as u32;
                return false;
            }
        }
        lefts.left = left as u32;
        true
    }
}

#[cfg(test)]
mod tests {
    use crate::{DeriveOptions, ModuleString, NativeHost, Output, SymbolTable, System};
    use rand_mt::Mt;

    /// One step of `text` by `rules` (with `ignore` ignored), and the modules produced.
    fn step(rules: &[&str], ignore: &str, text: &str) -> String {
        let mut symbols = SymbolTable::new();
        let mut system = System::new();
        system.ignore(ignore, &mut symbols);
        for r in rules {
            system
                .add_production(r, None, 0, &mut symbols)
                .expect("rule");
        }
        let prepared = system.prepare(&symbols).expect("prepare");
        let src = system
            .parse_string(text, &mut symbols, &mut || 0.0)
            .expect("string");
        let mut out = ModuleString::new();
        let mut rng = Mt::new(1);
        prepared
            .derive(
                &src,
                &DeriveOptions::new(1, 1, 1_000_000),
                &mut NativeHost { rng: &mut rng },
                Output::Keep(&mut out),
            )
            .expect("step");
        out.to_text(&symbols, "")
    }

    #[test]
    fn the_pass_for_fixed_successors_matches_contexts_as_the_general_one() {
        let rules = [
            "b < a -> b",
            "b -> a",
            "a > b -> c",
            "c < c > a -> dd",
            "d -> d[c]",
            "+ -> -",
        ];
        // A rule with a condition (on a symbol the strings lack) sends the same rules down
        // the general path.
        let general: Vec<&str> = rules.iter().copied().chain(["Z : 1 > 0 -> Z"]).collect();
        let mut rng = Mt::new(5);
        let alphabet = ['a', 'b', 'c', 'd', '+', '[', ']'];
        for k in 0..600 {
            let len = 1 + rng.next_u32() as usize % 40;
            let text: String = (0..len)
                .map(|_| alphabet[rng.next_u32() as usize % alphabet.len()])
                .collect();
            // Ignored brackets too: skipped by contexts, still paired.
            let ignore = ["+ -", "+ [", "+ ]"][k % 3];
            assert_eq!(
                step(&rules, ignore, &text),
                step(&general, ignore, &text),
                "{text} ignoring {ignore}"
            );
        }
        assert_eq!(step(&rules, "+ -", "ba[b]a]a[+a"), "ab[a]a]a[-a");
    }
}
