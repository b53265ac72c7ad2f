//! Context matching: which modules around a predecessor a rule's left and right contexts
//! name, across branches.

use super::rule::PatternItem;
use crate::module_string::ModuleString;
use crate::symbol::Sym;

/// Whether `s` is skipped by context matching.
#[inline]
fn is_ignored(ignored: &[bool], s: Sym) -> bool {
    ignored.get(s.index()).copied().unwrap_or(false)
}

/// Matches a left context of symbols (leftmost first) for module `i` of `src`: the path
/// toward the root, skipping whole branches, climbing out of enclosing ones and skipping
/// the symbols marked in `ignored`. `matches` pairs brackets (see
/// [`ModuleString::bracket_matches`]); only the entries of `]` before `i` are read. Pushes
/// the matched indices, leftmost first.
pub(super) fn match_left(
    ignored: &[bool],
    left: impl DoubleEndedIterator<Item = Sym>,
    src: &ModuleString,
    matches: &[u32],
    i: usize,
    out: &mut Vec<usize>,
) -> bool {
    let base = out.len();
    let mut j = i;
    for p in left.rev() {
        loop {
            if j == 0 {
                return false;
            }
            j -= 1;
            let s = src.sym(j);
            if s == Sym::POP {
                let open = matches[j];
                if open == u32::MAX {
                    return false;
                }
                j = open as usize;
            } else if s != Sym::PUSH && !is_ignored(ignored, s) {
                break;
            }
        }
        if src.sym(j) != p {
            return false;
        }
        out.push(j);
    }
    out[base..].reverse();
    true
}

/// Matches the right context of module `i`: along the axis, skipping branches the pattern
/// does not enter and the symbols marked in `ignored`; `[` in the pattern enters a
/// branch, `]` skips the rest of the current one. Pushes the matched indices.
pub(super) fn match_right(
    ignored: &[bool],
    right: &[PatternItem],
    src: &ModuleString,
    matches: &[u32],
    i: usize,
    out: &mut Vec<usize>,
) -> bool {
    let n = src.len();
    let mut j = i + 1;
    for p in right {
        if p.sym == Sym::POP {
            loop {
                if j >= n {
                    return false;
                }
                let s = src.sym(j);
                if s == Sym::POP {
                    j += 1;
                    break;
                }
                if s == Sym::PUSH {
                    let close = matches[j];
                    if close == u32::MAX {
                        return false;
                    }
                    j = close as usize + 1;
                } else {
                    j += 1;
                }
            }
            continue;
        }
        loop {
            if j >= n {
                return false;
            }
            let s = src.sym(j);
            if is_ignored(ignored, s) {
                j += 1;
            } else if s == Sym::PUSH && p.sym != Sym::PUSH {
                let close = matches[j];
                if close == u32::MAX {
                    return false;
                }
                j = close as usize + 1;
            } else {
                break;
            }
        }
        if src.sym(j) != p.sym {
            return false;
        }
        if p.sym != Sym::PUSH {
            out.push(j);
        }
        j += 1;
    }
    true
}
