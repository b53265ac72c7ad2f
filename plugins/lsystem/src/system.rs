//! An L-system's rules and how they are added; compilation ([`compile`]), context matching
//! ([`context`]) and the derivation step ([`derive`](mod@derive)) live in their own files.

mod compile;
mod context;
mod derive;
mod fixed;
mod host;
mod rule;
mod stream;

use self::compile::Tables;
use self::derive::Deriver;
use self::rule::{Kind, Lhs, RuleDef, normalise, pattern_items};
use crate::classic::{self, LhsAst};
use crate::error::LsError;
use crate::expr::{Ast, Expr, Operand};
use crate::module_string::ModuleString;
use crate::symbol::{Sym, SymbolTable};

pub use self::derive::StepOptions;
pub use self::host::{Host, NativeHost};

///
/// ```
/// use pge_lsystem::{ModuleString, NativeHost, StepOptions, SymbolTable, System};
/// use rand_mt::Mt;
///
/// let mut symbols = SymbolTable::new();
/// let mut system = System::new();
/// system.add_production("F -> F[+F]F", None, 0, &mut symbols).unwrap();
/// system.prepare(&symbols).unwrap();
/// let axiom = system.parse_string("F", &mut symbols, &mut || 0.0).unwrap();
/// let mut next = ModuleString::new();
/// let mut rng = Mt::new(1);
/// let opts = StepOptions { step: 1, max_modules: 1000, stream: false };
/// system.step(&axiom, &mut next, &mut NativeHost { rng: &mut rng }, &opts).unwrap();
/// assert_eq!(next.len(), 6);
/// ```
#[derive(Clone, Debug, Default)]
pub struct System {
    declared: Vec<String>,
    defs: Vec<RuleDef>,
    ignore_syms: Vec<Sym>,
    global_names: Vec<String>,
    global_values: Vec<f64>,
    tables: Tables,
    prepared: bool,
}

impl System {
    /// An empty system.
    #[must_use]
    pub fn new() -> System {
        System::default()
    }

    /// Declares multi-letter module names for the classic notation (separated by spaces).
    pub fn declare(&mut self, names: &str) {
        for n in names.split_whitespace() {
            if !self.declared.iter().any(|d| d == n) {
                self.declared.push(n.to_string());
            }
        }
        self.declared
            .sort_by(|a, b| b.len().cmp(&a.len()).then(a.cmp(b)));
        self.prepared = false;
    }

    /// Symbols skipped when matching contexts (names separated by spaces).
    pub fn ignore(&mut self, names: &str, symbols: &mut SymbolTable) {
        for n in names.split_whitespace() {
            let s = symbols.intern(n);
            if !self.ignore_syms.contains(&s) {
                self.ignore_syms.push(s);
            }
        }
        self.prepared = false;
    }

    /// Sets a numeric global, readable by name in classic expressions.
    pub fn set_global(&mut self, name: &str, value: f64) {
        match self.global_names.iter().position(|n| n == name) {
            Some(i) => self.global_values[i] = value,
            None => {
                self.global_names.push(name.to_string());
                self.global_values.push(value);
                self.prepared = false;
            }
        }
    }

    /// A numeric global.
    #[must_use]
    pub fn global(&self, name: &str) -> Option<f64> {
        self.global_names
            .iter()
            .position(|n| n == name)
            .map(|i| self.global_values[i])
    }

    /// Number of rules added.
    #[must_use]
    pub fn rule_count(&self) -> usize {
        self.defs.len()
    }

    /// Whether some rule is external (computed by the host).
    #[must_use]
    pub fn has_external(&self) -> bool {
        self.defs
            .iter()
            .any(|d| matches!(d.kind, Kind::External(_)))
    }

    /// Adds a classic production (`"A(l) : l > 1 -> F(l) [+A(l/2)]"`), with an optional
    /// stochastic weight. `origin` is the host's tag returned in errors.
    pub fn add_production(
        &mut self,
        text: &str,
        weight: Option<f64>,
        origin: u32,
        symbols: &mut SymbolTable,
    ) -> Result<usize, LsError> {
        let err = |message: String| LsError::Rule {
            origin,
            rule: text.trim().into(),
            message,
        };
        if let Some(w) = weight
            && !(w.is_finite() && w > 0.0)
        {
            return Err(err(format!(
                "the weight must be a positive number, not {w}"
            )));
        }
        let p = classic::parse_production(text, &self.declared).map_err(|e| err(e.to_string()))?;
        for m in &p.successor {
            symbols.intern(&m.name);
        }
        let key_end = text
            .find("-->")
            .or_else(|| text.find("->"))
            .unwrap_or(text.len());
        let key = normalise(&text[..key_end]);
        self.push_def(
            text,
            origin,
            &p.lhs,
            symbols,
            |condition| Kind::Classic {
                condition,
                successor: p.successor.clone(),
                weight,
            },
            key,
        )
    }

    /// Adds a rule whose successor the host computes ([`Host::apply`] receives `external`).
    /// The left side is symbol names separated by spaces: `"L < S > R"`.
    pub fn add_external(
        &mut self,
        lhs: &str,
        external: u32,
        origin: u32,
        symbols: &mut SymbolTable,
    ) -> Result<usize, LsError> {
        let err = |message: String| LsError::Rule {
            origin,
            rule: lhs.trim().into(),
            message,
        };
        if lhs.contains(':') {
            return Err(err(
                "a rule function's left side has no ':' condition".into()
            ));
        }
        let parsed = classic::parse_lhs(lhs, &|t| Ok(classic::parse_lua_patterns(t)))
            .map_err(|e| err(e.to_string()))?;
        self.push_def(
            lhs,
            origin,
            &parsed,
            symbols,
            |_| Kind::External(external),
            normalise(lhs),
        )
    }

    fn push_def(
        &mut self,
        text: &str,
        origin: u32,
        lhs: &LhsAst,
        symbols: &mut SymbolTable,
        kind: impl FnOnce(Option<Ast>) -> Kind,
        key: String,
    ) -> Result<usize, LsError> {
        let left = pattern_items(&lhs.left, symbols);
        let pred = pattern_items(std::slice::from_ref(&lhs.pred), symbols)[0];
        let right = pattern_items(&lhs.right, symbols);
        let mut formals = Vec::new();
        for p in lhs
            .left
            .iter()
            .chain(std::iter::once(&lhs.pred))
            .chain(&lhs.right)
        {
            formals.extend(p.formals.iter().flatten().cloned());
        }
        self.defs.push(RuleDef {
            text: text.trim().to_string(),
            origin,
            lhs: Lhs { left, pred, right },
            formals,
            kind: kind(lhs.condition.clone()),
            key,
        });
        self.prepared = false;
        Ok(self.defs.len() - 1)
    }

    /// Parses a classic string whose arguments are constant expressions (an axiom, a
    /// successor string returned by a rule function); names are numeric globals.
    pub fn parse_string(
        &self,
        text: &str,
        symbols: &mut SymbolTable,
        rand: &mut dyn FnMut() -> f64,
    ) -> Result<ModuleString, LsError> {
        self.parse_string_constness(text, symbols, rand)
            .map(|(s, _)| s)
    }

    /// Like [`System::parse_string`], and tells whether the result is the same on every
    /// call: true unless an argument drew `rand()` or read a global (which may change
    /// between steps), so that callers may cache only constant strings.
    pub fn parse_string_constness(
        &self,
        text: &str,
        symbols: &mut SymbolTable,
        rand: &mut dyn FnMut() -> f64,
    ) -> Result<(ModuleString, bool), LsError> {
        let mut constant = true;
        let err = |message: String| LsError::Syntax {
            text: text.trim().into(),
            message,
        };
        let modules =
            classic::split_modules(text, &self.declared).map_err(|e| err(e.to_string()))?;
        let mut out = ModuleString::new();
        out.reserve(modules.len());
        let mut params = Vec::new();
        for (name, args) in modules {
            params.clear();
            for a in args.iter().flatten() {
                if a.trim().is_empty() {
                    return Err(err(format!("empty argument of '{name}'")));
                }
                let v = match literal(a) {
                    Some(v) => v,
                    None => {
                        let ast = crate::expr::parse(a).map_err(|e| err(e.0))?;
                        let e = Expr::compile(&ast, &mut |n| {
                            constant = false;
                            self.global(n).map(Operand::Const)
                        })
                        .map_err(|e| err(e.0))?;
                        let mut drew = false;
                        let v = e.eval(&[], &[], &mut || {
                            drew = true;
                            rand()
                        });
                        constant &= !drew;
                        v
                    }
                };
                if !v.is_finite() {
                    return Err(err(format!("an argument of '{name}' is {v}")));
                }
                params.push(v);
            }
            let sym = symbols.intern(name);
            if (sym == Sym::PUSH || sym == Sym::POP) && !params.is_empty() {
                return Err(err(format!("'{name}' takes no parameters")));
            }
            out.push(sym, &params);
        }
        Ok((out, constant))
    }

    /// Compiles every rule: names resolve against formals and globals, dispatch tables are
    /// built. Called before the first step and again after any change.
    pub fn prepare(&mut self, symbols: &SymbolTable) -> Result<(), LsError> {
        self.tables = Tables::build(&self.defs, &self.ignore_syms, &self.global_names, symbols)?;
        self.prepared = true;
        Ok(())
    }

    /// Matches a left context of symbols (leftmost first) for module `i` of `src`: the path
    /// toward the root, skipping whole branches, climbing out of enclosing ones and skipping
    /// ignored symbols. `matches` pairs brackets (see [`ModuleString::bracket_matches`]); only
    /// the entries of `]` before `i` are read. Pushes the matched indices, leftmost first.
    pub fn match_left_context(
        &self,
        left: &[Sym],
        src: &ModuleString,
        matches: &[u32],
        i: usize,
        out: &mut Vec<usize>,
    ) -> bool {
        context::match_left(
            &self.tables.ignored,
            left.iter().copied(),
            src,
            matches,
            i,
            out,
        )
    }

    /// One derivation step: rewrites `src` into `out` (cleared first).
    ///
    /// # Panics
    /// If the rules changed since the last [`System::prepare`].
    pub fn step<H: Host>(
        &self,
        src: &ModuleString,
        out: &mut ModuleString,
        host: &mut H,
        opts: &StepOptions,
    ) -> Result<(), H::Error> {
        assert!(
            self.prepared,
            "System::prepare must be called after changing the rules"
        );
        self.deriver().step(src, out, host, opts)
    }

    /// One derivation step delivered in pieces, for a caller that streams the result instead
    /// of keeping it: rewrites `src` like [`System::step`], appending the successors of every
    /// `chunk` modules of `src` to `buf` (cleared before each piece) and handing it to `sink`.
    /// The module cap holds for the whole step. Returns the number of modules produced.
    ///
    /// # Panics
    /// If the rules changed since the last [`System::prepare`].
    pub fn step_chunks<H: Host>(
        &self,
        src: &ModuleString,
        buf: &mut ModuleString,
        host: &mut H,
        opts: &StepOptions,
        chunk: usize,
        sink: &mut dyn FnMut(&ModuleString) -> Result<(), H::Error>,
    ) -> Result<u64, H::Error> {
        assert!(
            self.prepared,
            "System::prepare must be called after changing the rules"
        );
        self.deriver()
            .step_chunks(src, buf, host, opts, chunk, sink)
    }

    /// The number of modules one step would make of `src`, without keeping them (checking
    /// the module cap and every rule as [`System::step`] does). A system of fixed successors
    /// is counted without rewriting; otherwise modules without rules are counted, not copied.
    ///
    /// # Panics
    /// If the rules changed since the last [`System::prepare`].
    pub fn step_count<H: Host>(
        &self,
        src: &ModuleString,
        host: &mut H,
        opts: &StepOptions,
    ) -> Result<u64, H::Error> {
        assert!(
            self.prepared,
            "System::prepare must be called after changing the rules"
        );
        let deriver = self.deriver();
        if deriver.plain_fast_path(src, opts) {
            return Ok(deriver.plain_count(src, opts)?);
        }
        if deriver.fixed_pass(src, opts) {
            let mut buf = ModuleString::new();
            return deriver.step_chunks(src, &mut buf, host, opts, 1 << 16, &mut |_| Ok(()));
        }
        deriver.count(src, host, opts)
    }

    /// Whether [`System::count_two_steps`] and [`System::step_chunks_two`] take the steps
    /// depth first, piece by piece, never keeping the string between them: rules without
    /// contexts that draw no random numbers, no rule functions, no streaming interpretation.
    #[must_use]
    pub fn two_steps_depth_first(&self, first: &StepOptions, second: &StepOptions) -> bool {
        self.prepared && self.deriver().depth_first(first, second)
    }

    /// The number of modules the steps `first` and then `second` make of `src`: the first
    /// step's and the second's, the second counted as [`System::step_count`] counts. The
    /// errors (module caps, rules, the host's checks) are those of the two steps taken one
    /// after the other.
    ///
    /// # Panics
    /// If the rules changed since the last [`System::prepare`].
    pub fn count_two_steps<H: Host>(
        &self,
        src: &ModuleString,
        host: &mut H,
        first: &StepOptions,
        second: &StepOptions,
    ) -> Result<(u64, u64), H::Error> {
        assert!(
            self.prepared,
            "System::prepare must be called after changing the rules"
        );
        let deriver = self.deriver();
        if deriver.depth_first(first, second) {
            return deriver.count_two(src, host, first, second);
        }
        let mut between = ModuleString::new();
        deriver.step(src, &mut between, host, first)?;
        let n = self.step_count(&between, host, second)?;
        Ok((between.len() as u64, n))
    }

    /// The steps `first` and then `second` of `src` delivered in pieces of the second step,
    /// as [`System::step_chunks`] delivers one step (`chunk` modules between the steps per
    /// piece). Returns the number of modules of the second step.
    ///
    /// # Panics
    /// If the rules changed since the last [`System::prepare`].
    #[allow(clippy::too_many_arguments)]
    pub fn step_chunks_two<H: Host>(
        &self,
        src: &ModuleString,
        buf: &mut ModuleString,
        host: &mut H,
        first: &StepOptions,
        second: &StepOptions,
        chunk: usize,
        sink: &mut dyn FnMut(&ModuleString) -> Result<(), H::Error>,
    ) -> Result<u64, H::Error> {
        assert!(
            self.prepared,
            "System::prepare must be called after changing the rules"
        );
        let deriver = self.deriver();
        if deriver.depth_first(first, second) {
            return deriver.step_chunks_two(src, buf, host, first, second, chunk, sink);
        }
        let mut between = ModuleString::new();
        deriver.step(src, &mut between, host, first)?;
        deriver.step_chunks(&between, buf, host, second, chunk, sink)
    }

    fn deriver(&self) -> Deriver<'_> {
        Deriver {
            defs: &self.defs,
            globals: &self.global_values,
            tables: &self.tables,
            args: self
                .tables
                .exprs
                .iter()
                .map(|e| e.bind(&self.global_values))
                .collect(),
        }
    }
}

/// The value of an argument that is one unsigned decimal number (`1`, `0.25`, `.5`), read
/// as the expression parser reads a number token; `None` for any other argument.
fn literal(text: &str) -> Option<f64> {
    let t = text.trim();
    let bytes = t.as_bytes();
    let numeric = bytes.iter().any(u8::is_ascii_digit)
        && bytes.iter().all(|b| b.is_ascii_digit() || *b == b'.')
        && bytes.iter().filter(|b| **b == b'.').count() <= 1;
    if numeric { t.parse().ok() } else { None }
}

#[cfg(test)]
mod tests;
