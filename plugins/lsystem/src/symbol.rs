//! Interned module names.

use std::collections::HashMap;

/// An interned module name: a small integer that indexes dispatch tables.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Sym(pub u32);

impl Sym {
    /// The branch opening `[`.
    pub const PUSH: Sym = Sym(0);
    /// The branch closing `]`.
    pub const POP: Sym = Sym(1);

    /// The index of this symbol in per-symbol tables.
    #[must_use]
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

/// The names of all symbols of one L-system; `[` and `]` are always symbols 0 and 1.
#[derive(Clone, Debug)]
pub struct SymbolTable {
    names: Vec<Box<str>>,
    ids: HashMap<Box<str>, Sym>,
}

impl Default for SymbolTable {
    fn default() -> Self {
        let mut table = SymbolTable {
            names: Vec::new(),
            ids: HashMap::new(),
        };
        table.intern("[");
        table.intern("]");
        table
    }
}

impl SymbolTable {
    /// A table holding only `[` and `]`.
    #[must_use]
    pub fn new() -> SymbolTable {
        SymbolTable::default()
    }

    /// The symbol called `name`, created on first use.
    pub fn intern(&mut self, name: &str) -> Sym {
        if let Some(s) = self.ids.get(name) {
            return *s;
        }
        let sym = Sym(self.names.len() as u32);
        self.names.push(name.into());
        self.ids.insert(name.into(), sym);
        sym
    }

    /// The symbol called `name`, if it exists.
    #[must_use]
    pub fn get(&self, name: &str) -> Option<Sym> {
        self.ids.get(name).copied()
    }

    /// The name of `sym`.
    ///
    /// # Panics
    /// If `sym` was not created by this table.
    #[must_use]
    pub fn name(&self, sym: Sym) -> &str {
        &self.names[sym.index()]
    }

    /// Number of symbols.
    #[must_use]
    pub fn len(&self) -> usize {
        self.names.len()
    }

    /// Always false: `[` and `]` exist from the start.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.names.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn brackets_are_predefined_and_names_are_interned_once() {
        let mut t = SymbolTable::new();
        assert_eq!(t.get("["), Some(Sym::PUSH));
        assert_eq!(t.get("]"), Some(Sym::POP));
        let a = t.intern("Apex");
        assert_eq!(t.intern("Apex"), a);
        assert_eq!(t.name(a), "Apex");
        assert_eq!(t.len(), 3);
        assert_eq!(t.get("B"), None);
    }
}
