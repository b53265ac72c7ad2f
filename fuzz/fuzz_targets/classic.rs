//! The classic notation: the first line is the axiom, each further line a production.
//! Parsing, compiling and a few derivation steps (kept, counted and in pieces) must return
//! errors, never panic.
#![no_main]

use libfuzzer_sys::fuzz_target;
use pge_lsystem::{DeriveOptions, ModuleString, NativeHost, Output, SymbolTable, System};
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
    let Ok(prepared) = system.prepare(&symbols) else {
        return;
    };
    let mut draws = 0.0;
    let Ok(axiom) = system.parse_string(axiom, &mut symbols, &mut || {
        draws += 0.37;
        draws % 1.0
    }) else {
        return;
    };
    // Four steps kept, counted and in pieces: however the derivation takes them.
    let opts = DeriveOptions::new(1, 4, 2_000);
    let mut string = ModuleString::new();
    let _ = prepared.derive(
        &axiom,
        &opts,
        &mut NativeHost { rng: &mut Mt::new(7) },
        Output::Keep(&mut string),
    );
    let _ = prepared.derive(
        &axiom,
        &opts,
        &mut NativeHost { rng: &mut Mt::new(7) },
        Output::Count,
    );
    let _ = prepared.derive(
        &axiom,
        &opts,
        &mut NativeHost { rng: &mut Mt::new(7) },
        Output::Pieces(&mut |_| Ok(())),
    );
});
