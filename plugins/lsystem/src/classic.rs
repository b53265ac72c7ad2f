//! Parsing of the classic notation (ABOP, cpfg, L-Py): module strings and productions.

use crate::expr::{self, Ast, ExprError};

/// A module as written: a name and its argument expressions.
#[derive(Clone, Debug, PartialEq)]
pub struct ModuleAst {
    /// The module's name (`F`, `+`, `[`, or a declared multi-letter name).
    pub name: String,
    /// Argument expressions, empty without parentheses.
    pub args: Vec<Ast>,
}

/// A module of a left side: a name and the names given to its parameters.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PatternAst {
    /// The module's name.
    pub name: String,
    /// Formal parameter names (`A(l, w)`); `None` when written without parentheses.
    pub formals: Option<Vec<String>>,
}

/// A production's left side: `left < pred > right : condition`.
#[derive(Clone, Debug, PartialEq)]
pub struct LhsAst {
    /// Left context, leftmost first.
    pub left: Vec<PatternAst>,
    /// The strict predecessor.
    pub pred: PatternAst,
    /// Right context, may hold `[` and `]`.
    pub right: Vec<PatternAst>,
    /// The condition after `:`.
    pub condition: Option<Ast>,
}

/// A whole classic production.
#[derive(Clone, Debug, PartialEq)]
pub struct ProductionAst {
    /// Left side.
    pub lhs: LhsAst,
    /// Successor modules.
    pub successor: Vec<ModuleAst>,
}

/// Why a text in classic notation does not parse.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum SyntaxError {
    /// A parenthesis or comma where a module name belongs.
    #[error("unexpected '{found}' in '{text}'")]
    Unexpected {
        /// The character.
        found: char,
        /// The whole text.
        text: String,
    },
    /// A module's arguments are not closed.
    #[error("missing ')' after '{name}(' in '{text}'")]
    UnclosedArguments {
        /// The module.
        name: String,
        /// The whole text.
        text: String,
    },
    /// A module has an empty argument (`A(1,)`).
    #[error("empty argument of '{name}' in '{text}'")]
    EmptyArgument {
        /// The module.
        name: String,
        /// The whole text.
        text: String,
    },
    /// An argument expression does not parse.
    #[error("{0}")]
    Argument(ExprError),
    /// A rule's condition does not parse.
    #[error("condition: {0}")]
    Condition(ExprError),
    /// A parameter on a left side is not a name.
    #[error("a parameter of '{name}' on a left side must be a name, not '{found}'")]
    FormalNotAName {
        /// The module.
        name: String,
        /// What stands where the name belongs.
        found: String,
    },
    /// The left side has no symbol to rewrite.
    #[error("the left side names no symbol to rewrite")]
    NoPredecessor,
    /// The strict predecessor holds several symbols (the text given).
    #[error("the strict predecessor must be one symbol, found '{0}'")]
    SeveralPredecessors(String),
    /// A left context holds a bracket.
    #[error("a left context cannot hold '[' or ']'")]
    BracketInLeftContext,
    /// Nothing before `<`.
    #[error("empty left context before '<'")]
    EmptyLeftContext,
    /// Nothing after `>`.
    #[error("empty right context after '>'")]
    EmptyRightContext,
    /// The predecessor is a bracket.
    #[error("brackets cannot be rewritten")]
    BracketPredecessor,
    /// No `->` between the left side and the successor.
    #[error("missing '->'")]
    MissingArrow,
}

/// A module's name and, when it has parentheses, its argument texts.
type RawModule<'a> = (&'a str, Option<Vec<&'a str>>);

/// Splits a classic string into (name, argument texts) pairs. `declared` holds multi-letter
/// names, longest first.
pub(crate) fn split_modules<'a>(
    text: &'a str,
    declared: &[String],
) -> Result<Vec<RawModule<'a>>, SyntaxError> {
    let mut out = Vec::new();
    let mut rest = text;
    loop {
        rest = rest.trim_start();
        let Some(c) = rest.chars().next() else { break };
        if c == '(' || c == ')' || c == ',' {
            return Err(SyntaxError::Unexpected {
                found: c,
                text: text.trim().to_string(),
            });
        }
        let len = declared
            .iter()
            .find(|d| rest.starts_with(d.as_str()))
            .map_or(c.len_utf8(), |d| d.len());
        let name = &rest[..len];
        rest = &rest[len..];
        let after = rest.trim_start();
        if let Some(inner) = after.strip_prefix('(') {
            let mut depth = 0usize;
            let mut args = Vec::new();
            let mut start = 0usize;
            let mut end = None;
            for (i, ch) in inner.char_indices() {
                match ch {
                    '(' => depth += 1,
                    ')' if depth == 0 => {
                        args.push(&inner[start..i]);
                        end = Some(i);
                        break;
                    }
                    ')' => depth -= 1,
                    ',' if depth == 0 => {
                        args.push(&inner[start..i]);
                        start = i + 1;
                    }
                    _ => {}
                }
            }
            let Some(end) = end else {
                return Err(SyntaxError::UnclosedArguments {
                    name: name.to_string(),
                    text: text.trim().to_string(),
                });
            };
            if args.len() == 1 && args[0].trim().is_empty() {
                args.clear();
            }
            out.push((name, Some(args)));
            rest = &inner[end + 1..];
        } else {
            out.push((name, None));
        }
    }
    Ok(out)
}

/// Parses a string of modules with argument expressions (a successor or an axiom).
pub fn parse_modules(text: &str, declared: &[String]) -> Result<Vec<ModuleAst>, SyntaxError> {
    let mut out = Vec::new();
    for (name, args) in split_modules(text, declared)? {
        let mut parsed = Vec::new();
        for a in args.unwrap_or_default() {
            if a.trim().is_empty() {
                return Err(SyntaxError::EmptyArgument {
                    name: name.to_string(),
                    text: text.trim().to_string(),
                });
            }
            parsed.push(expr::parse(a).map_err(SyntaxError::Argument)?);
        }
        out.push(ModuleAst {
            name: name.to_string(),
            args: parsed,
        });
    }
    Ok(out)
}

fn is_identifier(s: &str) -> bool {
    let mut chars = s.chars();
    chars
        .next()
        .is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_')
}

/// Parses a string of pattern modules (a context or a predecessor) in classic notation.
pub fn parse_patterns(text: &str, declared: &[String]) -> Result<Vec<PatternAst>, SyntaxError> {
    let mut out = Vec::new();
    for (name, args) in split_modules(text, declared)? {
        let formals = match args {
            None => None,
            Some(args) => {
                let mut names = Vec::new();
                for a in args {
                    let a = a.trim();
                    if !is_identifier(a) {
                        return Err(SyntaxError::FormalNotAName {
                            name: name.to_string(),
                            found: a.to_string(),
                        });
                    }
                    names.push(a.to_string());
                }
                Some(names)
            }
        };
        out.push(PatternAst {
            name: name.to_string(),
            formals,
        });
    }
    Ok(out)
}

/// Parses the left side of a Lua rule: symbol names separated by spaces, `[` and `]` apart.
pub fn parse_lua_patterns(text: &str) -> Vec<PatternAst> {
    let spaced = text.replace('[', " [ ").replace(']', " ] ");
    spaced
        .split_whitespace()
        .map(|n| PatternAst {
            name: n.to_string(),
            formals: None,
        })
        .collect()
}

/// Finds `c` outside parentheses.
fn find_top(text: &str, c: char) -> Option<usize> {
    let mut depth = 0i32;
    for (i, ch) in text.char_indices() {
        match ch {
            '(' => depth += 1,
            ')' => depth -= 1,
            _ if ch == c && depth == 0 => return Some(i),
            _ => {}
        }
    }
    None
}

/// Splits `left < pred > right` and builds a left side with `parse` for each part.
pub fn parse_lhs(
    text: &str,
    parse: &dyn Fn(&str) -> Result<Vec<PatternAst>, SyntaxError>,
) -> Result<LhsAst, SyntaxError> {
    let (head, condition) = match find_top(text, ':') {
        Some(at) => {
            let cond = text[at + 1..].trim();
            let condition = if cond.is_empty() || cond == "*" {
                None
            } else {
                Some(expr::parse(cond).map_err(SyntaxError::Condition)?)
            };
            (&text[..at], condition)
        }
        None => (text, None),
    };
    let (left_text, rest) = match find_top(head, '<') {
        Some(at) => (Some(&head[..at]), &head[at + 1..]),
        None => (None, head),
    };
    let (pred_text, right_text) = match find_top(rest, '>') {
        Some(at) => (&rest[..at], Some(&rest[at + 1..])),
        None => (rest, None),
    };
    let mut pred = parse(pred_text)?;
    if pred.len() != 1 {
        return Err(if pred.is_empty() {
            SyntaxError::NoPredecessor
        } else {
            SyntaxError::SeveralPredecessors(pred_text.trim().to_string())
        });
    }
    let left = match left_text {
        Some(t) if t.trim() != "*" => parse(t)?,
        _ => Vec::new(),
    };
    if left.iter().any(|p| p.name == "[" || p.name == "]") {
        return Err(SyntaxError::BracketInLeftContext);
    }
    if left_text.is_some_and(|t| t.trim().is_empty()) {
        return Err(SyntaxError::EmptyLeftContext);
    }
    let right = match right_text {
        Some(t) if t.trim() != "*" => parse(t)?,
        _ => Vec::new(),
    };
    if right_text.is_some_and(|t| t.trim().is_empty()) {
        return Err(SyntaxError::EmptyRightContext);
    }
    let pred = pred.remove(0);
    if pred.name == "[" || pred.name == "]" {
        return Err(SyntaxError::BracketPredecessor);
    }
    Ok(LhsAst {
        left,
        pred,
        right,
        condition,
    })
}

/// Parses `lhs -> successor` (also `-->`).
pub fn parse_production(text: &str, declared: &[String]) -> Result<ProductionAst, SyntaxError> {
    let (at, len) = match text.find("-->") {
        Some(at) => (at, 3),
        None => match text.find("->") {
            Some(at) => (at, 2),
            None => return Err(SyntaxError::MissingArrow),
        },
    };
    let lhs = parse_lhs(&text[..at], &|t| parse_patterns(t, declared))?;
    let succ_text = text[at + len..].trim();
    let successor = if succ_text == "*" || succ_text.is_empty() {
        Vec::new()
    } else {
        parse_modules(succ_text, declared)?
    };
    Ok(ProductionAst { lhs, successor })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(m: &[ModuleAst]) -> Vec<&str> {
        m.iter().map(|m| m.name.as_str()).collect()
    }

    #[test]
    fn modules_are_single_characters_or_declared_names() {
        let m = parse_modules("F[+F]Apex(1, 2*3)", &[]).expect("parses");
        assert_eq!(names(&m), ["F", "[", "+", "F", "]", "A", "p", "e", "x"]);
        assert_eq!(m[8].args.len(), 2);
        let declared = vec!["Apex".to_string()];
        let m = parse_modules("F Apex(1, 2*3) ~(0.5)", &declared).expect("parses");
        assert_eq!(names(&m), ["F", "Apex", "~"]);
        assert_eq!(m[1].args.len(), 2);
        assert_eq!(m[2].args.len(), 1);
    }

    #[test]
    fn productions_split_contexts_conditions_and_successor() {
        let p = parse_production("A(x) B < C(y) > [D]E(z) : x + y > z --> C(y+1) F", &[])
            .expect("parses");
        assert_eq!(p.lhs.left.len(), 2);
        assert_eq!(p.lhs.left[0].formals, Some(vec!["x".to_string()]));
        assert_eq!(p.lhs.pred.name, "C");
        assert_eq!(names_p(&p.lhs.right), ["[", "D", "]", "E"]);
        assert!(p.lhs.condition.is_some());
        assert_eq!(names(&p.successor), ["C", "F"]);
        let d = parse_production("A -> ", &[]).expect("parses");
        assert!(d.successor.is_empty());
    }

    fn names_p(m: &[PatternAst]) -> Vec<&str> {
        m.iter().map(|m| m.name.as_str()).collect()
    }

    #[test]
    fn bad_productions_are_explained() {
        assert_eq!(
            parse_production("F FF", &[]).expect_err("no arrow"),
            SyntaxError::MissingArrow
        );
        assert!(
            parse_production("AB -> C", &[])
                .expect_err("two")
                .to_string()
                .contains("one symbol")
        );
        assert!(
            parse_production("A(1) -> C", &[])
                .expect_err("formal")
                .to_string()
                .contains("must be a name")
        );
        assert!(
            parse_production("A -> B(1", &[])
                .expect_err("paren")
                .to_string()
                .contains("missing ')'")
        );
        assert!(
            parse_production("[ < A -> B", &[])
                .expect_err("bracket")
                .to_string()
                .contains("left context")
        );
        assert!(
            parse_production("A : x > -> B", &[])
                .expect_err("cond")
                .to_string()
                .contains("condition")
        );
    }

    #[test]
    fn lua_left_sides_split_on_spaces_and_brackets() {
        let p = parse_lua_patterns("Apex B[C]D");
        assert_eq!(names_p(&p), ["Apex", "B", "[", "C", "]", "D"]);
    }
}
