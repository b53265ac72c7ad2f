//! `pge world`: the world directory's manifest (`DIR/world.json`), recorded, adopted and
//! verified. A scheduler (`pge-world` on Ray, a job array) grows the tiles; this command is
//! the one writer of the manifest, and `pge merge` reads it through the same type.

mod manifest;
mod tile;

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use clap::{Args, Subcommand};
use serde_json::{Value, json};

use manifest::{
    Identity, MANIFEST, VARIANTS_BIN, VARIANTS_JSON, VariantsEntry, read_plain, tiles_folder,
};
pub(crate) use manifest::{Manifest, TileEntry, sha256_hex};
use tile::{TileFile, entry_of};

/// Arguments of `pge world`.
#[derive(Args, Debug)]
pub struct WorldArgs {
    #[command(subcommand)]
    pub command: WorldCommand,
}

/// What `pge world` does to a world directory.
#[derive(Subcommand, Debug)]
pub enum WorldCommand {
    /// Open DIR for growing SCRIPT's world: create it and DIR/tiles (or take an empty
    /// folder), or check that its manifest is of the same world and keep the tiles whose
    /// files are intact.
    /// Prints {"created", "fresh" (no manifest before), "complete", "variants", "tiles":
    /// [[i, j], ...]} (the tiles kept).
    Init(InitArgs),
    /// Record the shared variants written into DIR (`pge run --variants-out DIR`); when they
    /// differ from the recorded ones every tile is dropped. Prints {"changed", "variants"}.
    Variants(DirArg),
    /// Record tiles written into DIR/tiles (I_J.glb), each checked to be of this world.
    Add(AddArgs),
    /// Record every tile file in DIR/tiles the manifest does not list (written by a job
    /// array), each checked to be of this world. Prints the tiles adopted, [[i, j], ...].
    Adopt(DirArg),
    /// Mark the world complete once every tile of its grid is recorded; removes what a
    /// killed writer left (.tmp* files). Prints {"tiles", "instances"}.
    Finish(DirArg),
    /// Check every file the manifest records (length and SHA-256) and that the world is
    /// complete; exit 1 naming the first problem.
    Verify(DirArg),
}

/// `pge world init`'s arguments.
#[derive(Args, Debug)]
pub struct InitArgs {
    /// The forest script (pge.Forest with tile = T).
    pub script: PathBuf,
    /// The world directory.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Seed of every random draw.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// A parameter's value, as given to `pge run --set` (repeatable).
    #[arg(long = "set", value_name = "NAME=VALUE", value_parser = crate::common::parse_set)]
    pub set: Vec<(String, String)>,
    /// The tiles carry their variants (no shared variants in DIR).
    #[arg(long)]
    pub standalone_tiles: bool,
}

/// A world directory.
#[derive(Args, Debug)]
pub struct DirArg {
    /// The world directory.
    pub dir: PathBuf,
}

/// `pge world add`'s arguments.
#[derive(Args, Debug)]
pub struct AddArgs {
    /// The world directory.
    pub dir: PathBuf,
    /// The tiles, each I,J: DIR/tiles/I_J.glb.
    #[arg(required = true, value_name = "I,J", value_parser = parse_index)]
    pub tiles: Vec<(u64, u64)>,
}

fn parse_index(s: &str) -> Result<(u64, u64), String> {
    s.split_once(',')
        .and_then(|(i, j)| Some((i.trim().parse().ok()?, j.trim().parse().ok()?)))
        .ok_or_else(|| format!("'{s}' is not I,J (two integers >= 0)"))
}

/// Runs `pge world`.
pub fn world(args: &WorldArgs) -> anyhow::Result<()> {
    let out = match &args.command {
        WorldCommand::Init(a) => init(a)?,
        WorldCommand::Variants(a) => variants(&a.dir)?,
        WorldCommand::Add(a) => {
            add(&a.dir, &a.tiles)?;
            return Ok(());
        }
        WorldCommand::Adopt(a) => adopt(&a.dir)?,
        WorldCommand::Finish(a) => finish(&a.dir)?,
        WorldCommand::Verify(a) => {
            crate::common::print_line(verify(&a.dir)?)?;
            return Ok(());
        }
    };
    crate::common::print_line(out)?;
    Ok(())
}

fn indices(m: &Manifest) -> Value {
    m.tiles.iter().map(|t| json!([t.i, t.j])).collect()
}

/// `pge world init`.
fn init(args: &InitArgs) -> anyhow::Result<Value> {
    let dir = &args.out;
    let script = std::path::absolute(&args.script)
        .with_context(|| format!("cannot resolve {}", args.script.display()))?;
    let text =
        std::fs::read(&script).with_context(|| format!("{}: no such script", script.display()))?;
    let ident = Identity {
        script_sha256: sha256_hex(&text),
        seed: args.seed,
        set: args.set.iter().cloned().collect(),
    };
    let shared = !args.standalone_tiles;
    let created = !dir.exists();
    let old = if created {
        std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
        None
    } else {
        if !dir.is_dir() {
            bail!("{}: not a folder; choose another --out", dir.display());
        }
        let old = Manifest::read(dir)?;
        if old.is_none() {
            refuse_a_folder_of_other_things(dir)?;
        }
        old
    };
    std::fs::create_dir_all(tiles_folder(dir))
        .with_context(|| format!("cannot create {}", tiles_folder(dir).display()))?;
    remove_temporaries(dir);
    let fresh = old.is_none();
    let mut m = match old {
        Some(old) if !old.is_world(&ident) => bail!(
            "{} holds another world (script {}, seed {}, set {}): choose another --out or delete \
             it",
            dir.display(),
            old.script,
            old.seed,
            serde_json::to_string(&old.set)?
        ),
        Some(old) => old,
        None => Manifest::new(&script, &ident),
    };
    m.script = script.display().to_string();
    let was = m.clone();
    if m.variants.is_some() != shared {
        // The tiles are of the other form (standalone or referring to shared variants).
        m.tiles.clear();
        m.variants = None;
    }
    let mut kept = Vec::new();
    for t in std::mem::take(&mut m.tiles) {
        if Manifest::tile_intact(dir, &t)? {
            kept.push(t);
        }
    }
    m.tiles = kept;
    // Damaged variants stay recorded: `pge world variants` compares the ones written again.
    let variants_ok = match &m.variants {
        Some(v) => VariantsEntry::of(dir)?.as_ref() == Some(v),
        None => false,
    };
    m.complete = m.complete && m.tiles == was.tiles && (!shared || variants_ok);
    m.write(dir)?;
    Ok(json!({
        "created": created,
        "fresh": fresh,
        "complete": m.complete,
        "variants": variants_ok,
        "tiles": indices(&m),
    }))
}

/// Refuses a folder without a manifest unless it is empty or holds only what a world's
/// writers leave (tiles, shared variants, temporaries): `--out` never takes over a folder of
/// other files.
fn refuse_a_folder_of_other_things(dir: &Path) -> anyhow::Result<()> {
    let refuse = |what: &str| {
        anyhow::anyhow!(
            "{}: not empty and not a world ({what}, and no {MANIFEST}): choose another --out (a \
             new or empty folder)",
            dir.display()
        )
    };
    let entries = |d: &Path| -> anyhow::Result<Vec<(String, std::fs::FileType)>> {
        std::fs::read_dir(d)
            .with_context(|| format!("cannot read {}", d.display()))?
            .map(|e| {
                let e = e?;
                Ok((e.file_name().to_string_lossy().into_owned(), e.file_type()?))
            })
            .collect()
    };
    for (name, kind) in entries(dir)? {
        let ok = match name.as_str() {
            "tiles" if kind.is_dir() => {
                for (name, kind) in entries(&tiles_folder(dir))? {
                    if !(kind.is_file() && (is_temporary(&name) || is_tile_name(&name))) {
                        return Err(refuse(&format!("it holds tiles/{name}")));
                    }
                }
                true
            }
            VARIANTS_BIN | VARIANTS_JSON => kind.is_file(),
            _ => kind.is_file() && is_temporary(&name),
        };
        if !ok {
            return Err(refuse(&format!("it holds {name}")));
        }
    }
    Ok(())
}

/// A temporary file of pge's naming (an atomic write that never finished).
fn is_temporary(name: &str) -> bool {
    name.starts_with(".tmp")
}

/// `I_J.glb`.
fn is_tile_name(name: &str) -> bool {
    tile_index(name).is_some()
}

fn tile_index(name: &str) -> Option<(u64, u64)> {
    let (i, j) = name.strip_suffix(".glb")?.split_once('_')?;
    let digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
    (digits(i) && digits(j)).then(|| Some((i.parse().ok()?, j.parse().ok()?)))?
}

/// Removes the regular `.tmp*` files in DIR and DIR/tiles: what a killed writer left.
fn remove_temporaries(dir: &Path) {
    for folder in [dir.to_path_buf(), tiles_folder(dir)] {
        let Ok(entries) = std::fs::read_dir(&folder) else {
            continue;
        };
        for e in entries.flatten() {
            let plain = e.file_type().is_ok_and(|t| t.is_file());
            if plain && is_temporary(&e.file_name().to_string_lossy()) {
                let _ = std::fs::remove_file(e.path());
            }
        }
    }
}

/// `pge world variants`.
fn variants(dir: &Path) -> anyhow::Result<Value> {
    let mut m = Manifest::read_existing(dir)?;
    let Some(entry) = VariantsEntry::of(dir)? else {
        bail!(
            "{}: no shared variants ({VARIANTS_BIN} and {VARIANTS_JSON}; pge run SCRIPT \
             --variants-out DIR writes them)",
            dir.display()
        );
    };
    let changed = m.variants.as_ref().is_some_and(|v| *v != entry);
    if changed || m.variants.is_none() {
        // The tiles refer to other variants (or to none): all grow again.
        m.tiles.clear();
        m.complete = false;
    }
    m.variants = Some(entry);
    m.write(dir)?;
    Ok(json!({"changed": changed, "variants": serde_json::to_value(&m.variants)?}))
}

/// `pge world add`.
fn add(dir: &Path, tiles: &[(u64, u64)]) -> anyhow::Result<()> {
    let mut m = Manifest::read_existing(dir)?;
    for &index in tiles {
        let Some((entry, params)) = entry_of(dir, &m, index)? else {
            bail!(
                "{}: no such tile file",
                dir.join(manifest::tile_file(index.0, index.1)).display()
            );
        };
        if m.params.is_empty() {
            m.params = params;
        }
        m.put_tile(entry);
    }
    m.write(dir)
}

/// `pge world adopt`.
fn adopt(dir: &Path) -> anyhow::Result<Value> {
    let mut m = Manifest::read_existing(dir)?;
    let listed: BTreeSet<(u64, u64)> = m.tiles.iter().map(|t| (t.i, t.j)).collect();
    let mut found: Vec<(u64, u64)> = match std::fs::read_dir(tiles_folder(dir)) {
        Ok(entries) => entries
            .flatten()
            .filter_map(|e| tile_index(&e.file_name().to_string_lossy()))
            .filter(|index| !listed.contains(index))
            .collect(),
        Err(_) => Vec::new(),
    };
    found.sort_unstable();
    for &index in &found {
        if let Some((entry, params)) = entry_of(dir, &m, index)? {
            if m.params.is_empty() {
                m.params = params;
            }
            m.put_tile(entry);
        }
    }
    m.write(dir)?;
    Ok(found.iter().map(|(i, j)| json!([i, j])).collect())
}

/// The tiles of `m`'s grid that it does not list (the grid read from its first tile).
fn missing(dir: &Path, m: &Manifest) -> anyhow::Result<Vec<(u64, u64)>> {
    let Some(first) = m.tiles.first() else {
        bail!("{}: no tile recorded yet", dir.display());
    };
    let path = dir.join(manifest::tile_file(first.i, first.j));
    let bytes = read_plain(&path)?.with_context(|| format!("{}: missing", path.display()))?;
    let listed: BTreeSet<(u64, u64)> = m.tiles.iter().map(|t| (t.i, t.j)).collect();
    Ok(TileFile::parse(&bytes, &path)?
        .grid()?
        .into_iter()
        .map(|t| (t.0, t.1))
        .filter(|index| !listed.contains(index))
        .collect())
}

fn missing_error(dir: &Path, missing: &[(u64, u64)], total: usize) -> anyhow::Error {
    let (i, j) = missing[0];
    anyhow::anyhow!(
        "{}: {} of {total} tiles not recorded (the first: {i},{j}); grow them (run pge-world \
         again on this directory)",
        dir.display(),
        missing.len()
    )
}

/// `pge world finish`.
fn finish(dir: &Path) -> anyhow::Result<Value> {
    let mut m = Manifest::read_existing(dir)?;
    let gone = missing(dir, &m)?;
    if !gone.is_empty() {
        return Err(missing_error(dir, &gone, gone.len() + m.tiles.len()));
    }
    m.complete = true;
    m.write(dir)?;
    remove_temporaries(dir);
    Ok(json!({"tiles": m.tiles.len(), "instances": m.instances}))
}

/// `pge world verify`: the line printed for a world whose every file matches.
fn verify(dir: &Path) -> anyhow::Result<String> {
    let m = Manifest::read_existing(dir)?;
    let differs = |file: &str| {
        anyhow::anyhow!(
            "{}: missing, or not the file {MANIFEST} records (length and SHA-256); run \
             pge-world again on this directory to grow it again",
            dir.join(file).display()
        )
    };
    if let Some(v) = &m.variants
        && VariantsEntry::of(dir)?.as_ref() != Some(v)
    {
        return Err(differs(VARIANTS_BIN));
    }
    for t in &m.tiles {
        if !Manifest::tile_intact(dir, t)? {
            return Err(differs(&t.file));
        }
    }
    let gone = missing(dir, &m)?;
    if !gone.is_empty() {
        return Err(missing_error(dir, &gone, gone.len() + m.tiles.len()));
    }
    if !m.complete {
        bail!(
            "{}: every tile is there but the world is not marked complete: run pge-world again \
             on this directory (or pge world finish)",
            dir.join(MANIFEST).display()
        );
    }
    let variants = if m.variants.is_some() {
        ", shared variants"
    } else {
        ""
    };
    Ok(format!(
        "{}: a complete world of {} tiles and {} instances{variants}; every file matches {MANIFEST}",
        dir.display(),
        m.tiles.len(),
        m.instances
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tile_names_are_two_indices() {
        assert_eq!(tile_index("3_14.glb"), Some((3, 14)));
        for bad in [
            "3_14.gltf",
            "_1.glb",
            "1_.glb",
            "a_1.glb",
            "1_2_3.glb",
            "-1_2.glb",
        ] {
            assert_eq!(tile_index(bad), None, "{bad}");
        }
        assert_eq!(parse_index("2, 3"), Ok((2, 3)));
        assert!(parse_index("2").is_err() && parse_index("-1,0").is_err());
    }

    #[test]
    fn only_an_empty_folder_or_one_of_a_worlds_files_is_taken_without_a_manifest() {
        let dir = tempfile::tempdir().expect("tempdir");
        let d = dir.path();
        refuse_a_folder_of_other_things(d).expect("empty");
        std::fs::create_dir(d.join("tiles")).expect("tiles");
        for f in [
            "tiles/0_1.glb",
            "tiles/.tmpAbc",
            "variants.bin",
            "variants.json",
            ".tmpX",
        ] {
            std::fs::write(d.join(f), b"x").expect("file");
        }
        refuse_a_folder_of_other_things(d).expect("a world's files");
        for other in ["notes.txt", "tiles/readme.md"] {
            std::fs::write(d.join(other), b"x").expect("file");
            let e = refuse_a_folder_of_other_things(d).expect_err(other);
            assert!(e.to_string().contains("not empty and not a world"), "{e}");
            std::fs::remove_file(d.join(other)).expect("rm");
        }
        std::fs::create_dir(d.join("src")).expect("folder");
        assert!(refuse_a_folder_of_other_things(d).is_err());
    }

    #[test]
    fn temporaries_of_our_naming_are_removed_and_nothing_else() {
        let dir = tempfile::tempdir().expect("tempdir");
        let d = dir.path();
        std::fs::create_dir(d.join("tiles")).expect("tiles");
        for f in [
            "tiles/.tmpA",
            ".tmpB",
            "tiles/0_0.glb",
            "tiles/tmp",
            "keep.tmp",
        ] {
            std::fs::write(d.join(f), b"x").expect("file");
        }
        std::fs::create_dir(d.join(".tmpdir")).expect("folder");
        remove_temporaries(d);
        for (f, there) in [
            ("tiles/.tmpA", false),
            (".tmpB", false),
            ("tiles/0_0.glb", true),
            ("tiles/tmp", true),
            ("keep.tmp", true),
            (".tmpdir", true),
        ] {
            assert_eq!(d.join(f).exists(), there, "{f}");
        }
    }
}
