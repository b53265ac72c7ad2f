//! The peer of `pge derive` for whole-process comparisons: ABOP fig. 1.24d
//! (`X -> F[+X]F[-X]+X`, `F -> FF`) derived by the `lindenmayer` crate, printing the number of
//! modules like `pge derive --format count`.
//!
//! `cargo run --release -p pge-lsystem --example lindenmayer_peer -- 14 [string|iter]`:
//! `string` (the default) builds the string as the crate's `string` does; `iter` counts the
//! crate's streaming builder.

use lindenmayer::LSystem;

fn main() {
    let mut args = std::env::args().skip(1);
    let depth: usize = args.next().and_then(|a| a.parse().ok()).unwrap_or(14);
    let mode = args.next().unwrap_or_else(|| "string".into());
    let system = LSystem::new(String::from("X"), &[('X', "F[+X]F[-X]+X"), ('F', "FF")]);
    let n = if mode == "iter" {
        system.builder(depth).count()
    } else {
        system.string(depth).len()
    };
    println!("{n}");
}
