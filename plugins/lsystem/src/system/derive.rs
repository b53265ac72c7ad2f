//! The derivation step: every module of a string rewritten by the first rule that applies.

use super::compile::{CKind, Tables};
use super::context::{match_left, match_right};
use super::dispatch::Dispatch;
use super::fixed::{FixedTables, LeftCodes};
use super::host::Host;
use super::rule::RuleDef;
use crate::error::LsError;
use crate::expr::Arg;
use crate::module_string::ModuleString;
use crate::symbol::Sym;

/// Options of one derivation step.
#[derive(Clone, Copy, Debug)]
pub struct StepOptions {
    /// The step's number (1-based), for error messages.
    pub step: u32,
    /// The module cap.
    pub max_modules: usize,
    /// Call [`Host::interpret`] after each module's successor.
    pub stream: bool,
}

/// The symbol a one-symbol left context of module `i` would match (as
/// [`super::context::match_left`] walks: skipping branches, climbing out of enclosing ones,
/// skipping ignored symbols).
#[inline]
fn left_neighbour(ignored: &[bool], src: &ModuleString, matches: &[u32], i: usize) -> Option<Sym> {
    let mut j = i;
    loop {
        if j == 0 {
            return None;
        }
        j -= 1;
        let s = src.sym(j);
        if s == Sym::POP {
            match matches[j] {
                u32::MAX => return None,
                open => j = open as usize,
            }
        } else if s != Sym::PUSH && !ignored.get(s.index()).copied().unwrap_or(false) {
            return Some(s);
        }
    }
}

/// The symbol a one-symbol right context (not a bracket) of module `i` would match (as
/// [`super::context::match_right`] walks: skipping branches and ignored symbols).
#[inline]
fn right_neighbour(ignored: &[bool], src: &ModuleString, matches: &[u32], i: usize) -> Option<Sym> {
    let n = src.len();
    let mut j = i + 1;
    while j < n {
        let s = src.sym(j);
        if ignored.get(s.index()).copied().unwrap_or(false) {
            j += 1;
        } else if s == Sym::PUSH {
            match matches[j] {
                u32::MAX => return None,
                close => j = close as usize + 1,
            }
        } else {
            return Some(s);
        }
    }
    None
}

/// Reused buffers of a step: the modules a rule matched and their gathered parameters; and,
/// for the pass over a string without parameters, the left neighbour of the next module.
#[derive(Default)]
pub(super) struct Scratch {
    pub(super) matched: Vec<usize>,
    pub(super) gathered: Vec<f64>,
    /// The left context codes of the pass of [`super::fixed`].
    pub(super) lefts: LeftCodes,
}

/// What context matching reads during a step: the bracket pairs (general loop; empty when
/// no rule has a context), or the right neighbours' codes of the pass of
/// [`super::fixed`] (empty when no rule has a right context).
pub(super) enum Context {
    Brackets(Vec<u32>),
    Rights(Vec<u8>),
}

impl Context {
    /// No context to read.
    pub(super) const NONE: Context = Context::Brackets(Vec::new());

    /// The bracket pairs (empty for the pass of [`super::fixed`]).
    fn brackets(&self) -> &[u32] {
        match self {
            Context::Brackets(m) => m,
            Context::Rights(_) => &[],
        }
    }
}

/// A compiled system's rules, ready to derive.
pub(super) struct Deriver<'a> {
    /// The rules as added (left sides, origins and texts for errors).
    pub(super) defs: &'a [RuleDef],
    /// The values of the numeric globals.
    pub(super) globals: &'a [f64],
    /// The compiled rules and dispatch tables.
    pub(super) tables: &'a Tables,
    /// [`Tables::exprs`] bound to the globals' values.
    pub(super) args: Vec<Arg<'a>>,
}

impl Deriver<'_> {
    /// One derivation step: rewrites `src` into `out` (cleared first).
    pub(super) fn step<H: Host>(
        &self,
        src: &ModuleString,
        out: &mut ModuleString,
        host: &mut H,
        opts: &StepOptions,
    ) -> Result<(), H::Error> {
        out.clear();
        if self.plain_fast_path(src, opts) {
            let total = self.plain_count(src, opts)?;
            out.reserve(total as usize);
            for chunk in src.raw_syms().chunks(1 << 16) {
                host.check()?;
                self.expand_plain(chunk, out);
            }
            return Ok(());
        }
        let matches = self.context_table(src, opts);
        if !self.fixed_pass(src, opts) {
            self.reserve(src, out, opts);
        }
        let mut scratch = Scratch::default();
        self.step_range(
            src,
            0..src.len(),
            &matches,
            0,
            out,
            host,
            opts,
            &mut scratch,
        )
    }

    /// One derivation step delivered in pieces: the successors of every `chunk` modules of
    /// `src` are appended to `buf` (cleared before each piece) and handed to `sink`. The
    /// module cap holds for the whole step. Returns the number of modules produced.
    pub(super) fn step_chunks<H: Host>(
        &self,
        src: &ModuleString,
        buf: &mut ModuleString,
        host: &mut H,
        opts: &StepOptions,
        chunk: usize,
        sink: &mut dyn FnMut(&ModuleString) -> Result<(), H::Error>,
    ) -> Result<u64, H::Error> {
        let chunk = chunk.max(1);
        let plain = self.plain_fast_path(src, opts);
        let matches = if plain {
            Context::NONE
        } else {
            self.context_table(src, opts)
        };
        let mut scratch = Scratch::default();
        let mut total = 0u64;
        let mut start = 0;
        while start < src.len() {
            let end = (start + chunk).min(src.len());
            buf.clear();
            if plain {
                host.check()?;
                self.expand_plain(&src.raw_syms()[start..end], buf);
                if total + buf.len() as u64 > opts.max_modules as u64 {
                    return Err(self.too_many(opts, total + buf.len() as u64).into());
                }
            } else {
                self.step_range(
                    src,
                    start..end,
                    &matches,
                    total,
                    buf,
                    host,
                    opts,
                    &mut scratch,
                )?;
            }
            total += buf.len() as u64;
            sink(buf)?;
            start = end;
        }
        Ok(total)
    }

    /// Reserves room in `out` for the most modules and parameters a step can make of a long
    /// `src` (see [`Tables::growth`]), so that the step's output is allocated once instead of
    /// grown by copies; nothing when the bound passes the module cap or is unknown.
    fn reserve(&self, src: &ModuleString, out: &mut ModuleString, opts: &StepOptions) {
        let growth = &self.tables.growth;
        if src.len() < 1 << 16 || growth.is_empty() {
            return;
        }
        let (mut modules, mut params) = (0u64, src.param_count() as u64);
        for i in 0..src.len() {
            let (m, p) = growth.get(src.sym(i).index()).copied().unwrap_or((1, 0));
            modules += u64::from(m);
            params += u64::from(p);
        }
        if modules <= opts.max_modules as u64 {
            out.reserve_with_params(modules as usize, params as usize);
        }
    }

    /// Whether a step of `src` copies fixed strings of symbols only (no parameters, no
    /// conditions, no contexts, no streaming interpretation).
    pub(super) fn plain_fast_path(&self, src: &ModuleString, opts: &StepOptions) -> bool {
        self.tables.all_plain && src.is_flat() && !opts.stream
    }

    pub(super) fn too_many(&self, opts: &StepOptions, count: u64) -> LsError {
        LsError::TooManyModules {
            step: opts.step,
            count,
            max: opts.max_modules,
        }
    }

    /// Whether a step of `src` takes the pass of [`Deriver::step_fixed`].
    pub(super) fn fixed_pass(&self, src: &ModuleString, opts: &StepOptions) -> bool {
        self.tables.fixed.is_some() && src.is_flat() && !opts.stream
    }

    /// What context matching reads during a step: the right neighbours of the modules for
    /// [`Deriver::step_fixed`] (when a rule has a right context), the bracket pairs for the
    /// general path (when a rule has a context).
    pub(super) fn context_table(&self, src: &ModuleString, opts: &StepOptions) -> Context {
        match &self.tables.fixed {
            Some(fixed) if self.fixed_pass(src, opts) => Context::Rights(if fixed.uses_right {
                fixed.right_codes(src)
            } else {
                Vec::new()
            }),
            _ => Context::Brackets(self.bracket_matches(src)),
        }
    }

    pub(super) fn bracket_matches(&self, src: &ModuleString) -> Vec<u32> {
        if self.tables.uses_context {
            src.bracket_matches()
        } else {
            Vec::new()
        }
    }

    /// Appends the successors of the parameterless modules `syms` of a plain system.
    #[inline]
    pub(super) fn expand_plain(&self, syms: &[u32], out: &mut ModuleString) {
        for &s in syms {
            match self.tables.dispatch.get(s as usize) {
                Some(Dispatch::Plain { start, len }) => out.extend_plain(
                    &self.tables.plain_pool[*start as usize..(*start + *len) as usize],
                ),
                _ => out.extend_plain(&[s]),
            }
        }
    }

    /// Rewrites the modules `range` of `src`, appending to `out`; `before` modules were
    /// produced earlier in this step (for the module cap). The ranges of one step follow
    /// each other from the start of `src`.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn step_range<H: Host>(
        &self,
        src: &ModuleString,
        range: std::ops::Range<usize>,
        context: &Context,
        before: u64,
        out: &mut ModuleString,
        host: &mut H,
        opts: &StepOptions,
        scratch: &mut Scratch,
    ) -> Result<(), H::Error> {
        if let Some(fixed) = &self.tables.fixed
            && let Context::Rights(rights) = context
            && self.fixed_pass(src, opts)
            && out.is_flat()
        {
            return self.step_fixed(fixed, src, range, rights, before, out, host, opts, scratch);
        }
        let matches = context.brackets();
        let max = opts.max_modules as u64;
        let base = out.len() as u64;
        let end = range.end;
        let mut i = range.start;
        // The deadline is checked every 65 536 modules of `src` (and once per range).
        let mut next_check = i;
        while i < end {
            if i >= next_check {
                host.check()?;
                next_check = (i | 0xFFFF) + 1;
            }
            let from = out.len();
            let s = src.sym(i);
            let mut bulk = false;
            match self.tables.dispatch.get(s.index()) {
                Some(Dispatch::Plain { start, len }) => {
                    out.extend_plain(
                        &self.tables.plain_pool[*start as usize..(*start + *len) as usize],
                    );
                    i += 1;
                }
                Some(Dispatch::Direct { rule }) => {
                    if !self.apply_direct(*rule as usize, src, i, out, host)? {
                        out.push_from(src, i);
                    }
                    i += 1;
                }
                Some(Dispatch::Rules { start, len }) => {
                    let list = &self.tables.rule_lists[*start as usize..(*start + *len) as usize];
                    let applied = self.apply_rules(
                        list,
                        src,
                        matches,
                        i,
                        out,
                        host,
                        &mut scratch.matched,
                        &mut scratch.gathered,
                    )?;
                    if !applied {
                        out.push_from(src, i);
                    }
                    i += 1;
                }
                _ => {
                    // A run of modules without rules: copied in bulk.
                    let mut j = i + 1;
                    let stop = end.min(next_check);
                    while j < stop
                        && matches!(
                            self.tables.dispatch.get(src.sym(j).index()),
                            None | Some(Dispatch::Copy)
                        )
                    {
                        j += 1;
                    }
                    out.extend_from(src, i..j);
                    bulk = true;
                    i = j;
                }
            }
            let count = before + out.len() as u64 - base;
            if count > max {
                // A bulk copy stops where a module-by-module one would have.
                let count = if bulk { count.min(max + 1) } else { count };
                return Err(self.too_many(opts, count).into());
            }
            if opts.stream {
                host.interpret(out, from)?;
            }
        }
        Ok(())
    }

    #[allow(clippy::too_many_arguments)]
    pub(super) fn apply_rules<H: Host>(
        &self,
        list: &[u32],
        src: &ModuleString,
        matches: &[u32],
        i: usize,
        out: &mut ModuleString,
        host: &mut H,
        matched: &mut Vec<usize>,
        gathered: &mut Vec<f64>,
    ) -> Result<bool, H::Error> {
        for &r in list {
            let r = r as usize;
            // One-symbol contexts, the common case, are rejected without the full match.
            let compiled = &self.tables.rules[r];
            if let Some(q) = compiled.left1
                && left_neighbour(&self.tables.ignored, src, matches, i) != Some(q)
            {
                continue;
            }
            if let Some(q) = compiled.right1
                && right_neighbour(&self.tables.ignored, src, matches, i) != Some(q)
            {
                continue;
            }
            let def = &self.defs[r];
            let lhs = &def.lhs;
            matched.clear();
            if !lhs.left.is_empty()
                && !match_left(
                    &self.tables.ignored,
                    lhs.left.iter().map(|p| p.sym),
                    src,
                    matches,
                    i,
                    matched,
                )
            {
                continue;
            }
            matched.push(i);
            if !lhs.right.is_empty()
                && !match_right(&self.tables.ignored, &lhs.right, src, matches, i, matched)
            {
                continue;
            }
            match &self.tables.rules[r].kind {
                CKind::External(id) => {
                    if host.apply(*id, matched, src, out)? {
                        return Ok(true);
                    }
                }
                CKind::Classic {
                    condition,
                    successor,
                    choices,
                } => {
                    let params: &[f64] = if lhs.left.is_empty() && lhs.right.is_empty() {
                        match lhs.pred.arity {
                            None => &[],
                            Some(k) => {
                                self.check_arity(def, src, i, k)?;
                                src.params(i)
                            }
                        }
                    } else {
                        gathered.clear();
                        let items = lhs.left.iter().chain(std::iter::once(&lhs.pred)).chain(
                            lhs.right
                                .iter()
                                .filter(|p| p.sym != Sym::PUSH && p.sym != Sym::POP),
                        );
                        for (p, &m) in items.zip(matched.iter()) {
                            if let Some(k) = p.arity {
                                self.check_arity(def, src, m, k)?;
                                gathered.extend_from_slice(src.params(m));
                            }
                        }
                        gathered
                    };
                    let globals = self.globals;
                    if let Some(c) = condition
                        && self.args[*c as usize].eval(params, globals, &mut || host.random())
                            == 0.0
                    {
                        continue;
                    }
                    let (succ, def) = match choices {
                        Some(choices) => {
                            let x = host.random();
                            let pick = choices
                                .iter()
                                .find(|(cum, _)| x < *cum)
                                .map_or(choices[choices.len() - 1].1, |c| c.1);
                            match &self.tables.rules[pick].kind {
                                CKind::Classic { successor, .. } => (successor, &self.defs[pick]),
                                CKind::External(_) => (successor, def),
                            }
                        }
                        None => (successor, def),
                    };
                    let mark = out.param_count();
                    out.push_modules(
                        &succ.syms,
                        &succ.ends,
                        self.args[succ.arg_range()]
                            .iter()
                            .map(|a| a.eval(params, globals, &mut || host.random())),
                    );
                    if let Some(v) = out.params_since(mark).iter().find(|v| !v.is_finite()) {
                        return Err(LsError::Rule {
                            origin: def.origin,
                            rule: def.text.clone(),
                            message: format!("a parameter of the successor evaluated to {v}"),
                        }
                        .into());
                    }
                    return Ok(true);
                }
            }
        }
        Ok(false)
    }

    /// The parameters rule `r` (without contexts) reads from module `i`, and whether its
    /// condition holds for them.
    #[inline]
    pub(super) fn direct_params<'s, H: Host>(
        &self,
        r: usize,
        condition: Option<u32>,
        src: &'s ModuleString,
        i: usize,
        host: &mut H,
    ) -> Result<Option<&'s [f64]>, LsError> {
        let def = &self.defs[r];
        let params: &[f64] = match def.lhs.pred.arity {
            None => &[],
            Some(k) => {
                self.check_arity(def, src, i, k)?;
                src.params(i)
            }
        };
        if let Some(c) = condition
            && self.args[c as usize].eval(params, self.globals, &mut || host.random()) == 0.0
        {
            return Ok(None);
        }
        Ok(Some(params))
    }

    /// Applies [`Dispatch::Direct`] rule `r` to module `i` of `src` as
    /// [`Deriver::apply_rules`] would: false when its condition fails.
    #[inline]
    fn apply_direct<H: Host>(
        &self,
        r: usize,
        src: &ModuleString,
        i: usize,
        out: &mut ModuleString,
        host: &mut H,
    ) -> Result<bool, H::Error> {
        let CKind::Classic {
            condition,
            successor,
            ..
        } = &self.tables.rules[r].kind
        else {
            return Ok(false);
        };
        let Some(params) = self.direct_params(r, *condition, src, i, host)? else {
            return Ok(false);
        };
        let globals = self.globals;
        let mark = out.param_count();
        out.push_modules(
            &successor.syms,
            &successor.ends,
            self.args[successor.arg_range()]
                .iter()
                .map(|a| a.eval(params, globals, &mut || host.random())),
        );
        if let Some(v) = out.params_since(mark).iter().find(|v| !v.is_finite()) {
            return Err(self.not_finite(r, *v).into());
        }
        Ok(true)
    }

    #[cold]
    pub(super) fn not_finite(&self, r: usize, v: f64) -> LsError {
        let def = &self.defs[r];
        LsError::Rule {
            origin: def.origin,
            rule: def.text.clone(),
            message: format!("a parameter of the successor evaluated to {v}"),
        }
    }

    #[cold]
    fn arity_error(&self, def: &RuleDef, src: &ModuleString, m: usize, k: u16) -> LsError {
        let message = if src.external(m).is_some() {
            format!(
                "a classic production cannot read the non-numeric parameters of module #{} ({})",
                m + 1,
                def.text
                    .split(['<', '>', ':', '-'])
                    .next()
                    .unwrap_or("")
                    .trim()
            )
        } else {
            format!(
                "expects {k} parameter{} but module #{} has {}",
                if k == 1 { "" } else { "s" },
                m + 1,
                src.params(m).len()
            )
        };
        LsError::Rule {
            origin: def.origin,
            rule: def.text.clone(),
            message,
        }
    }

    #[inline]
    pub(super) fn check_arity(
        &self,
        def: &RuleDef,
        src: &ModuleString,
        m: usize,
        k: u16,
    ) -> Result<(), LsError> {
        if src.external(m).is_some() || src.params(m).len() != k as usize {
            return Err(self.arity_error(def, src, m, k));
        }
        Ok(())
    }

    /// [`Deriver::step_range`] for a string without parameters whose rules all have fixed
    /// successors (see [`FixedTables`]), appending to `out` (without parameters too);
    /// `rights` as [`FixedTables::right_codes`] gives them.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn step_fixed<H: Host>(
        &self,
        fixed: &FixedTables,
        src: &ModuleString,
        range: std::ops::Range<usize>,
        rights: &[u8],
        before: u64,
        out: &mut ModuleString,
        host: &mut H,
        opts: &StepOptions,
        scratch: &mut Scratch,
    ) -> Result<(), H::Error> {
        let max = (opts.max_modules as u64).saturating_sub(before);
        // The output's symbols are moved out for the pass (their length stays in a
        // register) and put back whatever happens.
        let mut o = std::mem::take(out.flat_syms_mut());
        let base = o.len();
        let mut i = range.start;
        let mut result = Ok(());
        while i < range.end {
            if let Err(e) = host.check() {
                result = Err(e);
                break;
            }
            let stop = range.end.min((i | 0xFFFF) + 1);
            if !fixed.run(
                src.raw_syms(),
                rights,
                i..stop,
                &mut o,
                base as u64 + max,
                &mut scratch.lefts,
            ) {
                result = Err(self.too_many(opts, before + (o.len() - base) as u64).into());
                break;
            }
            i = stop;
        }
        *out.flat_syms_mut() = o;
        result
    }
}
