//! Tests of the rewriting engine: classic, parametric, context-sensitive and stochastic
//! systems against independent references, limits, pieces and external rules.

use super::*;
use pge_engine::random::uniform;
use rand_mt::Mt;
use std::collections::HashMap;

mod counting;

struct Run {
    symbols: SymbolTable,
    prepared: Prepared,
    string: ModuleString,
    rng: Mt,
    steps: u32,
    max: usize,
}

impl Run {
    fn new(axiom: &str, rules: &[&str]) -> Run {
        Run::with(axiom, rules, |_, _| {})
    }

    fn with(axiom: &str, rules: &[&str], setup: impl FnOnce(&mut System, &mut SymbolTable)) -> Run {
        let mut symbols = SymbolTable::new();
        let mut system = System::new();
        setup(&mut system, &mut symbols);
        for r in rules {
            system
                .add_production(r, None, 0, &mut symbols)
                .expect("rule parses");
        }
        let prepared = system.prepare(&symbols).expect("compiles");
        let string = system
            .parse_string(axiom, &mut symbols, &mut || 0.0)
            .expect("axiom");
        Run {
            symbols,
            prepared,
            string,
            rng: Mt::new(7),
            steps: 0,
            max: 10_000_000,
        }
    }

    fn step(&mut self) -> Result<(), LsError> {
        self.steps += 1;
        let mut next = ModuleString::new();
        self.prepared.derive(
            &self.string,
            &DeriveOptions::new(self.steps, 1, self.max),
            &mut NativeHost { rng: &mut self.rng },
            Output::Keep(&mut next),
        )?;
        self.string = next;
        Ok(())
    }

    fn steps(&mut self, n: u32) -> &mut Run {
        for _ in 0..n {
            self.step().expect("derives");
        }
        self
    }

    fn text(&self) -> String {
        self.string.to_text(&self.symbols, "")
    }
}

/// Counts symbols after `n` steps of a context-free single-character system by iterating
/// occurrence counts, independently of the engine.
fn expected_counts(axiom: &str, rules: &[(char, &str)], n: u32) -> u64 {
    let mut counts: HashMap<char, u64> = HashMap::new();
    for c in axiom.chars() {
        *counts.entry(c).or_default() += 1;
    }
    for _ in 0..n {
        let mut next: HashMap<char, u64> = HashMap::new();
        for (c, k) in &counts {
            match rules.iter().find(|r| r.0 == *c) {
                Some((_, succ)) => {
                    for s in succ.chars() {
                        *next.entry(s).or_default() += k;
                    }
                }
                None => *next.entry(*c).or_default() += k,
            }
        }
        counts = next;
    }
    counts.values().sum()
}

#[test]
fn koch_island_first_step() {
    let mut r = Run::new("F-F-F-F", &["F -> F-F+F+FF-F-F+F"]);
    r.steps(1);
    assert_eq!(
        r.text(),
        "F-F+F+FF-F-F+F-F-F+F+FF-F-F+F-F-F+F+FF-F-F+F-F-F+F+FF-F-F+F"
    );
    r.steps(2);
    assert_eq!(
        r.string.len() as u64,
        expected_counts("F-F-F-F", &[('F', "F-F+F+FF-F-F+F")], 3)
    );
}

type Plant = (&'static str, &'static [(char, &'static str)], u32);

#[test]
fn abop_fig_1_24_module_counts_at_several_depths() {
    let plants: [Plant; 6] = [
        ("F", &[('F', "F[+F]F[-F]F")], 5),
        ("F", &[('F', "F[+F]F[-F][F]")], 5),
        ("F", &[('F', "FF-[-F+F+F]+[+F-F-F]")], 4),
        ("X", &[('X', "F[+X]F[-X]+X"), ('F', "FF")], 7),
        ("X", &[('X', "F[+X][-X]FX"), ('F', "FF")], 7),
        ("X", &[('X', "F-[[X]+X]+F[+FX]-X"), ('F', "FF")], 5),
    ];
    for (axiom, rules, n) in plants {
        let texts: Vec<String> = rules.iter().map(|(p, s)| format!("{p} -> {s}")).collect();
        let texts: Vec<&str> = texts.iter().map(String::as_str).collect();
        let mut r = Run::new(axiom, &texts);
        for depth in 1..=n {
            r.steps(1);
            assert_eq!(
                r.string.len() as u64,
                expected_counts(axiom, rules, depth),
                "{axiom} {rules:?} at depth {depth}"
            );
        }
    }
    // Fig. 1.24a: 5^5 segments.
    let mut a = Run::new("F", &["F -> F[+F]F[-F]F"]);
    a.steps(1);
    assert_eq!(a.text(), "F[+F]F[-F]F");
    a.steps(4);
    assert_eq!(a.text().matches('F').count(), 3125);
    assert_eq!(a.string.len(), 3125 + 6 * 781);
}

#[test]
fn signal_propagation_step_by_step() {
    // ABOP §1.8: an acropetal signal...
    let mut r = Run::new("baaaaaaaa", &["b < a -> b", "b -> a"]);
    let mut seen = vec![r.text()];
    for _ in 0..9 {
        r.steps(1);
        seen.push(r.text());
    }
    assert_eq!(seen[1], "abaaaaaaa");
    assert_eq!(seen[2], "aabaaaaaa");
    assert_eq!(seen[8], "aaaaaaaab");
    assert_eq!(seen[9], "aaaaaaaaa");
    // ... and a basipetal one.
    let mut r = Run::new("aaaaaaaab", &["a > b -> b", "b -> a"]);
    r.steps(1);
    assert_eq!(r.text(), "aaaaaaaba");
    r.steps(7);
    assert_eq!(r.text(), "baaaaaaaa");
}

#[test]
fn left_context_skips_branches_and_climbs_out() {
    // ABOP p. 32: BC < S > G[H]M applies to S in ABC[DE][SG[HI[JK]L]MNO].
    let mut r = Run::new("ABC[DE][SG[HI[JK]L]MNO]", &["BC < S > G[H]M -> X"]);
    r.steps(1);
    assert_eq!(r.text(), "ABC[DE][XG[HI[JK]L]MNO]");
    // The right context must not see inside a branch it does not enter.
    let mut r = Run::new("SG[M]", &["S > GM -> X"]);
    r.steps(1);
    assert_eq!(r.text(), "SG[M]");
    let mut r = Run::new("SG[K]M", &["S > GM -> X"]);
    r.steps(1);
    assert_eq!(r.text(), "XG[K]M");
    // A left context is not found inside a sibling branch, only on the path to the root.
    let mut r = Run::new("A[B]C", &["B < C -> X", "A < C -> Y", "A < B -> Z"]);
    r.steps(1);
    assert_eq!(r.text(), "A[Z]Y");
    // The end of a branch ends the right context.
    let mut r = Run::new("A[B]C", &["B > C -> X"]);
    r.steps(1);
    assert_eq!(r.text(), "A[B]C");
}

#[test]
fn ignored_symbols_are_skipped_by_both_contexts() {
    let mut r = Run::with("A+-B-C", &["A < B > C -> X"], |s, t| s.ignore("+ -", t));
    r.steps(1);
    assert_eq!(r.text(), "A+-X-C");
    let mut r = Run::new("A+-B-C", &["A < B > C -> X"]);
    r.steps(1);
    assert_eq!(r.text(), "A+-B-C");
}

/// The Hogeweg-Hesper systems of ABOP fig. 1.31 (a-e).
fn hogeweg(which: usize) -> (&'static str, [&'static str; 8], u32) {
    let a = ["0", "1[+F1F1]", "1", "1", "0", "1F1", "0", "0"];
    let b = ["1", "1[-F1F1]", "1", "1", "0", "1F1", "1", "0"];
    let c = ["0", "1", "0", "1[+F1F1]", "0", "1F1", "0", "0"];
    let d = ["1", "0", "0", "1F1", "1", "1[+F1F1]", "1", "0"];
    let e = ["0", "1[-F1F1]", "1", "1", "0", "1F1", "1", "0"];
    match which {
        0 => ("F1F1F1", a, 30),
        1 => ("F1F1F1", b, 30),
        2 => ("F1F1F1", c, 26),
        3 => ("F0F1F1", d, 24),
        _ => ("F1F1F1", e, 26),
    }
}

/// A direct, slow implementation of the same systems to compare against.
fn hogeweg_reference(axiom: &str, succ: &[&str; 8], steps: u32) -> String {
    let ignore = |c: char| matches!(c, '+' | '-' | 'F');
    let mut s: Vec<char> = axiom.chars().collect();
    for _ in 0..steps {
        let mut next = Vec::new();
        for i in 0..s.len() {
            let c = s[i];
            if c == '+' || c == '-' {
                next.push(if c == '+' { '-' } else { '+' });
                continue;
            }
            if c != '0' && c != '1' {
                next.push(c);
                continue;
            }
            let mut left = None;
            let mut depth = 0;
            for j in (0..i).rev() {
                match s[j] {
                    ']' => depth += 1,
                    '[' => depth = (depth - 1).max(0),
                    x if depth == 0 && !ignore(x) => {
                        left = Some(x);
                        break;
                    }
                    _ => {}
                }
            }
            let mut right = None;
            let mut depth = 0;
            for &x in &s[i + 1..] {
                match x {
                    '[' => depth += 1,
                    ']' if depth == 0 => break,
                    ']' => depth -= 1,
                    x if depth == 0 && !ignore(x) => {
                        right = Some(x);
                        break;
                    }
                    _ => {}
                }
            }
            match (left, right) {
                (Some(l), Some(r)) => {
                    let k = (l == '1') as usize * 4 + (c == '1') as usize * 2 + (r == '1') as usize;
                    next.extend(succ[k].chars());
                }
                _ => next.push(c),
            }
        }
        s = next;
    }
    s.into_iter().collect()
}

#[test]
fn hogeweg_hesper_systems_match_abop_across_branches() {
    for which in 0..5 {
        let (axiom, succ, n) = hogeweg(which);
        let mut rules = Vec::new();
        for (k, s) in succ.iter().enumerate() {
            rules.push(format!("{} < {} > {} -> {s}", k >> 2, (k >> 1) & 1, k & 1));
        }
        rules.push("+ -> -".into());
        rules.push("- -> +".into());
        let rules: Vec<&str> = rules.iter().map(String::as_str).collect();
        let mut r = Run::with(axiom, &rules, |s, t| s.ignore("+ - F", t));
        if which == 0 {
            r.steps(1);
            assert_eq!(r.text(), "F1F0F1");
            r.steps(1);
            assert_eq!(r.text(), "F1F1F1F1");
            r.steps(1);
            assert_eq!(r.text(), "F1F0F0F1");
            r.steps(n - 3);
        } else {
            r.steps(n);
        }
        let expected = hogeweg_reference(axiom, &succ, n);
        assert!(expected.contains('['), "system {which} branches");
        assert_eq!(r.text(), expected, "fig 1.31 system {which}");
    }
}

#[test]
fn parametric_productions_with_conditions() {
    let mut r = Run::new(
        "A(1,0.5)",
        &[
            "A(l,w) : l < 3 -> F(l) [ +(30) A(l+1, w*0.5) ] A(l+1, w)",
            "A(l,w) -> B(l*w)",
        ],
    );
    r.steps(1);
    assert_eq!(
        r.string.to_text(&r.symbols, " "),
        "F(1) [ +(30) A(2,0.25) ] A(2,0.5)"
    );
    r.steps(2);
    assert!(r.text().contains("B(0.375)"), "{}", r.text());
    assert!(r.text().contains("B(1.5)"));
}

#[test]
fn contexts_pass_parameters_leftmost_first() {
    let mut r = Run::new(
        "A(1)B(2)C(3)",
        &["A(x) < B(y) > C(z) : x + y + z > 5 -> D(x*100 + y*10 + z)"],
    );
    r.steps(1);
    assert_eq!(r.string.to_text(&r.symbols, ""), "A(1)D(123)C(3)");
}

#[test]
fn globals_and_declared_names() {
    let mut r = Run::with("Apex(2)", &["Apex(x) -> Apex(x*r) Bud"], |s, _| {
        s.declare("Apex Bud");
        s.set_global("r", 0.5);
    });
    r.steps(2);
    assert_eq!(r.string.to_text(&r.symbols, " "), "Apex(0.5) Bud Bud");
}

#[test]
fn first_applicable_rule_wins_and_unmatched_symbols_are_copied() {
    let mut r = Run::new("A(1)A(5)C", &["A(x) : x > 3 -> B", "A(x) -> D(x)", "Z -> "]);
    r.steps(1);
    assert_eq!(r.text(), "D(1)BC");
    let mut r = Run::new("AZA", &["Z -> "]);
    r.steps(1);
    assert_eq!(r.text(), "AA");
}

#[test]
fn stochastic_choice_is_weighted_and_deterministic_per_seed() {
    let rules = ["A -> B", "A -> C"];
    let build = |seed: u32| {
        let mut symbols = SymbolTable::new();
        let mut system = System::new();
        system
            .add_production(rules[0], Some(3.0), 0, &mut symbols)
            .expect("ok");
        system
            .add_production(rules[1], Some(1.0), 0, &mut symbols)
            .expect("ok");
        let prepared = system.prepare(&symbols).expect("ok");
        let axiom = system
            .parse_string(&"A".repeat(4000), &mut symbols, &mut || 0.0)
            .expect("ok");
        let mut out = ModuleString::new();
        let mut rng = Mt::new(seed);
        prepared
            .derive(
                &axiom,
                &DeriveOptions::new(1, 1, 100_000),
                &mut NativeHost { rng: &mut rng },
                Output::Keep(&mut out),
            )
            .expect("ok");
        out.to_text(&symbols, "")
    };
    let a = build(1);
    assert_eq!(a, build(1));
    assert_ne!(a, build(2));
    let b = a.matches('B').count() as f64 / 4000.0;
    assert!((b - 0.75).abs() < 0.03, "B share {b}");
}

#[test]
fn growth_past_max_modules_fails_before_allocating() {
    let mut r = Run::new("F", &["F -> FF"]);
    let mut failed = None;
    for _ in 0..40 {
        if let Err(e) = r.step() {
            failed = Some(e);
            break;
        }
    }
    assert_eq!(
        failed.expect("stops"),
        LsError::TooManyModules {
            step: 24,
            count: 16_777_216,
            max: 10_000_000
        }
    );
    assert!(r.string.len() <= 10_000_000);
    // The general path stops as soon as the cap is passed.
    let mut r = Run::new("A(1)", &["A(x) -> A(x)A(x)"]);
    r.max = 1000;
    let err = (0..30).find_map(|_| r.step().err()).expect("stops");
    assert_eq!(
        err,
        LsError::TooManyModules {
            step: 10,
            count: 1002,
            max: 1000
        }
    );
}

/// `steps` steps of `r` under the cap `max` delivered in pieces, joined, with the number of
/// pieces; and counted, with the same result.
fn in_pieces(r: &Run, steps: u32, max: usize) -> Result<(ModuleString, u64, usize), LsError> {
    let mut joined = ModuleString::new();
    let mut pieces = 0;
    let opts = DeriveOptions::new(r.steps + 1, steps, max);
    let n = r.prepared.derive(
        &r.string,
        &opts,
        &mut NativeHost {
            rng: &mut r.rng.clone(),
        },
        Output::Pieces(&mut |piece| {
            joined.append(piece);
            pieces += 1;
            Ok(())
        }),
    );
    let counted = r.prepared.derive(
        &r.string,
        &opts,
        &mut NativeHost {
            rng: &mut r.rng.clone(),
        },
        Output::Count,
    );
    assert_eq!(counted, n);
    Ok((joined, n?, pieces))
}

#[test]
fn a_step_in_pieces_joins_to_the_whole_step() {
    let cases: [(&str, &[&str]); 4] = [
        ("X", &["X -> F[+X]F[-X]+X", "F -> FF"]),
        (
            "A(1,10)",
            &[
                "A(l,w) -> !(w)F(l)[&(45)B(l*0.6,w*0.7)]/(137.5)A(l*0.9,w*0.7)",
                "B(l,w) : l > 0.2 -> !(w)F(l)[-(45)$B(l*0.6,w*0.7)]B(l*0.9,w*0.7)",
            ],
        ),
        (
            "baaa[aa]a[a[a]a]aa",
            &["b < a -> b", "b -> c", "a > b -> d"],
        ),
        ("A(1)", &["A(x) -> A(x+1) B(x)", "A(x) -> B(x) A(x*2)"]),
    ];
    for (axiom, rules) in cases {
        let mut r = Run::new(axiom, rules);
        if axiom == "A(1)" {
            // Stochastic: both alternatives, drawn from the same generator.
            r = Run::with(axiom, &[], |system, symbols| {
                for rule in rules {
                    system
                        .add_production(rule, Some(1.0), 0, symbols)
                        .expect("rule");
                }
            });
        }
        r.steps(4);
        let mut whole = Run {
            string: r.string.clone(),
            symbols: r.symbols.clone(),
            prepared: r.prepared.clone(),
            rng: r.rng.clone(),
            steps: r.steps,
            max: r.max,
        };
        let mut lengths = Vec::new();
        for steps in 1..=3 {
            whole.step().expect("derives");
            lengths.push(whole.string.len());
            let (joined, n, pieces) = in_pieces(&r, steps, r.max).expect("derives");
            assert_eq!(n as usize, whole.string.len(), "{axiom}, {steps} steps");
            assert_eq!(joined, whole.string, "{axiom}, {steps} steps");
            if whole.string.len() > 100_000 {
                assert!(pieces > 1, "{axiom}, {steps} steps: never whole");
            }
            // The cap holds for each whole step, not for each piece: the first step longer
            // than it fails.
            let max = whole.string.len() - 1;
            let fails = r.steps + 1 + lengths.iter().position(|&n| n > max).unwrap_or(0) as u32;
            let err = in_pieces(&r, steps, max).expect_err("over the cap");
            assert!(
                matches!(err, LsError::TooManyModules { step, .. } if step == fails),
                "{axiom}, {steps} steps: {err:?}"
            );
        }
    }
}

#[test]
fn bad_rules_name_themselves() {
    let mut symbols = SymbolTable::new();
    let mut s = System::new();
    s.add_production("A(x) -> B(y)", None, 3, &mut symbols)
        .expect("parses");
    let e = s.prepare(&symbols).expect_err("unknown name");
    assert_eq!(e.to_string(), "rule 'A(x) -> B(y)': unknown name 'y'");
    assert!(matches!(e, LsError::Rule { origin: 3, .. }));
    let e = s
        .add_production("A(x) B -> C", None, 4, &mut symbols)
        .expect_err("two preds");
    assert!(
        e.to_string()
            .starts_with("rule 'A(x) B -> C': the strict predecessor")
    );
    let mut s = System::new();
    s.add_production("A(x, y) -> B(x)", None, 0, &mut symbols)
        .expect("parses");
    let p = s.prepare(&symbols).expect("ok");
    let axiom = s
        .parse_string("A(1)", &mut symbols, &mut || 0.0)
        .expect("ok");
    let mut out = ModuleString::new();
    let mut rng = Mt::new(1);
    let opts = DeriveOptions::new(1, 1, 100);
    let e = p
        .derive(
            &axiom,
            &opts,
            &mut NativeHost { rng: &mut rng },
            Output::Keep(&mut out),
        )
        .expect_err("arity");
    assert_eq!(
        e.to_string(),
        "rule 'A(x, y) -> B(x)': expects 2 parameters but module #1 has 1"
    );
    let mut s = System::new();
    s.add_production("A(x) -> B(1/x)", None, 0, &mut symbols)
        .expect("parses");
    let p = s.prepare(&symbols).expect("ok");
    let axiom = s
        .parse_string("A(0)", &mut symbols, &mut || 0.0)
        .expect("ok");
    let e = p
        .derive(
            &axiom,
            &opts,
            &mut NativeHost { rng: &mut rng },
            Output::Keep(&mut out),
        )
        .expect_err("inf");
    assert!(e.to_string().ends_with("evaluated to inf"), "{e}");
}

/// Records what a host is asked to do.
struct Recorder {
    rng: Mt,
    calls: Vec<(u32, Vec<usize>)>,
    interpreted: Vec<usize>,
}

impl Host for Recorder {
    type Error = LsError;
    fn random(&mut self) -> f64 {
        uniform(&mut self.rng)
    }
    fn apply(
        &mut self,
        rule: u32,
        matched: &[usize],
        src: &ModuleString,
        out: &mut ModuleString,
    ) -> Result<bool, LsError> {
        self.calls.push((rule, matched.to_vec()));
        if rule == 0 {
            return Ok(false);
        }
        out.push(src.sym(matched[0]), &[9.0]);
        out.push_external(Sym::PUSH.max(Sym(2)), 4);
        Ok(true)
    }
    fn interpret(&mut self, out: &ModuleString, from: usize) -> Result<(), LsError> {
        self.interpreted.push(out.len() - from);
        Ok(())
    }
}

#[test]
fn external_rules_fall_through_on_nil_and_stream_interpretation() {
    let mut symbols = SymbolTable::new();
    let mut s = System::new();
    s.add_external("A", 0, 0, &mut symbols).expect("ok");
    s.add_external("A > B", 1, 0, &mut symbols).expect("ok");
    let p = s.prepare(&symbols).expect("ok");
    let axiom = s
        .parse_string("AAB", &mut symbols, &mut || 0.0)
        .expect("ok");
    let mut out = ModuleString::new();
    let mut host = Recorder {
        rng: Mt::new(1),
        calls: Vec::new(),
        interpreted: Vec::new(),
    };
    let opts = DeriveOptions {
        interpret: true,
        ..DeriveOptions::new(1, 1, 100)
    };
    p.derive(&axiom, &opts, &mut host, Output::Keep(&mut out))
        .expect("ok");
    // Rule 0 declines both A; rule 1 applies to the A before B only.
    assert_eq!(
        host.calls,
        vec![(0, vec![0]), (0, vec![1]), (1, vec![1, 2])]
    );
    assert_eq!(out.to_text(&symbols, " "), "A A(9) A B");
    assert_eq!(out.external(2), Some(4));
    assert_eq!(host.interpreted, vec![1, 2, 1]);
}

#[test]
fn number_arguments_read_without_the_parser_equal_parsed_ones() {
    for text in [
        "1", "0.25", ".5", "5.", "007", "1.5e3", "2 ", "1.2.3", "-1", "1e400", "x",
    ] {
        if let Some(v) = super::literal(text) {
            let ast = crate::expr::parse(text).expect("a number parses");
            let e = Expr::compile(&ast, &mut |_| None).expect("compiles");
            assert_eq!(
                v.to_bits(),
                e.eval(&[], &[], &mut || 0.0).to_bits(),
                "{text}"
            );
        }
    }
    assert_eq!(super::literal("1.5e3"), None);
    assert_eq!(super::literal("1.2.3"), None);
    assert_eq!(super::literal("-1"), None);
    assert_eq!(super::literal(" 0.25 "), Some(0.25));
    let mut symbols = SymbolTable::new();
    let system = System::new();
    let s = system
        .parse_string("A(1, .5)B(2)", &mut symbols, &mut || 0.0)
        .expect("parses");
    assert_eq!(s.params(0), &[1.0, 0.5]);
    assert_eq!(s.params(1), &[2.0]);
}
