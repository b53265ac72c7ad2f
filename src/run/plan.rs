//! What `pge run` does, decided once from its flags: a [`Plan`] of typed modes that the
//! run then carries out without looking at the flags again.

use std::fmt;
use std::path::PathBuf;

use pge_engine::export::SharedVariants;

use super::RunArgs;
use crate::common::usage;

/// What a run does.
pub(crate) enum Plan {
    /// `--stages`: one individual at several growth stages, each a scene of one glb.
    Stages {
        /// The increasing step counts.
        stages: Vec<u32>,
        /// The glb.
        output: PathBuf,
    },
    /// The script run once per target, each writing one file.
    Runs {
        /// What each run writes.
        product: Product,
        /// Where.
        targets: Targets,
    },
}

/// What each run of a [`Plan::Runs`] writes.
pub(crate) enum Product {
    /// The model: a .glb, an .obj, a .usda or a .usdz.
    Model,
    /// The variants of the forest's layers of a few variants, once (`--variants-out DIR`).
    SharedVariants(PathBuf),
    /// A glb that refers to the shared variants of a folder (`--variants DIR`), read and
    /// checked before anything runs.
    Referring {
        /// The folder.
        dir: PathBuf,
        /// Its description (boxed: it is large, the other products are a path at most).
        shared: Box<SharedVariants>,
    },
}

/// The runs of a [`Plan::Runs`].
pub(crate) enum Targets {
    /// One run: the whole script, or one tile of its forest.
    One(Target),
    /// `--tile I,J... --out-dir DIR`: each tile to `DIR/I_J.glb`, one after the other.
    Tiles {
        /// The folder.
        dir: PathBuf,
        /// The tiles, in the order given.
        tiles: Vec<(usize, usize)>,
    },
}

/// One run: a tile of the forest (or the whole script) and the file it writes.
pub(crate) struct Target {
    /// The tile, if one.
    pub(crate) tile: Option<(usize, usize)>,
    /// The file.
    pub(crate) output: PathBuf,
}

/// The flag that makes a run need a forest, named in the error when the script returns
/// something else.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum ForestFlag {
    /// `--tile`.
    Tile,
    /// `--variants-out`.
    VariantsOut,
    /// `--variants`.
    Variants,
}

impl fmt::Display for ForestFlag {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            ForestFlag::Tile => "--tile",
            ForestFlag::VariantsOut => "--variants-out",
            ForestFlag::Variants => "--variants",
        })
    }
}

impl Product {
    /// The flag that asks for a forest, if this product or the tile does.
    pub(crate) fn forest_flag(&self, tile: Option<(usize, usize)>) -> Option<ForestFlag> {
        match self {
            Product::SharedVariants(_) => Some(ForestFlag::VariantsOut),
            Product::Referring { .. } => Some(ForestFlag::Variants),
            Product::Model => tile.map(|_| ForestFlag::Tile),
        }
    }
}

impl Plan {
    /// The plan of `args`: a usage error for a combination `pge run` cannot do; with
    /// `--variants DIR`, the shared variants' description read and checked.
    pub(crate) fn decide(args: &RunArgs) -> anyhow::Result<Plan> {
        if let Some(dir) = &args.out_dir {
            let targets = Targets::Tiles {
                dir: dir.clone(),
                tiles: args.tile.clone(),
            };
            return Ok(Plan::Runs {
                product: product(args)?,
                targets,
            });
        }
        if args.tile.len() > 1 {
            usage!(
                "{} tiles need --out-dir DIR (each is written to DIR/I_J.glb)",
                args.tile.len()
            );
        }
        let output = match &args.output {
            Some(o) => o.clone(),
            None => PathBuf::from(args.script.script.file_stem().unwrap_or_default())
                .with_extension("glb"),
        };
        let ext = output
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        if !matches!(ext.as_deref(), Some("glb" | "obj" | "usda" | "usdz")) {
            usage!(
                "{}: the output must end in .glb, .obj, .usda or .usdz",
                output.display()
            );
        }
        if let Some(stages) = &args.stages {
            if !matches!(ext.as_deref(), Some("glb" | "usda" | "usdz")) {
                usage!(
                    "{}: --stages writes one scene per stage, which needs a .glb, .usda or \
                     .usdz output",
                    output.display()
                );
            }
            return Ok(Plan::Stages {
                stages: stages.clone(),
                output,
            });
        }
        if args.variants.is_some() && ext.as_deref() != Some("glb") {
            usage!(
                "{}: --variants writes a glb that refers to the shared variants, which needs a \
                 .glb output",
                output.display()
            );
        }
        let target = Target {
            tile: args.tile.first().copied(),
            output,
        };
        Ok(Plan::Runs {
            product: product(args)?,
            targets: Targets::One(target),
        })
    }
}

/// What the runs write (clap has refused `--variants-out` with `--variants`).
fn product(args: &RunArgs) -> anyhow::Result<Product> {
    Ok(match (&args.variants_out, &args.variants) {
        (Some(dir), _) => Product::SharedVariants(dir.clone()),
        (None, Some(dir)) => Product::Referring {
            dir: dir.clone(),
            shared: Box::new(crate::shared::read_variants(
                dir,
                &args.script.script,
                args.script.seed,
            )?),
        },
        (None, None) => Product::Model,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        run: RunArgs,
    }

    fn plan(args: &[&str]) -> anyhow::Result<Plan> {
        let cli = Cli::try_parse_from(["pge"].iter().chain(args)).expect("parses");
        Plan::decide(&cli.run)
    }

    #[test]
    fn the_output_defaults_to_the_script_stem_and_must_be_glb_obj_or_usd() {
        let Plan::Runs {
            product: Product::Model,
            targets: Targets::One(t),
        } = plan(&["scripts/species/oak.lua"]).expect("plan")
        else {
            panic!("one model");
        };
        assert_eq!((t.tile, t.output), (None, PathBuf::from("oak.glb")));
        assert!(plan(&["a.lua", "-o", "a.usda"]).is_ok());
        assert!(plan(&["a.lua", "-o", "a.usdz"]).is_ok());
        let e = plan(&["a.lua", "-o", "a.png"]).err().expect("usage");
        assert!(e.downcast_ref::<crate::common::Usage>().is_some(), "{e}");
    }

    #[test]
    fn stages_need_a_glb_and_tiles_an_out_dir() {
        assert!(matches!(
            plan(&["a.lua", "--stages", "1,2"]).expect("plan"),
            Plan::Stages { ref stages, .. } if stages == &[1, 2]
        ));
        assert!(plan(&["a.lua", "--stages", "1,2", "-o", "a.obj"]).is_err());
        for usd in ["a.usda", "a.USDZ"] {
            assert!(matches!(
                plan(&["a.lua", "--stages", "1,2", "-o", usd]).expect("plan"),
                Plan::Stages { .. }
            ));
        }
        assert!(plan(&["a.lua", "--tile", "0,0", "--tile", "0,1"]).is_err());
        let Plan::Runs { targets, product } =
            plan(&["a.lua", "--tile", "0,0", "--tile", "2,1", "--out-dir", "d"]).expect("plan")
        else {
            panic!("runs");
        };
        let Targets::Tiles { dir, tiles } = targets else {
            panic!("tiles");
        };
        assert_eq!((dir, tiles), (PathBuf::from("d"), vec![(0, 0), (2, 1)]));
        assert_eq!(product.forest_flag(Some((2, 1))), Some(ForestFlag::Tile));
        assert_eq!(Product::Model.forest_flag(None), None);
        assert_eq!(ForestFlag::VariantsOut.to_string(), "--variants-out");
    }
}
