//! The derivation string: modules stored flat, without an allocation per module.

use std::fmt::Write;

use crate::symbol::{Sym, SymbolTable};

/// Flag set on a module whose parameters live outside the string (Lua values); its one
/// stored parameter is then the index of those values in the host's side table.
const EXTERNAL: u32 = 1 << 31;

/// A string of modules: interned symbols and their numeric parameters in flat arrays.
///
/// Each module costs 4 bytes for its symbol, 4 bytes for its parameter offset (only once some
/// module of the string has parameters) and 8 bytes per parameter. Modules whose parameters are
/// not plain numbers (any Lua value) are *external*: the string stores an index into a side
/// table kept by the host.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ModuleString {
    syms: Vec<u32>,
    /// Empty while no module has parameters; otherwise `syms.len() + 1` offsets into `params`.
    starts: Vec<u32>,
    params: Vec<f64>,
}

impl ModuleString {
    /// An empty string.
    #[must_use]
    pub fn new() -> ModuleString {
        ModuleString::default()
    }

    /// Number of modules, brackets included.
    #[must_use]
    pub fn len(&self) -> usize {
        self.syms.len()
    }

    /// Whether the string has no modules.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.syms.is_empty()
    }

    /// Removes every module, keeping the allocations.
    pub fn clear(&mut self) {
        self.syms.clear();
        self.starts.clear();
        self.params.clear();
    }

    /// Reserves room for `modules` more modules.
    pub fn reserve(&mut self, modules: usize) {
        self.syms.reserve(modules);
        if !self.starts.is_empty() {
            self.starts.reserve(modules);
        }
    }

    /// Reserves room for `modules` more modules holding `params` more parameters in all
    /// (their offsets included, should the string have none yet).
    pub fn reserve_with_params(&mut self, modules: usize, params: usize) {
        self.syms.reserve(modules);
        if params > 0 || !self.starts.is_empty() {
            self.starts.reserve(modules + 1);
        }
        self.params.reserve(params);
    }

    /// Bytes allocated by the string's buffers.
    #[must_use]
    pub fn memory_bytes(&self) -> usize {
        self.syms.capacity() * 4 + self.starts.capacity() * 4 + self.params.capacity() * 8
    }

    /// The symbol of module `i`.
    #[inline]
    #[must_use]
    pub fn sym(&self, i: usize) -> Sym {
        Sym(self.syms[i] & !EXTERNAL)
    }

    /// The raw symbol words (symbol id, with the external flag in the top bit).
    #[inline]
    #[must_use]
    pub fn raw_syms(&self) -> &[u32] {
        &self.syms
    }

    /// The symbol words of a string without parameters, to append parameterless modules to
    /// (plain symbols only: a string without offsets has no external module either).
    #[inline]
    pub(crate) fn flat_syms_mut(&mut self) -> &mut Vec<u32> {
        debug_assert!(self.starts.is_empty());
        &mut self.syms
    }

    /// Whether no module of the string has stored parameters.
    #[inline]
    #[must_use]
    pub fn is_flat(&self) -> bool {
        self.starts.is_empty()
    }

    /// The numeric parameters of module `i` (empty for an external module).
    #[inline]
    #[must_use]
    pub fn params(&self, i: usize) -> &[f64] {
        if self.starts.is_empty() || self.syms[i] & EXTERNAL != 0 {
            return &[];
        }
        &self.params[self.starts[i] as usize..self.starts[i + 1] as usize]
    }

    /// The side-table index of an external module's parameters.
    #[inline]
    #[must_use]
    pub fn external(&self, i: usize) -> Option<u32> {
        if self.syms[i] & EXTERNAL == 0 {
            return None;
        }
        Some(self.params[self.starts[i] as usize] as u32)
    }

    #[inline]
    fn make_starts(&mut self) {
        if self.starts.is_empty() {
            self.first_starts();
        }
    }

    /// The offsets of a string whose modules had no parameters so far.
    #[cold]
    fn first_starts(&mut self) {
        // Keeps the allocation of a string cleared before.
        self.starts.resize(self.syms.len() + 1, 0);
    }

    /// Appends a module with numeric parameters.
    #[inline]
    pub fn push(&mut self, sym: Sym, params: &[f64]) {
        debug_assert!(sym.0 & EXTERNAL == 0);
        if params.is_empty() && self.starts.is_empty() {
            self.syms.push(sym.0);
            return;
        }
        self.make_starts();
        self.syms.push(sym.0);
        self.params.extend_from_slice(params);
        self.starts.push(self.params.len() as u32);
    }

    /// Appends the modules `syms` (raw symbol words, no external ones) with the parameters
    /// `values`, of which module `k` takes those up to `ends[k]` (cumulative counts, so
    /// `ends.len() == syms.len()` and `values` yields `ends[last]` numbers): a compiled
    /// successor written with one copy of its symbols and offsets.
    #[inline]
    pub fn push_modules(
        &mut self,
        syms: &[u32],
        ends: &[u32],
        values: impl ExactSizeIterator<Item = f64>,
    ) {
        debug_assert_eq!(syms.len(), ends.len());
        debug_assert_eq!(ends.last().map_or(0, |e| *e as usize), values.len());
        if values.len() == 0 {
            self.extend_plain(syms);
            return;
        }
        self.make_starts();
        self.syms.extend_from_slice(syms);
        let base = self.params.len() as u32;
        self.params.extend(values);
        self.starts.extend(ends.iter().map(|e| base + e));
    }

    /// The parameters from offset `from` to the end of the string's parameter array (those
    /// of the modules appended since the array had `from` numbers).
    #[inline]
    #[must_use]
    pub fn params_since(&self, from: usize) -> &[f64] {
        self.params.get(from..).unwrap_or(&[])
    }

    /// The number of parameters stored (a mark for [`ModuleString::params_since`]).
    #[inline]
    #[must_use]
    pub fn param_count(&self) -> usize {
        self.params.len()
    }

    /// Appends a module whose parameters are entry `slot` of the host's side table.
    pub fn push_external(&mut self, sym: Sym, slot: u32) {
        self.make_starts();
        self.syms.push(sym.0 | EXTERNAL);
        self.params.push(f64::from(slot));
        self.starts.push(self.params.len() as u32);
    }

    /// Starts a module whose parameters are then appended with [`push_param`](Self::push_param)
    /// (used by compiled productions to evaluate arguments straight into the string).
    #[inline]
    pub fn begin(&mut self, sym: Sym) {
        self.make_starts();
        self.syms.push(sym.0);
    }

    /// Appends one parameter to the module started by [`begin`](Self::begin).
    #[inline]
    pub fn push_param(&mut self, value: f64) {
        self.params.push(value);
    }

    /// Ends the module started by [`begin`](Self::begin).
    #[inline]
    pub fn end(&mut self) {
        self.starts.push(self.params.len() as u32);
    }

    /// Appends one parameterless module given as a raw symbol word.
    #[inline]
    pub fn push_raw(&mut self, raw: u32) {
        self.syms.push(raw);
        if !self.starts.is_empty() {
            self.starts.push(self.params.len() as u32);
        }
    }

    /// Appends parameterless modules given as raw symbol words.
    #[inline]
    pub fn extend_plain(&mut self, syms: &[u32]) {
        self.syms.extend_from_slice(syms);
        if !self.starts.is_empty() {
            let end = self.params.len() as u32;
            self.starts.resize(self.syms.len() + 1, end);
        }
    }

    /// Appends a copy of module `i` of `other` (an external module keeps its slot).
    #[inline]
    pub fn push_from(&mut self, other: &ModuleString, i: usize) {
        let raw = other.syms[i];
        if other.starts.is_empty() {
            self.syms.push(raw);
            if !self.starts.is_empty() {
                self.starts.push(self.params.len() as u32);
            }
            return;
        }
        let (a, b) = (other.starts[i] as usize, other.starts[i + 1] as usize);
        if a == b && self.starts.is_empty() {
            self.syms.push(raw);
            return;
        }
        self.make_starts();
        self.syms.push(raw);
        self.params.extend_from_slice(&other.params[a..b]);
        self.starts.push(self.params.len() as u32);
    }

    /// Appends a copy of the modules `range` of `other` (external modules keep their slots),
    /// with bulk copies of symbols, parameters and offsets.
    #[inline]
    pub fn extend_from(&mut self, other: &ModuleString, range: std::ops::Range<usize>) {
        if other.starts.is_empty() {
            self.extend_plain(&other.syms[range]);
            return;
        }
        let (a, b) = (other.starts[range.start], other.starts[range.end]);
        if a == b && self.starts.is_empty() {
            self.syms.extend_from_slice(&other.syms[range]);
            return;
        }
        self.make_starts();
        self.syms.extend_from_slice(&other.syms[range.clone()]);
        let base = self.params.len() as u32;
        self.params
            .extend_from_slice(&other.params[a as usize..b as usize]);
        self.starts.extend(
            other.starts[range.start + 1..=range.end]
                .iter()
                .map(|&s| s - a + base),
        );
    }

    /// Appends all modules of `other`.
    pub fn append(&mut self, other: &ModuleString) {
        self.extend_from(other, 0..other.len());
    }

    /// Replaces the side-table slot of external module `i`.
    pub fn set_external_slot(&mut self, i: usize, slot: u32) {
        if self.syms[i] & EXTERNAL != 0 {
            let at = self.starts[i] as usize;
            self.params[at] = f64::from(slot);
        }
    }

    /// Writes module `i` as `Name` or `Name(p1,p2)` (numbers in shortest round-trip form,
    /// see `write_param`); an external module is written with its name only.
    pub fn write_module(&self, i: usize, symbols: &SymbolTable, out: &mut String) {
        out.push_str(symbols.name(self.sym(i)));
        let params = self.params(i);
        if !params.is_empty() {
            out.push('(');
            for (k, p) in params.iter().enumerate() {
                if k > 0 {
                    out.push(',');
                }
                write_param(out, *p);
            }
            out.push(')');
        }
    }

    /// The whole string as text, modules separated by `sep`.
    #[must_use]
    pub fn to_text(&self, symbols: &SymbolTable, sep: &str) -> String {
        let mut out = String::new();
        for i in 0..self.len() {
            if i > 0 {
                out.push_str(sep);
            }
            self.write_module(i, symbols, &mut out);
        }
        out
    }

    /// For every bracket, the index of its partner (`u32::MAX` when unbalanced); other entries
    /// are unspecified. Computed once per step for context matching.
    #[must_use]
    pub fn bracket_matches(&self) -> Vec<u32> {
        let mut matches = vec![u32::MAX; self.syms.len()];
        let mut stack: Vec<u32> = Vec::new();
        for (i, &raw) in self.syms.iter().enumerate() {
            if raw == Sym::PUSH.0 {
                stack.push(i as u32);
            } else if raw == Sym::POP.0
                && let Some(open) = stack.pop()
            {
                matches[i] = open;
                matches[open as usize] = i as u32;
            }
        }
        matches
    }
}

/// Writes a parameter so that the classic notation reads it back to the same value: the
/// shortest round-trip form, and the non-finite values as the expressions that give them
/// (`(1/0)`, `(-1/0)`, `(0/0)`).
pub(crate) fn write_param(out: &mut String, p: f64) {
    if p.is_nan() {
        out.push_str("(0/0)");
    } else if p.is_infinite() {
        out.push_str(if p > 0.0 { "(1/0)" } else { "(-1/0)" });
    } else {
        let _ = write!(out, "{p}");
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flat_strings_store_no_offsets_until_a_parameter_arrives() {
        let mut s = ModuleString::new();
        s.push(Sym(2), &[]);
        s.extend_plain(&[3, 4]);
        assert!(s.is_flat());
        s.push(Sym(5), &[1.5, 2.0]);
        s.extend_plain(&[2]);
        assert!(!s.is_flat());
        assert_eq!(s.len(), 5);
        assert_eq!(s.params(0), &[] as &[f64]);
        assert_eq!(s.params(3), &[1.5, 2.0]);
        assert_eq!(s.params(4), &[] as &[f64]);
        assert_eq!(s.sym(3), Sym(5));
    }

    #[test]
    fn copies_keep_parameters_and_external_slots() {
        let mut a = ModuleString::new();
        a.push(Sym(2), &[1.0]);
        a.push_external(Sym(3), 7);
        a.begin(Sym(4));
        a.push_param(9.0);
        a.end();
        let mut b = ModuleString::new();
        b.append(&a);
        assert_eq!(a, b);
        // Ranges copied in bulk equal module-by-module copies, onto flat and parametric
        // strings alike.
        for (from, to) in [(0, 3), (1, 3), (2, 2), (0, 1)] {
            for mut head in [ModuleString::new(), a.clone()] {
                let mut one = head.clone();
                for i in from..to {
                    one.push_from(&a, i);
                }
                head.extend_from(&a, from..to);
                assert_eq!(head, one, "{from}..{to}");
            }
        }
        assert_eq!(b.external(1), Some(7));
        assert_eq!(b.params(1), &[] as &[f64]);
        assert_eq!(b.sym(1), Sym(3));
        assert_eq!(b.params(2), &[9.0]);
        b.set_external_slot(1, 2);
        assert_eq!(b.external(1), Some(2));
    }

    #[test]
    fn brackets_are_matched_and_unbalanced_ones_marked() {
        let mut s = ModuleString::new();
        // A [ B [ C ] ] ] [
        s.extend_plain(&[2, 0, 3, 0, 4, 1, 1, 1, 0]);
        let m = s.bracket_matches();
        assert_eq!(m[1], 6);
        assert_eq!(m[6], 1);
        assert_eq!(m[3], 5);
        assert_eq!(m[5], 3);
        assert_eq!(m[7], u32::MAX);
        assert_eq!(m[8], u32::MAX);
    }
}
