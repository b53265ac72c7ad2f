//! Tests of steps counted without being kept, and of steps taken depth first, against the
//! same steps taken whole one after the other.

use super::*;

/// One step of `r` under the cap `max`, whole and counted: the module count or the error.
fn whole_and_counted(r: &Run, max: usize) -> (Result<usize, LsError>, Result<u64, LsError>) {
    let opts = DeriveOptions::new(r.steps + 1, 1, max);
    let mut out = ModuleString::new();
    let whole = r
        .prepared
        .derive(
            &r.string,
            &opts,
            &mut NativeHost {
                rng: &mut r.rng.clone(),
            },
            Output::Keep(&mut out),
        )
        .map(|_| out.len());
    let counted = r.prepared.derive(
        &r.string,
        &opts,
        &mut NativeHost {
            rng: &mut r.rng.clone(),
        },
        Output::Count,
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

/// `n` steps of `r` under the cap `max`, one after the other: the lengths of their strings
/// and the last string, or the first error.
fn whole_steps(r: &Run, n: u32, max: usize) -> Result<(Vec<u64>, ModuleString), LsError> {
    let mut rng = r.rng.clone();
    let mut string = r.string.clone();
    let mut next = ModuleString::new();
    let mut lengths = Vec::new();
    for k in 0..n {
        r.prepared.derive(
            &string,
            &DeriveOptions::new(r.steps + 1 + k, 1, max),
            &mut NativeHost { rng: &mut rng },
            Output::Keep(&mut next),
        )?;
        std::mem::swap(&mut string, &mut next);
        lengths.push(string.len() as u64);
    }
    Ok((lengths, string))
}

#[test]
fn steps_in_pieces_equal_steps_one_after_the_other() {
    // A later step fails in an earlier piece than an earlier step's own failure: the
    // earlier step's error.
    let late = format!("B(1e200){}A(1e300)", " F".repeat(5000));
    // (axiom, rules, taken depth first)
    let cases: [(&str, &[&str], bool); 10] = [
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
        // Fixed strings: counted a symbol at a time, written depth first.
        ("X", &["X -> F[+X]F[-X]+X", "F -> FF"], true),
        ("X", &["X -> F[+X]F[-X]+X", "F -> FF", "F -> G"], true),
        // Fixed strings that shrink, and a symbol whose successor is empty.
        ("AB", &["A -> ABA", "B -> C", "C -> "], true),
        // Overflow: the error of the step in which it happens, even when a later step
        // overflows in an earlier piece than the earlier step's own failure.
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
        assert_eq!(r.prepared.derives_in_pieces(), depth_first, "{axiom}");
        for _ in 0..5 {
            for n in 1..=4 {
                let whole = whole_steps(&r, n, r.max);
                let lengths = match &whole {
                    Ok((lengths, _)) => lengths.clone(),
                    Err(_) => vec![1; n as usize],
                };
                failures += usize::from(whole.is_err());
                let mut caps = vec![r.max as u64, 0];
                for &len in &lengths {
                    caps.extend([len, len.saturating_sub(1), len / 2]);
                }
                for max in caps {
                    let max = max as usize;
                    let want = whole_steps(&r, n, max).map(|(l, _)| l[l.len() - 1]);
                    let opts = DeriveOptions::new(r.steps + 1, n, max);
                    let got = r.prepared.derive(
                        &r.string,
                        &opts,
                        &mut NativeHost {
                            rng: &mut r.rng.clone(),
                        },
                        Output::Count,
                    );
                    let what = format!(
                        "{}, {n} steps after {} under {max}",
                        axiom.chars().take(8).collect::<String>(),
                        r.steps
                    );
                    assert_eq!(got, want, "counted: {what}");
                    let mut joined = ModuleString::new();
                    let got = r.prepared.derive(
                        &r.string,
                        &opts,
                        &mut NativeHost {
                            rng: &mut r.rng.clone(),
                        },
                        Output::Pieces(&mut |piece| {
                            joined.append(piece);
                            Ok(())
                        }),
                    );
                    assert_eq!(got, want, "in pieces: {what}");
                    if let (Ok(_), Ok((_, string))) = (&got, &whole)
                        && max == r.max
                    {
                        assert_eq!(&joined, string, "in pieces: {what}");
                    }
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
