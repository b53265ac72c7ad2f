//! The peer of `pge derive` for whole-process comparisons: ABOP fig. 1.24d
//! (`X -> F[+X]F[-X]+X`, `F -> FF`) derived by the `lindenmayer` crate.
//!
//! `cargo run --release -p pge-lsystem --example lindenmayer_peer -- 14 MODE`, where MODE is
//! - `iter` (the default): counts the modules of the crate's streaming builder, which never
//!   holds the string; the peer of `pge derive --format count`, which counts its last steps
//!   without keeping them either. Prints the count.
//! - `text`: builds the whole string with the crate's `string`, then writes it as
//!   `pge derive --format text` does (modules separated by one space, then a newline); the
//!   two outputs are the same bytes.
//! - `string`: builds the whole string with the crate's `string` and prints its length (the
//!   peer's fastest way to make the string; `pge derive` has no mode that only builds it).

use std::io::{BufWriter, Write};

use lindenmayer::LSystem;

fn main() -> std::io::Result<()> {
    let mut args = std::env::args().skip(1);
    let depth: usize = args.next().and_then(|a| a.parse().ok()).unwrap_or(14);
    let mode = args.next().unwrap_or_else(|| "iter".into());
    let system = LSystem::new(String::from("X"), &[('X', "F[+X]F[-X]+X"), ('F', "FF")]);
    let stdout = std::io::stdout();
    let mut out = BufWriter::new(stdout.lock());
    match mode.as_str() {
        "iter" => writeln!(out, "{}", system.builder(depth).count())?,
        "string" => writeln!(out, "{}", system.string(depth).len())?,
        "text" => {
            let string = system.string(depth);
            let mut piece = Vec::with_capacity(1 << 17);
            for (i, c) in string.bytes().enumerate() {
                if i > 0 {
                    piece.push(b' ');
                }
                piece.push(c);
                if piece.len() >= 1 << 16 {
                    out.write_all(&piece)?;
                    piece.clear();
                }
            }
            piece.push(b'\n');
            out.write_all(&piece)?;
        }
        other => {
            eprintln!("lindenmayer_peer: mode must be iter, text or string, not '{other}'");
            std::process::exit(2);
        }
    }
    out.flush()
}
