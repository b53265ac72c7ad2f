//! An L-system's rules and how they are added; compilation ([`compile`]) makes the
//! [`Prepared`] form that derives ([`prepared`]): what each symbol turns into
//! ([`dispatch`]) and, when every successor is fixed, the tables of a one-pass rewrite
//! ([`fixed`]). Context matching ([`context`]), the derivation step
//! ([`derive`](mod@derive)), counting ([`count`]) and the depth-first pipeline ([`stream`])
//! live in their own files.

mod compile;
mod context;
mod count;
mod derive;
mod dispatch;
mod fixed;
mod host;
mod prepared;
mod rule;
mod stream;

use self::compile::Tables;
use self::rule::{Kind, Lhs, RuleDef, normalise, pattern_items};
use crate::classic::{self, LhsAst};
use crate::error::LsError;
use crate::expr::{Ast, Expr, Operand};
use crate::module_string::ModuleString;
use crate::symbol::{Sym, SymbolTable};

pub use self::host::{Host, NativeHost};
pub use self::prepared::{DeriveOptions, Output, Prepared};

/// An L-system's rules as they are added: classic productions, rules computed by the host,
/// declared names, ignored symbols and numeric globals. [`System::prepare`] compiles them
/// into the [`Prepared`] form that derives.
///
/// ```
/// use pge_lsystem::{DeriveOptions, ModuleString, NativeHost, Output, SymbolTable, System};
/// use rand_mt::Mt;
///
/// let mut symbols = SymbolTable::new();
/// let mut system = System::new();
/// system.add_production("F -> F[+F]F", None, 0, &mut symbols).unwrap();
/// let prepared = system.prepare(&symbols).unwrap();
/// let axiom = system.parse_string("F", &mut symbols, &mut || 0.0).unwrap();
/// let mut next = ModuleString::new();
/// let mut rng = Mt::new(1);
/// let opts = DeriveOptions::new(1, 1, 1000);
/// let host = &mut NativeHost { rng: &mut rng };
/// prepared.derive(&axiom, &opts, host, Output::Keep(&mut next)).unwrap();
/// assert_eq!(next.len(), 6);
/// ```
#[derive(Clone, Debug, Default)]
pub struct System {
    declared: Vec<String>,
    defs: Vec<RuleDef>,
    ignore_syms: Vec<Sym>,
    global_names: Vec<String>,
    global_values: Vec<f64>,
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
    }

    /// Symbols skipped when matching contexts (names separated by spaces).
    pub fn ignore(&mut self, names: &str, symbols: &mut SymbolTable) {
        for n in names.split_whitespace() {
            let s = symbols.intern(n);
            if !self.ignore_syms.contains(&s) {
                self.ignore_syms.push(s);
            }
        }
    }

    /// Sets a numeric global, readable by name in classic expressions.
    pub fn set_global(&mut self, name: &str, value: f64) {
        match self.global_names.iter().position(|n| n == name) {
            Some(i) => self.global_values[i] = value,
            None => {
                self.global_names.push(name.to_string());
                self.global_values.push(value);
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

    /// Compiles every rule (names resolve against formals and globals, dispatch tables are
    /// built) into the form that derives. A [`Prepared`] system does not follow later
    /// changes of this one: prepare it again after them.
    pub fn prepare(&self, symbols: &SymbolTable) -> Result<Prepared, LsError> {
        Ok(Prepared {
            defs: self.defs.clone().into(),
            global_values: self.global_values.clone(),
            tables: Tables::build(&self.defs, &self.ignore_syms, &self.global_names, symbols)?,
        })
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
