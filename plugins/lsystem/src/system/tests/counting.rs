//! Tests of steps counted without being kept, and of two steps taken depth first, against
//! the same steps taken whole.

use super::*;

/// One step of `r` under the cap `max`, whole and counted: the module count or the error.
fn whole_and_counted(r: &Run, max: usize) -> (Result<usize, LsError>, Result<u64, LsError>) {
    let opts = StepOptions {
        step: r.steps + 1,
        max_modules: max,
        stream: false,
    };
    let mut out = ModuleString::new();
    let whole = r
        .system
        .step(
            &r.string,
            &mut out,
            &mut NativeHost {
                rng: &mut r.rng.clone(),
            },
            &opts,
        )
        .map(|()| out.len());
    let counted = r.system.step_count(
        &r.string,
        &mut NativeHost {
            rng: &mut r.rng.clone(),
        },
        &opts,
    );
    (whole, counted)
}

#[test]
fn a_counted_step_has_the_length_and_the_errors_of_the_step() {
    // Conditions, random arguments and conditions (the same draws in the same order),
    // stochastic alternatives, rules applied without matching (one rule per symbol, no
    // context) beside rules with contexts, modules without rules in runs.
    let cases: [(&str, &[&str], &[f64]); 5] = [
        (
            "A(1,10)",
            &[
                "A(l,w) -> !(w)F(l)[&(45)B(l*0.6,w*0.7)]/(137.5)A(l*0.9,w*0.7)",
                "B(l,w) : l > 0.2 -> !(w)F(l)[-(45)$B(l*0.6,w*0.7)]B(l*0.9,w*0.7)",
            ],
            &[],
        ),
        (
            "A(1)",
            &[
                "A(x) : rand() < 0.6 -> A(x+rand()) [B(x)] C",
                "B(x) -> B(x*2) C C",
                "C < B(x) -> D(x)",
            ],
            &[],
        ),
        (
            "A(1)",
            &["A(x) -> A(x+1) B(x)", "A(x) -> B(x) A(x*2)"],
            &[1.0, 3.0],
        ),
        // A parameter that overflows: the error of the step, from the count.
        ("A(1)", &["A(x) -> A(x*1e80) F"], &[]),
        // The wrong number of parameters.
        ("A(1) F A(1,2)", &["A(x) -> A(x) A(x)"], &[]),
    ];
    let mut failed = Vec::new();
    for (axiom, rules, weights) in cases {
        let mut r = Run::with(axiom, &[], |system, symbols| {
            for (k, rule) in rules.iter().enumerate() {
                system
                    .add_production(rule, weights.get(k).copied(), 0, symbols)
                    .expect("rule");
            }
        });
        for step in 0..6 {
            let (whole, counted) = whole_and_counted(&r, r.max);
            assert_eq!(
                whole.clone().map(|n| n as u64),
                counted,
                "{axiom} at step {step}"
            );
            let Ok(len) = whole else {
                failed.push(axiom);
                break;
            };
            // Every cap below the length fails as the step fails.
            for max in [0, 1, len / 3, len / 2, len.saturating_sub(1)] {
                let (whole, counted) = whole_and_counted(&r, max);
                assert_eq!(whole.map(|n| n as u64), counted, "{axiom} under {max}");
            }
            if r.step().is_err() {
                break;
            }
        }
    }
    // The overflow and the wrong number of parameters were met.
    assert_eq!(failed, ["A(1)", "A(1) F A(1,2)"]);
}

/// Two steps of `r` under the cap `max`, one after the other: the lengths and the second
/// string, or the first error.
fn two_whole_steps(r: &Run, max: usize) -> Result<(u64, u64, ModuleString), LsError> {
    let mut rng = r.rng.clone();
    let mut strings = [r.string.clone(), ModuleString::new(), ModuleString::new()];
    for k in 0..2 {
        let opts = StepOptions {
            step: r.steps + 1 + k as u32,
            max_modules: max,
            stream: false,
        };
        let (done, rest) = strings.split_at_mut(k + 1);
        r.system.step(
            &done[k],
            &mut rest[0],
            &mut NativeHost { rng: &mut rng },
            &opts,
        )?;
    }
    let [_, a, b] = strings;
    Ok((a.len() as u64, b.len() as u64, b))
}

#[test]
fn two_steps_depth_first_equal_two_steps_one_after_the_other() {
    // The first step fails in a later piece than the second: the first step's error.
    let late = format!("B(1e200){}A(1e300)", " F".repeat(5000));
    // (axiom, rules, taken depth first)
    let cases: [(&str, &[&str], bool); 9] = [
        (
            &late,
            &[
                "B(x) -> D(x*1e100)",
                "D(x) -> D(x*1e10)",
                "A(x) -> A(x*1e10)",
            ],
            true,
        ),
        (
            "A(1,10)",
            &[
                "A(l,w) -> !(w)F(l)[&(45)B(l*0.6,w*0.7)]/(137.5)A(l*0.9,w*0.7)",
                "B(l,w) : l > 0.2 -> !(w)F(l)[-(45)$B(l*0.6,w*0.7)]B(l*0.9,w*0.7)",
            ],
            true,
        ),
        ("X", &["X -> F[+X]F[-X]+X", "F -> FF"], false),
        ("X", &["X -> F[+X]F[-X]+X", "F -> FF", "F -> G"], true),
        // Overflow: the error of the step in which it happens, even when the second step of
        // a pair overflows in an earlier piece than the first step's own failure.
        (
            "A(1)",
            &["A(x) -> A(x*1e100) F B(x)", "B(x) -> B(x) C(x*1e150)"],
            true,
        ),
        ("A(1) F A(1,2)", &["A(x) -> A(x) A(x)"], true),
        (
            "baaa[aa]a[a[a]a]aa",
            &["b < a -> b", "b -> c", "a > b -> d"],
            false,
        ),
        ("A(1)", &["A(x) -> A(x+rand()) B(x)", "B(x) -> B(x)"], false),
        (
            "A(1)",
            &["A(x) : x < 3 -> A(x+1) [B(x)] A(x+2)", "B(x) -> C B(x)"],
            true,
        ),
    ];
    let mut failures = 0;
    for (axiom, rules, depth_first) in cases {
        let mut r = Run::new(axiom, rules);
        for _ in 0..5 {
            let first = StepOptions {
                step: r.steps + 1,
                max_modules: r.max,
                stream: false,
            };
            let second = StepOptions {
                step: r.steps + 2,
                ..first
            };
            assert_eq!(
                r.system.two_steps_depth_first(&first, &second),
                depth_first,
                "{axiom}"
            );
            let whole = two_whole_steps(&r, r.max);
            let (n1, n2) = match &whole {
                Ok((n1, n2, _)) => (*n1 as usize, *n2 as usize),
                Err(_) => (1, 1),
            };
            failures += usize::from(whole.is_err());
            for max in [r.max, n2, n2 - 1, n2 / 2, n1, n1 - 1, n1 / 2, 0] {
                let want = two_whole_steps(&r, max).map(|(a, b, _)| (a, b));
                let first = StepOptions {
                    max_modules: max,
                    ..first
                };
                let second = StepOptions {
                    max_modules: max,
                    ..second
                };
                let mut rng = r.rng.clone();
                let got = r.system.count_two_steps(
                    &r.string,
                    &mut NativeHost { rng: &mut rng },
                    &first,
                    &second,
                );
                assert_eq!(
                    got,
                    want,
                    "{} after {} steps under {max}",
                    axiom.chars().take(8).collect::<String>(),
                    r.steps
                );
            }
            if let Ok((_, n2, string)) = &whole {
                for chunk in [1, 5, 100_000] {
                    let mut joined = ModuleString::new();
                    let mut buf = ModuleString::new();
                    let n = r
                        .system
                        .step_chunks_two(
                            &r.string,
                            &mut buf,
                            &mut NativeHost {
                                rng: &mut r.rng.clone(),
                            },
                            &first,
                            &second,
                            chunk,
                            &mut |piece| {
                                joined.append(piece);
                                Ok(())
                            },
                        )
                        .expect("derives");
                    assert_eq!(n, *n2);
                    assert_eq!(&joined, string, "{axiom} in pieces of {chunk}");
                }
            }
            if r.step().is_err() {
                break;
            }
        }
    }
    // The overflows and the wrong number of parameters were met.
    assert!(failures >= 3, "{failures}");
}
