//! No script can take the host down: one test per row of the issue's table, each
//! running the `pge` command on a hostile script and checking that it fails cleanly (exit 1,
//! one `FILE:LINE: message` line naming the limit or the option, no panic, no output file)
//! or does the right thing.

mod common;

use std::path::PathBuf;
use std::process::Output;

use common::pge_in;

/// A folder holding `main.lua` with `source`, and the path of the output beside it.
struct Case {
    dir: tempfile::TempDir,
}

impl Case {
    fn new(source: &str) -> Case {
        let dir = tempfile::tempdir().expect("tempdir");
        std::fs::write(dir.path().join("main.lua"), source).expect("write the script");
        std::fs::create_dir(dir.path().join("out")).expect("the output folder");
        Case { dir }
    }

    fn path(&self, name: &str) -> PathBuf {
        self.dir.path().join(name)
    }

    /// `pge run main.lua -o out/model.glb -q` plus `extra`, in the case's folder.
    fn run(&self, extra: &[&str]) -> Output {
        let mut args = vec!["run", "main.lua", "-o", "out/model.glb", "-q"];
        args.extend_from_slice(extra);
        pge_in(&args, self.dir.path())
    }

    /// Runs and checks a script error: exit 1, one line starting with `main.lua:LINE:` and
    /// holding every needle, no panic and no model written. Returns the line.
    fn fails_at(&self, line: u32, needles: &[&str]) -> String {
        self.fails_with(&[], line, needles)
    }

    fn fails_with(&self, extra: &[&str], line: u32, needles: &[&str]) -> String {
        let o = self.run(extra);
        let err = String::from_utf8_lossy(&o.stderr).to_string();
        assert_eq!(o.status.code(), Some(1), "exit code: {err}");
        assert!(!err.contains("panicked"), "a panic: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "one line: {err}");
        let at = format!("main.lua:{line}: ");
        assert!(err.starts_with(&at), "expected '{at}...', got: {err}");
        for needle in needles {
            assert!(err.contains(needle), "expected '{needle}' in: {err}");
        }
        assert!(!self.path("out/model.glb").exists(), "a model was written");
        err
    }

    /// Runs and checks success; returns stderr.
    fn succeeds(&self, extra: &[&str]) -> String {
        let o = self.run(extra);
        let err = String::from_utf8_lossy(&o.stderr).to_string();
        assert_eq!(o.status.code(), Some(0), "exit code: {err}");
        assert!(self.path("out/model.glb").is_file(), "no model: {err}");
        err
    }
}

/// An L-system whose only rule is `rule` (a Lua expression giving the rule's text).
fn lsystem_with_rule(rule: &str) -> String {
    format!(
        "local l = pge.LSystem()\nl:axiom(\"A(1)\")\nl:rule({rule})\nl:iterations(2)\nreturn l\n"
    )
}

#[test]
fn nested_parentheses_in_a_classic_rule_are_a_located_error() {
    let case = Case::new(&lsystem_with_rule(
        r#""A(x) -> A(" .. string.rep("(", 10000) .. "x" .. string.rep(")", 10000) .. ")""#,
    ));
    case.fails_at(3, &["nested deeper than the limit of 100 levels"]);
    // A long flat chain nests as deep (each operator is a level of the tree).
    let case = Case::new(&lsystem_with_rule(
        r#""A(x) -> A(x" .. string.rep(" + 1", 10000) .. ")""#,
    ));
    case.fails_at(3, &["nested deeper than the limit of 100 levels"]);
    let case = Case::new(&lsystem_with_rule(
        r#""A(x) -> A(" .. string.rep("-", 10000) .. "x)""#,
    ));
    case.fails_at(3, &["nested deeper than the limit of 100 levels"]);
    // Nesting within the limit still works.
    let case = Case::new(&lsystem_with_rule(
        r#""A(x) -> A(" .. string.rep("(", 20) .. "x + 1" .. string.rep(")", 20) .. ")""#,
    ));
    case.succeeds(&[]);
}

#[test]
fn fifty_thousand_nested_shape_unions_are_a_located_error() {
    let case = Case::new(
        "local s = pge.shape.sphere{radius = 1}\n\
         for i = 1, 50000 do\n\
           s = pge.shape.union{s}\n\
         end\n\
         return pge.SpaceColonization{envelope = s}\n",
    );
    case.fails_at(3, &["pge.shape.union", "the limit of 64 levels"]);
    let case = Case::new(
        "local s = pge.shape.sphere{radius = 1}\n\
         for i = 1, 50000 do\n\
           s = pge.shape.difference{s, pge.shape.sphere{radius = 0.1}}\n\
         end\n",
    );
    case.fails_at(3, &["pge.shape.difference", "the limit of 64 levels"]);
    // A shared part counts once per use: 2^40 visits would hang every query.
    let case = Case::new(
        "local s = pge.shape.sphere{radius = 1}\n\
         for i = 1, 40 do\n\
           s = pge.shape.union{s, s}\n\
         end\n",
    );
    case.fails_at(3, &["the limit of 100000 parts"]);
}

#[test]
fn successor_arrays_nested_past_the_limit_are_a_located_error() {
    let case = Case::new(
        "local l = pge.LSystem()\n\
         l:axiom(\"A\")\n\
         l:RRule(\"A\", function()\n\
           local s = {\"B\"}\n\
           for i = 1, 100000 do s = {s} end\n\
           return s\n\
         end)\n\
         l:iterations(1)\n\
         return l\n",
    );
    case.fails_at(3, &["RRule 'A'", "the limit of 100 levels"]);
}

#[test]
fn a_script_that_sets_pge_random_to_its_own_function_keeps_rand_working() {
    // rand() in classic rules draws from the instance's generator, never from the script's
    // replacement, and the replacement is what the script's own calls get.
    let script = "pge.random = function() return 0.5 end\n\
                  local l = pge.LSystem()\n\
                  l:axiom(\"A(1)\")\n\
                  l:rule(\"A(x) -> A(x + rand()) B(rand())\")\n\
                  l:RRule(\"B\", function(b) return pge.sym(\"C\", {pge.random()}) end)\n\
                  l:iterations(3)\n\
                  return l\n";
    let case = Case::new(script);
    let o = pge_in(&["derive", "main.lua"], case.dir.path());
    let out = String::from_utf8_lossy(&o.stdout).to_string();
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert_eq!(o.status.code(), Some(0), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    assert!(
        out.contains("C(0.5)"),
        "the script's own calls use its function: {out}"
    );
    assert!(!out.contains("B(0.5)"), "rand() does not: {out}");
    case.succeeds(&[]);
}

#[test]
fn pge_random_raising_an_error_propagates_to_the_script_line() {
    let case = Case::new(
        "pge.random = function() error(\"no randomness here\") end\n\
         local l = pge.LSystem()\n\
         l:axiom(\"A(1)\")\n\
         l:RRule(\"A\", function(a)\n\
           return pge.sym(\"A\", {a[1] + pge.random()})\n\
         end)\n\
         l:iterations(2)\n\
         return l\n",
    );
    case.fails_at(1, &["no randomness here"]);
}

#[test]
fn math_random_over_the_whole_integer_range_is_uniform() {
    let case = Case::new(
        "local lo, hi, neg, pos = 0, 0, 0, 0\n\
         for i = 1, 400 do\n\
           local v = math.random(math.mininteger, math.maxinteger)\n\
           if v == math.mininteger then lo = lo + 1 end\n\
           if v < 0 then neg = neg + 1 else pos = pos + 1 end\n\
         end\n\
         assert(lo < 5, 'always mininteger: ' .. lo)\n\
         assert(neg > 100 and pos > 100, 'one-sided: ' .. neg .. ' ' .. pos)\n\
         local r = pge.rng(3)\n\
         local w = r:int(math.mininteger, math.maxinteger)\n\
         assert(w ~= math.mininteger, 'rng:int gives mininteger')\n\
         assert(math.random(-3, 3) >= -3)\n\
         local l = pge.LSystem()\n\
         l:axiom(\"F\")\n\
         return l\n",
    );
    case.succeeds(&[]);
}

#[test]
fn a_gc_finalizer_that_loops_forever_is_refused_before_it_can_hang() {
    let case = Case::new(
        "local t = {}\n\
         setmetatable(t, {__gc = function() while true do end end})\n\
         t = nil\n\
         collectgarbage()\n",
    );
    case.fails_with(
        &["--time-limit", "5"],
        2,
        &["__gc finalizers are not allowed"],
    );
    // A metatable without __gc is fine, and adding __gc later marks nothing (Lua's rule).
    let case = Case::new(
        "local mt = {}\n\
         local t = setmetatable({}, mt)\n\
         mt.__gc = function() while true do end end\n\
         t = nil\n\
         collectgarbage()\n\
         local l = pge.LSystem()\n\
         l:axiom(\"F\")\n\
         return l\n",
    );
    case.succeeds(&["--time-limit", "5"]);
}

#[test]
fn load_of_a_text_chunk_sees_the_globals_and_its_errors_name_the_script_line() {
    let case = Case::new(
        "local pi = load(\"return math.pi\")()\n\
         assert(pi == math.pi, 'load sees no globals')\n\
         assert(load(\"return x\", \"c\", \"t\", {x = 4})() == 4, 'env is used')\n\
         assert(load(\"\\27Lua\") == nil, 'binary chunks load')\n\
         local f = load(\"local x = nil\\nreturn x.y\")\n\
         f()\n",
    );
    case.fails_at(5, &["in load():2:", "attempt to index a nil value"]);
    let case = Case::new("local f, e = load(\"return +\")\nerror(e, 0)\n");
    case.fails_at(1, &["in load():1:"]);
}

#[test]
fn img_save_writes_only_png_files_inside_the_output_folder() {
    let keep = "local l = pge.LSystem()\nl:axiom(\"F\")\nreturn l\n";
    let case = Case::new(&format!("pge.Image.new(1, 1):save(\"notes.txt\")\n{keep}"));
    std::fs::write(case.path("notes.txt"), "precious").expect("write");
    case.fails_at(1, &["must end in .png"]);
    assert_eq!(
        std::fs::read_to_string(case.path("notes.txt")).expect("read"),
        "precious"
    );
    for (path, needle) in [("../x.png", "without '..'"), ("/tmp/x.png", "without '..'")] {
        let case = Case::new(&format!("pge.Image.new(1, 1):save(\"{path}\")\n{keep}"));
        case.fails_at(1, &[needle]);
    }
    // A link inside the output folder that leads out is refused.
    #[cfg(unix)]
    {
        let outside = tempfile::tempdir().expect("tempdir");
        let case = Case::new(&format!("pge.Image.new(1, 1):save(\"link/x.png\")\n{keep}"));
        std::os::unix::fs::symlink(outside.path(), case.path("out/link")).expect("link");
        case.fails_at(1, &["leads outside"]);
        assert!(!outside.path().join("x.png").exists());
    }
    // A dangling link planted at the target itself is refused, not followed to write the
    // file it names outside.
    #[cfg(unix)]
    {
        let outside = tempfile::tempdir().expect("tempdir");
        let case = Case::new(&format!("pge.Image.new(1, 1):save(\"x.png\")\n{keep}"));
        std::fs::create_dir_all(case.path("out")).expect("out");
        let planted = outside.path().join("planted.png");
        std::os::unix::fs::symlink(&planted, case.path("out/x.png")).expect("link");
        case.fails_at(1, &["leads outside", "symbolic link"]);
        assert!(
            !planted.exists(),
            "img:save followed a dangling link out of the folder"
        );
    }
    // A PNG goes beside the output, replacing what was there, and no temporary file stays.
    let case = Case::new(&format!("pge.Image.new(2, 2):save(\"maps/a.png\")\n{keep}"));
    std::fs::create_dir_all(case.path("out/maps")).expect("maps");
    std::fs::write(case.path("out/maps/a.png"), "old").expect("old file");
    case.succeeds(&[]);
    let png = std::fs::read(case.path("out/maps/a.png")).expect("the image beside the output");
    assert!(png.starts_with(b"\x89PNG"));
    assert!(!case.path("maps").exists());
    let names: Vec<_> = std::fs::read_dir(case.path("out/maps"))
        .expect("maps")
        .map(|e| e.expect("entry").file_name())
        .collect();
    assert_eq!(names, ["a.png"], "only the image is left in its folder");
}

fn usage_error(args: &[&str]) {
    let case = Case::new("local l = pge.LSystem()\nl:axiom(\"F\")\nreturn l\n");
    let o = pge_in(args, case.dir.path());
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
    assert!(!err.contains("panicked"), "{err}");
    let written = std::fs::read_dir(case.path("out")).expect("out").count();
    assert_eq!(written, 0, "{args:?} wrote something");
}

#[test]
fn memory_limit_zero_is_a_usage_error() {
    usage_error(&["run", "main.lua", "-o", "out/m.glb", "--memory-limit", "0"]);
    usage_error(&["derive", "main.lua", "--memory-limit", "0"]);
    usage_error(&["tiles", "main.lua", "--memory-limit", "0"]);
    usage_error(&["run", "main.lua", "-o", "out/m.glb", "--memory-limit", "-5"]);
}

#[test]
fn preview_usage_errors_exit_2_like_run() {
    for bad in [
        ["--time-limit", "-1"],
        ["--time-limit", "x"],
        ["--memory-limit", "0"],
    ] {
        usage_error(&["run", "main.lua", "-o", "out/m.glb", bad[0], bad[1]]);
        usage_error(&["derive", "main.lua", bad[0], bad[1]]);
        #[cfg(feature = "preview")]
        usage_error(&["preview", "main.lua", bad[0], bad[1]]);
    }
    // Impossible combinations found after parsing are usage errors too.
    usage_error(&["run", "main.lua", "-o", "out/m.png"]);
    usage_error(&["run", "main.lua", "-o", "out/m.obj", "--stages", "1,2"]);
    usage_error(&["run", "main.lua", "-o", "out/m.glb", "--threads", "0"]);
}

#[test]
fn a_glb_that_would_pass_the_limit_is_an_error_not_a_truncated_length() {
    use pge::pge_engine::export::{GLB_LIMIT, glb_container};
    let text = br#"{"asset":{"version":"2.0"}}    "#;
    let bin = vec![7u8; 64];
    let whole = glb_container(text, bin.clone(), GLB_LIMIT).expect("fits");
    assert_eq!(whole.len(), 12 + 8 + text.len() + 8 + bin.len());
    let total = u32::from_le_bytes([whole[8], whole[9], whole[10], whole[11]]);
    assert_eq!(total as usize, whole.len());
    // With a limit one byte short, an error naming the limit and no bytes.
    let limit = whole.len() as u64 - 1;
    let err = glb_container(text, bin.clone(), limit).expect_err("past the limit");
    let message = err.to_string();
    assert!(
        message.contains(&format!("limit of {limit} bytes")),
        "{message}"
    );
    assert!(glb_container(text, bin.clone(), whole.len() as u64).is_ok());
}

#[test]
fn marching_cubes_with_a_non_string_colour_names_the_option() {
    let case = Case::new(
        "local meta = pge.Metaballs{radius = 1}\n\
         meta:addParticle({0, 0, 0}, 1)\n\
         return pge.MarchingCubes(meta, {color = 5})\n",
    );
    case.fails_at(3, &["color"]);
}

#[test]
fn assigning_a_field_of_the_this_userdata_names_the_field() {
    let case = Case::new(
        "local l = pge.LSystem()\n\
         l:axiom(\"A\")\n\
         l:IRule(\"A\", function()\n\
           this.foo = 1\n\
           return true\n\
         end)\n\
         return l\n",
    );
    case.fails_at(4, &["foo"]);
}

// docs/lua-api.md says what the code does (three statements were contradicted by runs).

#[test]
fn successor_strings_with_rand_are_evaluated_every_time() {
    let case = Case::new(
        "local l = pge.LSystem()\n\
         l:axiom(\"A A A A A A A A\")\n\
         l:RRule(\"A\", function() return \"B(rand())\" end)\n\
         l:iterations(1)\n\
         return l\n",
    );
    let o = pge_in(&["derive", "main.lua"], case.dir.path());
    assert_eq!(o.status.code(), Some(0));
    let out = String::from_utf8_lossy(&o.stdout).to_string();
    let mut values: Vec<&str> = out.split("B(").skip(1).collect();
    assert_eq!(values.len(), 8, "{out}");
    values.sort_unstable();
    values.dedup();
    assert_eq!(values.len(), 8, "every B draws its own number: {out}");
}

#[test]
fn an_irule_condition_is_an_error_at_the_call() {
    let case = Case::new(
        "local l = pge.LSystem()\n\
         l:axiom(\"A(1)\")\n\
         l:IRule(\"A(x) : x > 2\", function() return true end)\n\
         return l\n",
    );
    case.fails_at(3, &["IRule", "condition"]);
}

#[test]
fn turtle_texture_paths_are_relative_to_the_script() {
    let case = Case::new("");
    let scripts = case.path("scripts");
    std::fs::create_dir_all(&scripts).expect("folder");
    image::RgbaImage::from_pixel(2, 2, image::Rgba([90, 60, 30, 255]))
        .save(scripts.join("bark.png"))
        .expect("png");
    std::fs::write(
        scripts.join("main.lua"),
        "local l = pge.LSystem()\n\
         l:axiom(\"F F\")\n\
         l:createInstance(function()\n\
           return pge.turtle{mesh = {texture = \"bark.png\"}}\n\
         end)\n\
         return l\n",
    )
    .expect("script");
    // Run from the case's folder: the texture is beside the script, not in the cwd.
    let o = pge_in(
        &["run", "scripts/main.lua", "-o", "out/model.glb", "-q"],
        case.dir.path(),
    );
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert_eq!(o.status.code(), Some(0), "{err}");
    let (doc, _, images) = gltf::import(case.path("out/model.glb")).expect("the glb reads");
    assert_eq!(doc.textures().count(), 1, "the bark texture is in the glb");
    assert_eq!(images[0].width, 2);
    // A texture that is only in the working directory is not found.
    std::fs::rename(scripts.join("bark.png"), case.path("bark.png")).expect("move");
    let o = pge_in(
        &["run", "scripts/main.lua", "-o", "out/model.glb", "-q"],
        case.dir.path(),
    );
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.starts_with("scripts/main.lua:4: "), "{err}");
    assert!(err.contains("mesh.texture"), "{err}");
}

// Found by the lua_api fuzz target: noise at coordinates past what the `noise` crate's lattice
// index holds (a huge frequency, lacunarity or coordinate) panicked inside the crate.
#[test]
fn noise_past_its_reach_is_a_located_error_not_a_panic() {
    let case = Case::new(
        "local a = pge.noise.fbm(1, 2, {frequency = 1e300})\n\
         return pge.Lines()\n",
    );
    case.fails_at(1, &["pge.noise.fbm", "frequency", "1e12"]);
    let case = Case::new("local a = pge.noise.fbm(3, 4, {octaves = 32, lacunarity = 1e30})\n");
    case.fails_at(1, &["pge.noise.fbm", "lacunarity"]);
    let case = Case::new("local a = pge.noise.perlin(1e300, 0)\n");
    case.fails_at(1, &["pge.noise.perlin", "1e12"]);
    let case = Case::new("local a = pge.noise.fbm(1, 2, {persistence = 0/0})\n");
    case.fails_at(1, &["persistence must be a finite number"]);
    // The forest's terrain: a tiny `scale` reaches as far.
    let case = Case::new(
        "local f = pge.Forest{size = {100, 100}, seed = 1}\n\
         f:terrain{height = 10, scale = 1e-300}\n\
         return f\n",
    );
    case.fails_at(2, &["forest:terrain", "scale", "1e12"]);
}
