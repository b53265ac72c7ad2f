//! Script options that must do what they say: an option that would do nothing is an error,
//! each growth option and the slope filter change what grows, and an option's error (a
//! layer's range, a density function's answer, a skeleton node) is located at its line.

mod common;

use common::{BUSH, one_line_error, script_fails};
use serde_json::Value;

#[test]
fn options_that_would_do_nothing_are_errors() {
    let scatter = |extra: &str| {
        format!(
            "local f = pge.Forest{{size = {{20, 20}}, seed = 1}}\n\
             f:scatter{{species = function() return {BUSH} end, minDistance = 4{extra}}}\n\
             return f\n"
        )
    };
    script_fails(
        &[("main.lua", &scatter(", jitter = 0.3"))],
        &[],
        "main.lua:2: ",
        &["jitter", "jittered"],
    );
    script_fails(
        &[("main.lua", &scatter(", method = \"poisson\", jitter = 0.3"))],
        &[],
        "main.lua:2: ",
        &["jitter"],
    );
    let dir = tempfile::tempdir().expect("tempdir");
    image::GrayImage::from_pixel(4, 4, image::Luma([128]))
        .save(dir.path().join("h.png"))
        .expect("png");
    for option in [
        "scale = 50",
        "octaves = 3",
        "lacunarity = 2",
        "persistence = 0.4",
    ] {
        let script = format!(
            "local f = pge.Forest{{size = {{20, 20}}, seed = 1}}\n\
             f:terrain{{image = \"h.png\", height = 5, {option}}}\n\
             return f\n"
        );
        std::fs::write(dir.path().join("main.lua"), script).expect("script");
        let o = common::pge_in(&["run", "main.lua", "-o", "out.glb", "-q"], dir.path());
        let name = option.split(' ').next().expect("name");
        let err = one_line_error(&o, &[name, "image"]);
        assert!(err.starts_with("main.lua:2: forest:terrain"), "{err}");
    }
    // Each alone is fine.
    let script = format!(
        "local f = pge.Forest{{size = {{20, 20}}, seed = 1}}\n\
         f:terrain{{image = \"h.png\", height = 5}}\n\
         f:scatter{{species = function() return {BUSH} end, minDistance = 4, \
         method = \"jittered\", jitter = 0.3}}\n\
         return f\n"
    );
    std::fs::write(dir.path().join("main.lua"), script).expect("script");
    let o = common::pge_in(&["run", "main.lua", "-o", "out.glb", "-q"], dir.path());
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

#[test]
fn a_density_function_s_wrong_answers_are_located_at_its_scatter() {
    for (body, line, needles) in [
        ("return true", 2, &["density", "returned a boolean"][..]),
        (
            "return 5",
            2,
            &["forest:scatter: density", "returned 5"][..],
        ),
        ("return 0/0", 2, &["forest:scatter: density", "NaN"][..]),
        (
            "error({})",
            2,
            &["an error raised with a table value, not a message"][..],
        ),
        ("error(\"no light\")", 4, &["no light"][..]),
    ] {
        let script = format!(
            "local f = pge.Forest{{size = {{20, 20}}, seed = 1}}\n\
             f:scatter{{species = function() return {BUSH} end, minDistance = 4,\n\
               density = function(x, z)\n\
                 {body}\n\
               end}}\n\
             return f\n"
        );
        let err = script_fails(
            &[("main.lua", &script)],
            &[],
            &format!("main.lua:{line}: "),
            needles,
        );
        assert!(!err.contains("0x"), "an address: {err}");
    }
}

#[test]
fn a_skeleton_node_out_of_reach_is_a_located_error() {
    let script = "local s = pge.Skeleton()\n\
                  local a = s:add(0, {0, 0, 0}, 0.1)\n\
                  local b = s:add(a, {0, 1e38, 0}, 0.05)\n\
                  return pge.tree{skeleton = s}\n";
    let err = script_fails(
        &[("main.lua", script)],
        &[],
        "main.lua:3: ",
        &["skeleton:add", "position must lie within 1e7 m", "1e38"],
    );
    assert!(!err.contains("uvs["), "{err}");
}

/// The skeleton (`extras.pge.skeleton`) of the bark mesh of the model `script` makes.
fn grown_skeleton(script: &str) -> Value {
    let dir = tempfile::tempdir().expect("tempdir");
    std::fs::write(dir.path().join("main.lua"), script).expect("script");
    let o = common::pge_in(&["run", "main.lua", "-o", "t.glb", "-q"], dir.path());
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let bytes = std::fs::read(dir.path().join("t.glb")).expect("glb");
    let glb = gltf::binary::Glb::from_slice(&bytes).expect("glb");
    let json: Value = serde_json::from_slice(&glb.json).expect("json");
    json["meshes"]
        .as_array()
        .expect("meshes")
        .iter()
        .find_map(|m| m.pointer("/extras/pge/skeleton").cloned())
        .expect("a skeleton")
}

#[test]
fn every_growth_option_changes_the_tree() {
    let growth = |option: &str| {
        grown_skeleton(&format!(
            "return pge.Growth{{seed = 3, steps = 40, {option}}}\n"
        ))
    };
    let plain = growth("");
    assert_eq!(plain, growth(""), "the same options grow the same tree");
    // Each at another value than its default grows another tree: an option that stopped
    // working would grow the plain one.
    for option in [
        "directedness = 0",
        "directedness = 1",
        "localdepth = 0",
        "localdepth = 8",
        "spread = 0",
        "spread = 1.5",
        "splitdecay = 0.5",
    ] {
        assert_ne!(plain, growth(option), "{option} changed nothing");
    }
    // A wider spread turns new branches further from their parent's line: the crown is wider.
    let width = |s: &Value| {
        // A flat list: x, y, z of each node.
        let flat: Vec<f64> = s["positions"]
            .as_array()
            .expect("positions")
            .iter()
            .map(|v| v.as_f64().expect("a number"))
            .collect();
        flat.chunks_exact(3)
            .map(|p| (p[0] * p[0] + p[2] * p[2]).sqrt())
            .fold(0.0, f64::max)
    };
    let (narrow, wide) = (width(&growth("spread = 0")), width(&growth("spread = 1.5")));
    assert!(wide > narrow, "spread 1.5: {wide} m, spread 0: {narrow} m");
}

#[test]
fn the_slope_filter_keeps_trees_off_steep_ground() {
    // Every tree of a layer with slope = {0, 10} stands where the ground is at most 10 degrees
    // steep, and there are fewer of them than without the filter.
    let dir = tempfile::tempdir().expect("tempdir");
    let script = format!(
        "local function forest(slope)\n\
           local f = pge.Forest{{size = {{60, 60}}, seed = 2}}\n\
           f:terrain{{height = 12, scale = 15, octaves = 2}}\n\
           f:scatter{{species = function() return {BUSH} end, minDistance = 2, slope = slope}}\n\
           return f\n\
         end\n\
         local filtered, all = forest({{0, 10}}):instances(), forest({{0, 90}}):instances()\n\
         local f = forest({{0, 10}})\n\
         for _, i in ipairs(filtered) do\n\
           local n = f:normal(i.position.x, i.position.z)\n\
           local degrees = math.deg(math.acos(n.y))\n\
           assert(degrees <= 10.01, 'a tree on a slope of ' .. degrees .. ' degrees')\n\
         end\n\
         assert(#filtered > 0 and #filtered < #all, #filtered .. ' of ' .. #all)\n\
         local l = pge.Lines()\n\
         return l\n"
    );
    std::fs::write(dir.path().join("main.lua"), script).expect("script");
    let o = common::pge_in(&["run", "main.lua", "-o", "t.glb", "-q"], dir.path());
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

#[test]
fn a_layer_option_out_of_range_is_located_at_its_scatter() {
    // The forest on line 1, the layer on line 3 (its options on line 4): every range error
    // of a layer's options names the layer's line, not the forest's.
    for (option, needles) in [
        (
            "density = 2",
            &["density must be a number between 0 and 1", "got 2"][..],
        ),
        ("scale = {2, 1}", &["scale must have min <= max"][..]),
        ("scale = {0, 1}", &["scale[1] must be a number > 0"][..]),
        (
            "variants = 0",
            &["variants must be an integer between 1 and 10000"][..],
        ),
        (
            "jitter = 5",
            &["jitter must be a number between 0 and 0.49"][..],
        ),
        ("slope = {1, 0}", &["slope must have min <= max"][..]),
        ("altitude = {5, 1}", &["altitude must have min <= max"][..]),
        (
            "minDistance = -1",
            &["minDistance must be a number > 0"][..],
        ),
    ] {
        let script = format!(
            "local f = pge.Forest{{size = {{20, 20}}, seed = 1}}\n\
             f:terrain{{height = 1}}\n\
             f:scatter{{species = function() return {BUSH} end, variants = 1,\n\
               minDistance = 4, {option}}}\n\
             return f\n"
        );
        let mut needles = needles.to_vec();
        needles.push("forest:scatter: ");
        script_fails(&[("main.lua", &script)], &[], "main.lua:3: ", &needles);
    }
}
