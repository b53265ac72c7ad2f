//! The classic notation: the first line is the axiom, each further line a production.
//! Parsing, compiling and a few derivation steps must return errors, never panic.
#![no_main]

use libfuzzer_sys::fuzz_target;
use pge_lsystem::{ModuleString, NativeHost, StepOptions, SymbolTable, System};
use rand_mt::Mt;

fuzz_target!(|text: &str| {
    let mut lines = text.lines();
    let axiom = lines.next().unwrap_or("");
    let mut symbols = SymbolTable::new();
    let mut system = System::new();
    for (i, rule) in lines.enumerate() {
        if let Some(names) = rule.strip_prefix("#declare ") {
            system.declare(names);
        } else if let Some(names) = rule.strip_prefix("#ignore ") {
            system.ignore(names, &mut symbols);
        } else if system
            .add_production(rule, None, i as u32, &mut symbols)
            .is_err()
        {
            return;
        }
    }
    if system.prepare(&symbols).is_err() {
        return;
    }
    let mut draws = 0.0;
    let Ok(mut string) = system.parse_string(axiom, &mut symbols, &mut || {
        draws += 0.37;
        draws % 1.0
    }) else {
        return;
    };
    let mut next = ModuleString::new();
    let mut rng = Mt::new(7);
    for step in 1..=4 {
        let opts = StepOptions {
            step,
            max_modules: 2_000,
            stream: false,
        };
        if system
            .step(&string, &mut next, &mut NativeHost { rng: &mut rng }, &opts)
            .is_err()
        {
            return;
        }
        std::mem::swap(&mut string, &mut next);
    }
});
