//! Helpers shared by the end-to-end tests: where the repository is and how to run `pge`.

#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The repository root (scripts are given relative to it).
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Runs `pge` with `args` in the repository root.
pub fn pge(args: &[&str]) -> Output {
    pge_in(args, &root())
}

/// Runs `pge` with `args` in `cwd`.
pub fn pge_in(args: &[&str], cwd: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_pge"))
        .args(args)
        .current_dir(cwd)
        .output()
        .expect("the pge binary runs")
}
