//! Parsing of the classic notation (ABOP, cpfg, L-Py): module strings and productions.

use crate::expr::{self, Ast};

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

/// A module's name and, when it has parentheses, its argument texts.
type RawModule<'a> = (&'a str, Option<Vec<&'a str>>);

/// Splits a classic string into (name, argument texts) pairs. `declared` holds multi-letter
/// names, longest first.
pub(crate) fn split_modules<'a>(
    text: &'a str,
    declared: &[String],
) -> Result<Vec<RawModule<'a>>, String> {
    let mut out = Vec::new();
    let mut rest = text;
    loop {
        rest = rest.trim_start();
        let Some(c) = rest.chars().next() else { break };
        if c == '(' || c == ')' || c == ',' {
            return Err(format!("unexpected '{c}' in '{}'", text.trim()));
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
                return Err(format!("missing ')' after '{name}(' in '{}'", text.trim()));
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
pub fn parse_modules(text: &str, declared: &[String]) -> Result<Vec<ModuleAst>, String> {
    let mut out = Vec::new();
    for (name, args) in split_modules(text, declared)? {
        let mut parsed = Vec::new();
        for a in args.unwrap_or_default() {
            if a.trim().is_empty() {
                return Err(format!("empty argument of '{name}' in '{}'", text.trim()));
            }
            parsed.push(expr::parse(a).map_err(|e| e.0)?);
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
pub fn parse_patterns(text: &str, declared: &[String]) -> Result<Vec<PatternAst>, String> {
    let mut out = Vec::new();
    for (name, args) in split_modules(text, declared)? {
        let formals = match args {
            None => None,
            Some(args) => {
                let mut names = Vec::new();
                for a in args {
                    let a = a.trim();
                    if !is_identifier(a) {
                        return Err(format!(
                            "a parameter of '{name}' on a left side must be a name, not '{a}'"
                        ));
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
    parse: &dyn Fn(&str) -> Result<Vec<PatternAst>, String>,
) -> Result<LhsAst, String> {
    let (head, condition) = match find_top(text, ':') {
        Some(at) => {
            let cond = text[at + 1..].trim();
            let condition = if cond.is_empty() || cond == "*" {
                None
            } else {
                Some(expr::parse(cond).map_err(|e| format!("condition: {}", e.0))?)
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
            "the left side names no symbol to rewrite".to_string()
        } else {
            format!(
                "the strict predecessor must be one symbol, found '{}'",
                pred_text.trim()
            )
        });
    }
    let left = match left_text {
        Some(t) if t.trim() != "*" => parse(t)?,
        _ => Vec::new(),
    };
    if left.iter().any(|p| p.name == "[" || p.name == "]") {
        return Err("a left context cannot hold '[' or ']'".into());
    }
    if left_text.is_some_and(|t| t.trim().is_empty()) {
        return Err("empty left context before '<'".into());
    }
    let right = match right_text {
        Some(t) if t.trim() != "*" => parse(t)?,
        _ => Vec::new(),
    };
    if right_text.is_some_and(|t| t.trim().is_empty()) {
        return Err("empty right context after '>'".into());
    }
    let pred = pred.remove(0);
    if pred.name == "[" || pred.name == "]" {
        return Err("brackets cannot be rewritten".into());
    }
    Ok(LhsAst {
        left,
        pred,
        right,
        condition,
    })
}

/// Parses `lhs -> successor` (also `-->`).
pub fn parse_production(text: &str, declared: &[String]) -> Result<ProductionAst, String> {
    let (at, len) = match text.find("-->") {
        Some(at) => (at, 3),
        None => match text.find("->") {
            Some(at) => (at, 2),
            None => return Err("missing '->'".into()),
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
            "missing '->'"
        );
        assert!(
            parse_production("AB -> C", &[])
                .expect_err("two")
                .contains("one symbol")
        );
        assert!(
            parse_production("A(1) -> C", &[])
                .expect_err("formal")
                .contains("must be a name")
        );
        assert!(
            parse_production("A -> B(1", &[])
                .expect_err("paren")
                .contains("missing ')'")
        );
        assert!(
            parse_production("[ < A -> B", &[])
                .expect_err("bracket")
                .contains("left context")
        );
        assert!(
            parse_production("A : x > -> B", &[])
                .expect_err("cond")
                .contains("condition")
        );
    }

    #[test]
    fn lua_left_sides_split_on_spaces_and_brackets() {
        let p = parse_lua_patterns("Apex B[C]D");
        assert_eq!(names_p(&p), ["Apex", "B", "[", "C", "]", "D"]);
    }
}
