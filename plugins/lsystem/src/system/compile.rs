//! Compilation: rules to bytecode, stochastic groups and the per-symbol dispatch tables.

use super::dispatch::Dispatch;
use super::fixed::{FixedRule, FixedTables};
use super::rule::{Kind, RuleDef};
use crate::error::LsError;
use crate::expr::{Expr, Operand};
use crate::symbol::{Sym, SymbolTable};

/// A compiled successor: its modules' symbols and, for each module, where its parameters
/// end among the successor's (cumulative counts), the expressions of which lie one after the
/// other in [`Tables::exprs`] from `args` on. A successor is written with one copy of its
/// symbols and offsets ([`ModuleString::push_modules`](crate::ModuleString::push_modules)).
#[derive(Clone, Debug)]
pub(super) struct Successor {
    pub(super) syms: Box<[u32]>,
    pub(super) ends: Box<[u32]>,
    pub(super) args: u32,
}

impl Successor {
    /// The number of parameter expressions.
    #[inline]
    pub(super) fn arg_count(&self) -> usize {
        self.ends.last().map_or(0, |e| *e as usize)
    }

    /// The range of its parameter expressions in [`Tables::exprs`].
    #[inline]
    pub(super) fn arg_range(&self) -> std::ops::Range<usize> {
        self.args as usize..self.args as usize + self.arg_count()
    }
}

/// A compiled rule's successor.
#[derive(Clone, Debug)]
pub(super) enum CKind {
    Classic {
        /// The condition's place in [`Tables::exprs`].
        condition: Option<u32>,
        successor: Successor,
        /// Stochastic alternatives (cumulative normalised weight, rule), on the group's head.
        choices: Option<Box<[(f64, usize)]>>,
    },
    External(u32),
}

/// A compiled rule.
#[derive(Clone, Debug)]
pub(super) struct Compiled {
    pub(super) kind: CKind,
    /// A non-head member of a stochastic group: reached through its head only.
    pub(super) skip: bool,
    /// The symbol of a one-symbol left context, tested before the full match.
    pub(super) left1: Option<Sym>,
    /// The symbol of a one-symbol right context (not a bracket), tested likewise.
    pub(super) right1: Option<Sym>,
    /// For a rule whose whole left side is `left1`, the predecessor and `right1` (no
    /// parameters, condition or alternatives) and whose successor is fixed symbols: that
    /// successor's place in [`Tables::plain_pool`] (start, length).
    pub(super) fixed: Option<(u32, u32)>,
}

/// The compiled form of a system's rules, rebuilt by [`Tables::build`] after every change.
#[derive(Clone, Debug, Default)]
pub(super) struct Tables {
    pub(super) rules: Vec<Compiled>,
    /// Every rule's condition and parameter expressions, bound to the globals' values at
    /// each step (see [`crate::expr::Arg`]).
    pub(super) exprs: Vec<Expr>,
    pub(super) dispatch: Vec<Dispatch>,
    pub(super) rule_lists: Vec<u32>,
    pub(super) plain_pool: Vec<u32>,
    pub(super) ignored: Vec<bool>,
    pub(super) uses_context: bool,
    /// Some rule draws random numbers (a stochastic choice, `rand()` in an expression).
    pub(super) random: bool,
    pub(super) all_plain: bool,
    /// When every rule reached through [`Dispatch::Rules`] has a `fixed` successor, the
    /// tables of the pass over strings without parameters (see [`super::fixed`]).
    pub(super) fixed: Option<FixedTables>,
    /// For every symbol, the most modules and parameters a module of it becomes (a copied
    /// module's own parameters not included); empty when a rule function may apply (its
    /// successors are unbounded).
    pub(super) growth: Vec<(u32, u32)>,
}

impl Tables {
    /// Compiles every rule: names resolve against formals and `global_names`, dispatch
    /// tables are built.
    pub(super) fn build(
        defs: &[RuleDef],
        ignore_syms: &[Sym],
        global_names: &[String],
        symbols: &SymbolTable,
    ) -> Result<Tables, LsError> {
        let n = symbols.len();
        let mut rules = Vec::with_capacity(defs.len());
        let mut exprs = Vec::new();
        for def in defs {
            rules.push(compile(def, global_names, symbols, &mut exprs)?);
        }
        // Stochastic groups: alternatives with the same left side; the first is the head.
        let mut seen: Vec<(String, usize)> = Vec::new();
        let mut members: Vec<Vec<(f64, usize)>> = Vec::new();
        for (i, def) in defs.iter().enumerate() {
            if let Kind::Classic {
                weight: Some(w), ..
            } = def.kind
            {
                match seen.iter().find(|(k, _)| *k == def.key) {
                    Some((_, g)) => {
                        members[*g].push((w, i));
                        rules[i].skip = true;
                    }
                    None => {
                        seen.push((def.key.clone(), members.len()));
                        members.push(vec![(w, i)]);
                    }
                }
            }
        }
        for group in members.iter().filter(|g| g.len() > 1) {
            let total: f64 = group.iter().map(|m| m.0).sum();
            let mut acc = 0.0;
            let choices: Box<[(f64, usize)]> = group
                .iter()
                .map(|&(w, r)| {
                    acc += w / total;
                    (acc, r)
                })
                .collect();
            if let CKind::Classic { choices: c, .. } = &mut rules[group[0].1].kind {
                *c = Some(choices);
            }
        }
        let mut plain_pool = Vec::new();
        for (rule, def) in rules.iter_mut().zip(defs) {
            let lhs = &def.lhs;
            let bare = |items: &[super::rule::PatternItem]| items.iter().all(|p| p.arity.is_none());
            let simple_lhs = lhs.pred.arity.is_none()
                && bare(&lhs.left)
                && bare(&lhs.right)
                && (lhs.left.is_empty() || rule.left1.is_some())
                && (lhs.right.is_empty() || rule.right1.is_some());
            if let CKind::Classic {
                condition: None,
                successor,
                choices: None,
            } = &rule.kind
                && simple_lhs
                && !rule.skip
                && successor.arg_count() == 0
            {
                let start = plain_pool.len() as u32;
                plain_pool.extend_from_slice(&successor.syms);
                rule.fixed = Some((start, successor.syms.len() as u32));
            }
        }
        let mut ignored = vec![false; n];
        for s in ignore_syms {
            ignored[s.index()] = true;
        }
        let uses_context = defs
            .iter()
            .any(|d| !d.lhs.left.is_empty() || !d.lhs.right.is_empty());
        let mut dispatch = vec![Dispatch::Copy; n];
        let mut rule_lists = Vec::new();
        for (s, slot) in dispatch.iter_mut().enumerate() {
            let list: Vec<u32> = (0..defs.len())
                .filter(|&r| defs[r].lhs.pred.sym.index() == s && !rules[r].skip)
                .map(|r| r as u32)
                .collect();
            if list.is_empty() {
                continue;
            }
            let r = list[0] as usize;
            let def = &defs[r];
            let plain = list.len() == 1
                && def.lhs.left.is_empty()
                && def.lhs.right.is_empty()
                && def.lhs.pred.arity.is_none()
                && matches!(&rules[r].kind, CKind::Classic { condition: None, successor, choices: None }
                    if successor.arg_count() == 0);
            if plain {
                let CKind::Classic { successor, .. } = &rules[r].kind else {
                    continue;
                };
                let start = plain_pool.len() as u32;
                plain_pool.extend_from_slice(&successor.syms);
                *slot = Dispatch::Plain {
                    start,
                    len: successor.syms.len() as u32,
                };
            } else if list.len() == 1
                && def.lhs.left.is_empty()
                && def.lhs.right.is_empty()
                && matches!(&rules[r].kind, CKind::Classic { choices: None, .. })
            {
                *slot = Dispatch::Direct { rule: r as u32 };
            } else {
                let start = rule_lists.len() as u32;
                rule_lists.extend(&list);
                *slot = Dispatch::Rules {
                    start,
                    len: list.len() as u32,
                };
            }
        }
        let all_plain = dispatch
            .iter()
            .all(|d| matches!(d, Dispatch::Copy | Dispatch::Plain { .. }));
        let all_fixed = !dispatch
            .iter()
            .any(|d| matches!(d, Dispatch::Direct { .. }))
            && rule_lists
                .iter()
                .all(|&r| rules[r as usize].fixed.is_some());
        let fixed_lists = if all_fixed {
            rule_lists
                .iter()
                .filter_map(|&r| {
                    let rule = &rules[r as usize];
                    let (start, len) = rule.fixed?;
                    Some(FixedRule {
                        left: rule.left1.map_or(FixedRule::ANY, |s| s.0),
                        right: rule.right1.map_or(FixedRule::ANY, |s| s.0),
                        start,
                        len,
                    })
                })
                .collect()
        } else {
            Vec::new()
        };
        let growth =
            if rules.iter().any(|r| matches!(r.kind, CKind::External(_))) {
                Vec::new()
            } else {
                (0..n)
                    .map(|s| match dispatch[s] {
                        Dispatch::Copy => (1, 0),
                        Dispatch::Plain { len, .. } => (len, 0),
                        Dispatch::Direct { rule } => alternatives(&rules, rule as usize)
                            .iter()
                            .fold((1, 0), |(m, p), succ| {
                                (
                                    m.max(succ.syms.len() as u32),
                                    p.max(succ.arg_count() as u32),
                                )
                            }),
                        Dispatch::Rules { start, len } => rule_lists
                            [start as usize..(start + len) as usize]
                            .iter()
                            .flat_map(|&r| alternatives(&rules, r as usize))
                            .fold((1, 0), |(m, p), succ| {
                                (
                                    m.max(succ.syms.len() as u32),
                                    p.max(succ.arg_count() as u32),
                                )
                            }),
                    })
                    .collect()
            };
        let fixed = if all_fixed {
            FixedTables::build(&dispatch, &ignored, &fixed_lists, &plain_pool)
        } else {
            None
        };
        let random = exprs.iter().any(Expr::is_random)
            || rules.iter().any(|r| {
                matches!(
                    r.kind,
                    CKind::Classic {
                        choices: Some(_),
                        ..
                    }
                )
            });
        Ok(Tables {
            random,
            rules,
            exprs,
            growth,
            fixed,
            dispatch,
            rule_lists,
            plain_pool,
            ignored,
            uses_context,
            all_plain,
        })
    }
}

/// The successors rule `r` may write: its own and its stochastic alternatives'.
fn alternatives(rules: &[Compiled], r: usize) -> Vec<&Successor> {
    let CKind::Classic {
        successor, choices, ..
    } = &rules[r].kind
    else {
        return Vec::new();
    };
    let mut all = vec![successor];
    for &(_, alt) in choices.iter().flatten() {
        if let CKind::Classic { successor, .. } = &rules[alt].kind {
            all.push(successor);
        }
    }
    all
}

/// Compiles one rule, appending its expressions to `exprs`; names resolve against its
/// formals, then `global_names`.
fn compile(
    def: &RuleDef,
    global_names: &[String],
    symbols: &SymbolTable,
    exprs: &mut Vec<Expr>,
) -> Result<Compiled, LsError> {
    let err = |message: String| LsError::Rule {
        origin: def.origin,
        rule: def.text.clone(),
        message,
    };
    let kind = match &def.kind {
        Kind::External(id) => CKind::External(*id),
        Kind::Classic {
            condition,
            successor,
            ..
        } => {
            let mut resolve = |name: &str| {
                if let Some(i) = def.formals.iter().position(|f| f == name) {
                    return Some(Operand::Param(i as u16));
                }
                global_names
                    .iter()
                    .position(|g| g == name)
                    .map(|i| Operand::Global(i as u16))
            };
            let condition = match condition {
                Some(c) => {
                    exprs.push(
                        Expr::compile(c, &mut resolve)
                            .map_err(|e| err(format!("condition: {e}")))?,
                    );
                    Some(exprs.len() as u32 - 1)
                }
                None => None,
            };
            let args = exprs.len() as u32;
            let mut syms = Vec::with_capacity(successor.len());
            let mut ends = Vec::with_capacity(successor.len());
            for m in successor {
                let sym = symbols
                    .get(&m.name)
                    .ok_or_else(|| err(format!("symbol '{}' was not interned", m.name)))?;
                if (sym == Sym::PUSH || sym == Sym::POP) && !m.args.is_empty() {
                    return Err(err(format!("'{}' takes no parameters", m.name)));
                }
                for a in &m.args {
                    exprs.push(Expr::compile(a, &mut resolve).map_err(|e| err(e.to_string()))?);
                }
                syms.push(sym.0);
                ends.push(exprs.len() as u32 - args);
            }
            CKind::Classic {
                condition,
                successor: Successor {
                    syms: syms.into_boxed_slice(),
                    ends: ends.into_boxed_slice(),
                    args,
                },
                choices: None,
            }
        }
    };
    let lhs = &def.lhs;
    let left1 = match lhs.left.as_slice() {
        [one] => Some(one.sym),
        _ => None,
    };
    let right1 = match lhs.right.as_slice() {
        [one] if one.sym != Sym::PUSH && one.sym != Sym::POP => Some(one.sym),
        _ => None,
    };
    Ok(Compiled {
        kind,
        skip: false,
        left1,
        right1,
        fixed: None,
    })
}
