//! The `pge` command: run scripts, print derivations, preview models.

use std::process::ExitCode;

use clap::{Parser, Subcommand};

mod common;
mod derive;
mod merge;
mod output;
#[cfg(feature = "preview")]
mod preview;
mod run;
mod shared;
mod tiles;
mod world;

/// PGE: procedural generation driven by Lua scripts. Grows plants, trees, forests and other
/// objects and writes them as glTF 2.0.
#[derive(Parser, Debug)]
#[command(name = "pge", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Run a script and write the model it generates (.glb, or .obj by extension).
    Run(run::RunArgs),
    /// Print the string an L-system derives (text, count or json).
    Derive(derive::DeriveArgs),
    /// Open a window that shows the script's model and regenerates it on every save.
    #[cfg(feature = "preview")]
    Preview(preview::PreviewArgs),
    /// Print the tiles of a forest with `tile = T` as JSON.
    Tiles(tiles::TilesArgs),
    /// Join the tiles of a world directory (written by pge-world) into one .glb.
    Merge(merge::MergeArgs),
    /// Record, adopt and verify a world directory's manifest (DIR/world.json).
    World(world::WorldArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    output::remove_on_signals();
    let result = match &cli.command {
        Command::Run(args) => run::run(args),
        #[cfg(feature = "preview")]
        Command::Preview(args) => preview::preview(args),
        Command::Tiles(args) => tiles::tiles(args),
        Command::Merge(args) => merge::merge(args),
        Command::World(args) => world::world(args),
        Command::Derive(args) => args
            .script
            .engine()
            .and_then(|engine| derive::derive(&engine, args)),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) if common::is_closed_stdout(&e) => ExitCode::SUCCESS,
        Err(e) if e.downcast_ref::<common::Usage>().is_some() => {
            eprintln!("error: {e}");
            ExitCode::from(2)
        }
        Err(e) => {
            eprintln!("{}", common::describe_error(&e));
            ExitCode::from(1)
        }
    }
}
