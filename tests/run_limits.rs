//! `--time-limit` and `--memory-limit` bound everything a run does, not only its Lua: the
//! forest's layout, the terrain mesh, the tile list, a forest's variants (one deadline for the
//! whole run), and the buffers a script keeps. Each case runs the real `pge` on a small
//! script and checks the typed limit: exit 1, one `FILE:LINE: ...` line naming the limit
//! (and the option that sized the work), no output file. The limits are tiny next to the
//! work asked for, so the cases do not depend on the machine's speed.

mod common;

use std::path::{Path, PathBuf};
use std::process::Output;

use common::pge_in;

/// A one-triangle species.
const STICK: &str = "return pge.mesh{ positions = {0,0,0, 1,0,0, 0,1,0}, indices = {0,1,2} }\n";

/// A folder with `main.lua`, a `stick.lua` species and an `out` folder.
struct Case {
    dir: tempfile::TempDir,
}

impl Case {
    fn new(source: &str) -> Case {
        let dir = tempfile::tempdir().expect("tempdir");
        std::fs::write(dir.path().join("main.lua"), source).expect("script");
        std::fs::write(dir.path().join("stick.lua"), STICK).expect("species");
        std::fs::create_dir(dir.path().join("out")).expect("output folder");
        Case { dir }
    }

    fn path(&self) -> &Path {
        self.dir.path()
    }

    fn pge(&self, args: &[&str]) -> Output {
        pge_in(args, self.path())
    }

    /// `pge run main.lua -o out/model.glb -q` plus `extra`.
    fn run(&self, extra: &[&str]) -> Output {
        let mut args = vec!["run", "main.lua", "-o", "out/model.glb", "-q"];
        args.extend_from_slice(extra);
        self.pge(&args)
    }

    fn output(&self) -> PathBuf {
        self.path().join("out/model.glb")
    }
}

/// Checks a limit: exit 1, one line `AT: ...` holding every needle, no panic, no output.
fn limit(o: &Output, at: &str, needles: &[&str], output: &Path) -> String {
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert_eq!(o.status.code(), Some(1), "exit code: {err}");
    assert!(!err.contains("panicked"), "a panic: {err}");
    assert_eq!(err.trim_end().lines().count(), 1, "one line: {err}");
    assert!(
        err.starts_with(&format!("{at}: ")),
        "expected '{at}: ...': {err}"
    );
    for needle in needles {
        assert!(err.contains(needle), "expected '{needle}' in: {err}");
    }
    assert!(!output.exists(), "an output was written");
    err
}

const TIME: &str = "time limit exceeded (see --time-limit)";
const MEMORY: &str = "MiB exceeded (see --memory-limit)";

/// About 4.7 million trunks: seconds of layout and hundreds of MiB.
const BIG_FOREST: &str = "local forest = pge.Forest{ size = {3000, 3000}, seed = 7 }\n\
     forest:scatter{ species = \"stick.lua\", minDistance = 1.2, variants = 1 }\n\
     return forest\n";

#[test]
fn a_forest_layout_stops_at_the_time_limit() {
    let case = Case::new(BIG_FOREST);
    let o = case.run(&["--time-limit", "0.2"]);
    limit(&o, "main.lua:1", &[TIME], &case.output());
}

#[test]
fn a_forest_layout_past_the_memory_limit_is_refused_before_it_runs() {
    // Placed at the layer whose options asked for the trees.
    let case = Case::new(BIG_FOREST);
    let o = case.run(&["--memory-limit", "64"]);
    limit(
        &o,
        "main.lua:2",
        &["the layout of about", "memory limit of 64 MiB exceeded"],
        &case.output(),
    );
}

#[test]
fn a_layout_too_big_points_at_the_layer_that_makes_it_so() {
    // A sparse layer, then a dense one: the dense one's line, for the memory limit and for
    // the cap on instances alike.
    let forest = |dense: &str| {
        format!(
            "local forest = pge.Forest{{ size = {{3000, 3000}}, seed = 7 }}\n\
             forest:scatter{{ species = \"stick.lua\", minDistance = 20, variants = 1 }}\n\
             forest:scatter{{ species = \"stick.lua\", minDistance = {dense}, variants = 1 }}\n\
             return forest\n"
        )
    };
    let case = Case::new(&forest("1.2"));
    let o = case.run(&["--memory-limit", "64"]);
    limit(
        &o,
        "main.lua:3",
        &["the layout of about", "memory limit of 64 MiB exceeded"],
        &case.output(),
    );
    let case = Case::new(&forest("0.5"));
    let o = case.run(&[]);
    limit(
        &o,
        "main.lua:3",
        &["more than the limit of 10000000", "raise minDistance"],
        &case.output(),
    );
}

#[test]
fn a_terrain_mesh_is_sized_before_it_is_made() {
    // A fine resolution: 20001 x 20001 vertices, about 21 GiB.
    let case = Case::new(
        "local forest = pge.Forest{ size = {1000, 1000}, seed = 7 }\n\
         forest:terrain{ height = 10, resolution = 0.05 }\n\
         return forest\n",
    );
    let o = case.run(&["--memory-limit", "256"]);
    limit(
        &o,
        "main.lua:1",
        &["terrain mesh", "resolution = 0.05", MEMORY],
        &case.output(),
    );
    // A 200 km world without terrain: the default 4 m grid, about 130 GiB.
    let case = Case::new("return pge.Forest{ size = {200000, 200000}, seed = 7 }\n");
    let o = case.run(&[]);
    limit(
        &o,
        "main.lua:1",
        &["terrain mesh", "resolution = 4", MEMORY],
        &case.output(),
    );
    // 300 km: more vertices than 32-bit indices number, whatever the memory.
    let case = Case::new("return pge.Forest{ size = {300000, 300000}, seed = 7 }\n");
    let o = case.run(&[]);
    let err = limit(
        &o,
        "main.lua:1",
        &["resolution", "4294967295"],
        &case.output(),
    );
    assert!(!err.contains("memory limit"), "{err}");
}

#[test]
fn tiny_tiles_are_counted_not_listed() {
    let case = Case::new(
        "local forest = pge.Forest{ size = {1000, 1000}, seed = 7, tile = 0.01 }\n\
         forest:scatter{ species = \"stick.lua\", minDistance = 10, variants = 1 }\n\
         return forest\n",
    );
    // One tile of 10^10 is found without listing them.
    let o = case.run(&["--tile", "50000,50000"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(case.output().is_file());
    std::fs::remove_file(case.output()).expect("remove the tile");
    let o = case.run(&["--tile", "100000,0"]);
    limit(
        &o,
        "main.lua:1",
        &["tile 100000,0 is out of range", "100000 x 100000 tiles"],
        &case.output(),
    );
    // Listing them is past any memory limit.
    let o = case.pge(&["tiles", "main.lua"]);
    limit(
        &o,
        "main.lua:1",
        &["tile = 0.01 makes 100000 x 100000 tiles", MEMORY],
        &case.output().with_extension("none"),
    );
    assert!(o.stdout.is_empty());
    let case = Case::new(
        "local forest = pge.Forest{ size = {1000, 1000}, seed = 7, tile = 0.01 }\n\
         local tiles = forest:tiles()\n\
         return forest\n",
    );
    let o = case.run(&[]);
    limit(
        &o,
        "main.lua:2",
        &["tiles, too many to list", MEMORY],
        &case.output(),
    );
}

#[test]
fn a_forests_variants_share_the_runs_deadline() {
    // Eight variants that never end: each stops at the run's deadline, not at one of its
    // own, and the run reports the limit where the species script was.
    let case = Case::new(
        "local forest = pge.Forest{ size = {100, 100}, seed = 7 }\n\
         forest:scatter{ species = \"loop.lua\", minDistance = 10, variants = 8 }\n\
         return forest\n",
    );
    std::fs::write(
        case.path().join("loop.lua"),
        "local i = 0\nwhile true do i = i + 1 end\n",
    )
    .expect("species");
    let o = case.run(&["--time-limit", "0.5", "--threads", "2"]);
    limit(&o, "loop.lua:2", &[TIME], &case.output());
}

#[test]
fn a_variant_that_fails_stops_the_others() {
    // One variant fails at once; the ones that loop are stopped, and the failure is the
    // run's error (not a time limit, not "cancelled").
    let case = Case::new(
        "local forest = pge.Forest{ size = {100, 100}, seed = 7 }\n\
         forest:scatter{ species = \"some.lua\", minDistance = 10, variants = 8 }\n\
         return forest\n",
    );
    std::fs::write(
        case.path().join("some.lua"),
        "if pge.random() < 0.5 then error('no sap') end\nwhile true do end\n",
    )
    .expect("species");
    let o = case.run(&["--time-limit", "100", "--threads", "2"]);
    let err = limit(&o, "main.lua:2", &["some.lua:1: no sap"], &case.output());
    assert!(!err.contains("cancelled"), "{err}");
}

#[test]
fn the_foliage_lod_stops_at_the_time_limit() {
    // 120 000 leaves given levels of detail: tens of seconds of simplification.
    let case = Case::new(
        "local s = pge.Skeleton()\n\
         local root = s:add(0, {0, 0, 0}, 0.3)\n\
         for i = 1, 3000 do\n\
           local a, r = i * 2.399, 1 + (i % 50) * 0.08\n\
           s:add(root, {r * math.cos(a), 2 + (i % 97) * 0.05, r * math.sin(a)}, 0.01)\n\
         end\n\
         return pge.tree{ skeleton = s, leaves = { perTip = {40, 40}, size = 0.2 },\n\
           lod = {} }\n",
    );
    let o = case.run(&["--time-limit", "1"]);
    limit(&o, "main.lua:7", &[TIME], &case.output());
}

#[test]
fn skeletons_a_script_keeps_are_charged_to_its_memory_limit() {
    let case = Case::new(
        "local s = pge.Skeleton()\n\
         local p = 0\n\
         for i = 1, 100000 do p = s:add(p, {0, i * 0.01, 0}, 0.1) end\n\
         local keep = {}\n\
         for i = 1, 400 do keep[i] = s:copy() end\n\
         return pge.mesh{ positions = {0,0,0, 1,0,0, 0,1,0}, indices = {0,1,2} }\n",
    );
    let o = case.run(&["--memory-limit", "128"]);
    limit(
        &o,
        "main.lua:5",
        &["pge.Skeleton", "memory limit of 128 MiB exceeded"],
        &case.output(),
    );
    // Copies that are dropped are given back.
    let case = Case::new(
        "local s = pge.Skeleton()\n\
         local p = 0\n\
         for i = 1, 100000 do p = s:add(p, {0, i * 0.01, 0}, 0.1) end\n\
         for i = 1, 400 do local c = s:copy() end\n\
         return pge.mesh{ positions = {0,0,0, 1,0,0, 0,1,0}, indices = {0,1,2} }\n",
    );
    let o = case.run(&["--memory-limit", "128"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

/// The forest of `big.lua`'s densities (its three layers, flat ground), `size` metres square
/// in tiles of 250 m.
fn world(size: u32) -> String {
    format!(
        "local forest = pge.Forest{{ size = {{{size}, {size}}}, seed = 7, tile = 250 }}\n\
         forest:scatter{{ species = \"stick.lua\", minDistance = 9, variants = 8 }}\n\
         forest:scatter{{ species = \"stick.lua\", minDistance = 2.7, variants = 8 }}\n\
         forest:scatter{{ species = \"stick.lua\", minDistance = 2.2, density = 0.8, \
         variants = 8, scale = {{0.5, 1.0}} }}\n\
         return forest\n"
    )
}

#[test]
fn a_tile_of_a_100_km2_world_is_a_tile_like_any_other() {
    // The whole world would hold about 23 million trees, past the layout's cap: a tile
    // counts its own region only.
    let stats = |size: u32, tile: &str| {
        let case = Case::new(&world(size));
        let o = case.run(&["--tile", tile, "--stats"]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        assert!(case.output().is_file());
        let stats: serde_json::Value =
            serde_json::from_slice(&o.stdout).expect("the stats are JSON");
        stats
    };
    let (small, large) = (stats(1000, "1,1"), stats(10_000, "20,20"));
    let count = |s: &serde_json::Value| s["instances"].as_f64().expect("instances");
    let (a, b) = (count(&small), count(&large));
    assert!(a > 5000.0, "{a}");
    assert!((a - b).abs() / a < 0.05, "{a} vs {b} instances");
    assert_eq!(small["meshes"], large["meshes"]);
    assert_eq!(small["tile"].as_array().map(Vec::len), Some(2));
}

#[test]
fn a_tiles_leaf_budget_lays_out_the_whole_world_within_the_limits() {
    // With a camera, a tile's leaves are budgeted on the whole forest's layout: about 4.7
    // million trunks here, for a tile of about 30,000. That layout keeps to the run's memory
    // budget (it ran unbounded) and is refused at the dense layer's line.
    let case = Case::new(
        "local forest = pge.Forest{ size = {3000, 3000}, seed = 7, tile = 250,\n\
           lod = { camera = {0, 2, 0}, total = 1000, near = 10, far = 500 } }\n\
         forest:scatter{ species = \"stick.lua\", minDistance = 1.2, variants = 1 }\n\
         return forest\n",
    );
    let o = case.run(&["--tile", "0,0", "--memory-limit", "64"]);
    limit(
        &o,
        "main.lua:3",
        &["the layout of about", "memory limit of 64 MiB exceeded"],
        &case.output(),
    );
}

/// A skeleton of 2000 nodes in one line: a tree model of it holds about 2 MiB of meshes.
const SKELETON: &str = "local s = pge.Skeleton()\n\
     local p = 0\n\
     for i = 1, 2000 do p = s:add(p, {math.sin(i) * 0.1, i * 0.01, 0}, 0) end\n";

#[test]
fn models_a_script_keeps_are_charged_to_its_memory_limit() {
    // 400 tree models kept in a table: about 800 MiB of meshes.
    let case = Case::new(&format!(
        "{SKELETON}local keep = {{}}\n\
         for i = 1, 400 do keep[i] = pge.tree{{ skeleton = s, mesh = {{ textureSize = 64 }} }} end\n\
         return keep[1]\n"
    ));
    let o = case.run(&["--memory-limit", "128"]);
    limit(
        &o,
        "main.lua:5",
        &[
            "the meshes and textures of a model",
            "memory limit of 128 MiB exceeded",
        ],
        &case.output(),
    );
    // Models that are dropped are given back.
    let case = Case::new(&format!(
        "{SKELETON}for i = 1, 100 do local t = pge.tree{{ skeleton = s, mesh = {{ textureSize = 64 }} }} end\n\
         return pge.tree{{ skeleton = s, mesh = {{ textureSize = 64 }} }}\n"
    ));
    let o = case.run(&["--memory-limit", "128"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // Models that share one tree's meshes and textures are charged them once.
    let case = Case::new(&format!(
        "{SKELETON}local t = pge.tree{{ skeleton = s, mesh = {{ textureSize = 64 }} }}\n\
         local keep = {{}}\n\
         for i = 1, 400 do\n\
           keep[i] = pge.model()\n\
           keep[i]:add(t)\n\
           keep[400 + i] = t:model()\n\
         end\n\
         return keep[1]\n"
    ));
    let o = case.run(&["--memory-limit", "128"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

/// A forest `size` metres square of trees of 18,000 vertices each (`tree.lua`, the
/// [`SKELETON`]'s tree), every 2 m or so.
fn tree_forest(size: u32) -> Case {
    let case = Case::new(&format!(
        "local forest = pge.Forest{{ size = {{{size}, {size}}}, seed = 7 }}\n\
         forest:scatter{{ species = \"tree.lua\", minDistance = 2, variants = 1 }}\n\
         return forest\n"
    ));
    std::fs::write(
        case.path().join("tree.lua"),
        format!("{SKELETON}return pge.tree{{ skeleton = s, mesh = {{ textureSize = 64 }} }}\n"),
    )
    .expect("species");
    case
}

/// `pge run main.lua -o out/forest.obj -q` plus `extra`.
fn run_obj(case: &Case, extra: &[&str]) -> Output {
    let mut args = vec!["run", "main.lua", "-o", "out/forest.obj", "-q"];
    args.extend_from_slice(extra);
    case.pge(&args)
}

#[test]
fn an_export_stops_at_the_time_limit() {
    // 1839 trees of 18,000 vertices each written out one by one as .obj text: 33 million
    // vertices, minutes of export; the layout and the one variant take milliseconds.
    let case = tree_forest(100);
    let o = run_obj(&case, &["--time-limit", "1"]);
    limit(
        &o,
        "main.lua:3",
        &[TIME],
        &case.path().join("out/forest.obj"),
    );
    let left: Vec<_> = std::fs::read_dir(case.path().join("out"))
        .expect("out")
        .collect();
    assert!(left.is_empty(), "nothing written: {left:?}");
}

#[test]
fn an_obj_text_past_the_memory_limit_stops_the_export() {
    // About 75 trees of 18,000 vertices written out as .obj text: over 100 MiB of text,
    // held whole until it is written; the model itself is a few MiB.
    let case = tree_forest(20);
    let o = run_obj(&case, &["--memory-limit", "64"]);
    limit(
        &o,
        "main.lua:3",
        &["the .obj text (past", "memory limit of 64 MiB exceeded"],
        &case.path().join("out/forest.obj"),
    );
    // The same forest as a glb (instanced) fits.
    let o = case.run(&["--memory-limit", "64"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

#[test]
fn images_a_script_keeps_are_charged_to_its_memory_limit() {
    // 400 copies of a 4 MiB image kept: 1.6 GiB of pixels.
    let keep = |body: &str| {
        Case::new(&format!(
            "local img = pge.Image.new(1024, 1024)\n\
             local keep = {{}}\n\
             for i = 1, 400 do {body} end\n\
             {STICK}"
        ))
    };
    let case = keep("keep[i] = img:clone()");
    let o = case.run(&["--memory-limit", "128"]);
    limit(
        &o,
        "main.lua:3",
        &[
            "image:clone() holds 4 MiB",
            "memory limit of 128 MiB exceeded",
        ],
        &case.output(),
    );
    // Textures made of an image: a 256 x 256 image of noise, about 256 KiB as PNG, 400
    // times (the pixels are charged once, the textures each).
    let textures = |body: &str| {
        Case::new(&format!(
            "local img = pge.Image.new(256, 256)\n\
             for y = 0, 255 do for x = 0, 255 do img:set(x, y, {{math.random(), math.random(), math.random(), 1}}) end end\n\
             local keep = {{}}\n\
             for i = 1, 400 do {body} end\n\
             {STICK}"
        ))
    };
    let case = textures("keep[i] = img:texture()");
    let o = case.run(&["--memory-limit", "64"]);
    limit(
        &o,
        "main.lua:4",
        &["a texture (", "memory limit of 64 MiB exceeded"],
        &case.output(),
    );
    let case = textures("local t = img:texture()");
    let o = case.run(&["--memory-limit", "64"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // Copies that are dropped are given back.
    let case = keep("local copy = img:clone()");
    let o = case.run(&["--memory-limit", "128"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}
