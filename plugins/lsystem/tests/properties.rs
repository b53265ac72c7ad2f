//! Properties of the classic notation: deriving random systems never panics, and
//! the text of a derived string (what `pge derive --format text` prints) parses back to the
//! same string.

use pge_lsystem::{DeriveOptions, ModuleString, NativeHost, Output, SymbolTable, System};
use proptest::prelude::*;
use rand_mt::Mt;

/// An expression over the parameters `x` and `y`, sometimes malformed.
fn expr() -> impl Strategy<Value = String> {
    let leaf = prop_oneof![
        Just("x".to_string()),
        Just("y".to_string()),
        Just("pi".to_string()),
        Just("rand()".to_string()),
        Just("g".to_string()),
        (-1000.0f64..1000.0).prop_map(|v| format!("{v}")),
        (0u32..5).prop_map(|v| v.to_string()),
    ];
    leaf.prop_recursive(6, 48, 3, |inner| {
        prop_oneof![
            (
                inner.clone(),
                prop::sample::select(vec![
                    "+", "-", "*", "/", "%", "^", "<", ">=", "==", "~=", "and", "or"
                ]),
                inner.clone()
            )
                .prop_map(|(a, op, b)| format!("({a} {op} {b})")),
            inner.clone().prop_map(|a| format!("-{a}")),
            inner.clone().prop_map(|a| format!("not {a}")),
            (
                prop::sample::select(vec!["sin", "sqrt", "floor", "abs", "log"]),
                inner.clone()
            )
                .prop_map(|(f, a)| format!("{f}({a})")),
            (inner.clone(), inner.clone()).prop_map(|(a, b)| format!("max({a}, {b})")),
            (inner.clone(), inner).prop_map(|(a, b)| format!("rand({a}, {b})")),
        ]
    })
}

/// A module of a successor: a name, maybe with argument expressions.
fn module() -> impl Strategy<Value = String> {
    prop_oneof![
        prop::sample::select(vec!["A", "B", "F", "+", "-", "[", "]", "f", "!"])
            .prop_map(str::to_string),
        (
            prop::sample::select(vec!["A", "B", "F", "+"]),
            prop::collection::vec(expr(), 1..3)
        )
            .prop_map(|(n, args)| format!("{n}({})", args.join(", "))),
    ]
}

/// A production `LHS -> successor`, with optional context and condition.
fn production() -> impl Strategy<Value = String> {
    (
        prop::sample::select(vec!["A(x)", "A(x, y)", "B(x)", "F(x)", "A", "B", "F"]),
        prop::option::of(prop::sample::select(vec!["B(y) < ", "F < ", "A < "])),
        prop::option::of(prop::sample::select(vec![" > B(y)", " > F", " > [A]"])),
        prop::option::of(expr()),
        prop::collection::vec(module(), 0..8),
    )
        .prop_map(|(pred, left, right, cond, succ)| {
            let cond = cond.map(|c| format!(" : {c}")).unwrap_or_default();
            format!(
                "{}{pred}{}{cond} -> {}",
                left.unwrap_or(""),
                right.unwrap_or(""),
                succ.join(" ")
            )
        })
}

fn axiom() -> impl Strategy<Value = String> {
    prop::collection::vec(
        prop_oneof![
            Just("A(1)".to_string()),
            Just("A(2, 3)".to_string()),
            Just("B(0.5)".to_string()),
            Just("F(1)".to_string()),
            Just("[".to_string()),
            Just("]".to_string()),
            Just("A".to_string()),
            (-5.0f64..5.0).prop_map(|v| format!("B({v})")),
        ],
        1..8,
    )
    .prop_map(|m| m.join(" "))
}

/// Builds and derives `steps` steps; `None` when the system is refused (a located error,
/// not a panic).
fn derive(
    productions: &[String],
    axiom: &str,
    steps: u32,
    seed: u32,
) -> Option<(ModuleString, SymbolTable, System)> {
    let mut symbols = SymbolTable::new();
    let mut system = System::new();
    system.set_global("g", 2.0);
    for (i, p) in productions.iter().enumerate() {
        system
            .add_production(p, None, i as u32, &mut symbols)
            .ok()?;
    }
    let prepared = system.prepare(&symbols).ok()?;
    let mut draws = Mt::new(seed);
    let mut rand = || f64::from(draws.next_u32()) / 4_294_967_296.0;
    let mut string = system.parse_string(axiom, &mut symbols, &mut rand).ok()?;
    let mut next = ModuleString::new();
    let mut rng = Mt::new(seed);
    for step in 1..=steps {
        let opts = DeriveOptions::new(step, 1, 4_000);
        if prepared
            .derive(
                &string,
                &opts,
                &mut NativeHost { rng: &mut rng },
                Output::Keep(&mut next),
            )
            .is_err()
        {
            break;
        }
        std::mem::swap(&mut string, &mut next);
    }
    Some((string, symbols, system))
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 200, ..ProptestConfig::default() })]

    /// Random systems derive or are refused: never a panic, an abort or a hang.
    #[test]
    fn deriving_random_classic_systems_never_panics(
        productions in prop::collection::vec(production(), 1..5),
        axiom in axiom(),
        seed in any::<u32>(),
    ) {
        let _ = derive(&productions, &axiom, 4, seed);
    }

    /// Arbitrary text as a production and an axiom: an error or a system, never a panic.
    #[test]
    fn any_text_is_a_production_or_an_error(text in "\\PC{0,80}", axiom in "\\PC{0,20}") {
        let _ = derive(&[text], &axiom, 2, 1);
    }

    /// The text of a derived string parses back to the same string, and prints the same.
    #[test]
    fn the_text_of_a_derived_string_parses_back_to_the_same_string(
        productions in prop::collection::vec(production(), 1..4),
        axiom in axiom(),
        seed in any::<u32>(),
    ) {
        if let Some((string, mut symbols, system)) = derive(&productions, &axiom, 3, seed) {
            let text = string.to_text(&symbols, " ");
            let back = system
                .parse_string(&text, &mut symbols, &mut || 0.0)
                .map_err(|e| TestCaseError::fail(format!("'{text}' does not parse: {e}")))?;
            prop_assert_eq!(back.len(), string.len());
            for i in 0..string.len() {
                prop_assert_eq!(back.sym(i), string.sym(i));
                let (a, b) = (back.params(i), string.params(i));
                prop_assert_eq!(a.len(), b.len());
                for (p, q) in a.iter().zip(b) {
                    prop_assert!(p.to_bits() == q.to_bits() || (p.is_nan() && q.is_nan()),
                        "{} became {} in '{}'", q, p, text);
                }
            }
            prop_assert_eq!(back.to_text(&symbols, " "), text);
        }
    }
}
