//! `pge.tree{ skeleton = s, mesh = {...}, leaves = {...} }`: any skeleton meshed with the
//! common bark and leaf options, so a trunk grown by one method and a crown by another
//! become one tree.

use mlua::{Lua, Table, Value};
use pge_engine::Plugin;
use pge_engine::lua::{LuaModel, Options, run_context, skeleton_from_value};
use pge_engine::random::mix_seed_multiply;

use crate::options::RadiiMode;
use crate::{build_tree, lua::tree_options};

/// Adds `pge.tree` to every session.
#[derive(Clone, Copy, Debug, Default)]
pub struct TreePlugin;

impl Plugin for TreePlugin {
    fn name(&self) -> &str {
        "tree"
    }

    fn lazy_names(&self) -> &'static [&'static str] {
        &["tree"]
    }

    fn register(&self, lua: &Lua, pge: &Table) -> mlua::Result<()> {
        pge.set("tree", lua.create_function(|lua, v: Value| tree(lua, v))?)
    }
}

/// Meshes the skeleton. Radii: the skeleton's own when every node has one (`mesh.radii =
/// "keep"`), the pipe model otherwise, unless `mesh.radii` says which.
fn tree(lua: &Lua, v: Value) -> mlua::Result<LuaModel> {
    let w = "pge.tree";
    let o = Options::new(lua, v, w)?;
    let skeleton = match o.value("skeleton")? {
        Value::Nil => return Err(o.missing("skeleton", "a pge.Skeleton")),
        v => skeleton_from_value(&v).ok_or_else(|| {
            o.wrong_type(
                "skeleton",
                "a skeleton (pge.Skeleton, e.g. from handle:skeleton())",
                &v,
            )
        })?,
    };
    let seed = o.integer("seed", 0..=i64::MAX)?.unwrap_or(0) as u64;
    let mut options = tree_options(&o)?;
    let radii_given = match o.value("mesh")? {
        Value::Table(m) => !m.get::<Value>("radii")?.is_nil(),
        _ => false,
    };
    o.finish()?;
    if !radii_given && !skeleton.is_empty() && skeleton.radii.iter().all(|r| *r > 0.0) {
        options.mesh.radii = RadiiMode::Keep;
    }
    let seed = mix_seed_multiply(run_context(lua).seed, seed);
    build_tree(&skeleton, &options, seed)
        .map(LuaModel)
        .map_err(|e| match e {
            crate::TreeError::Lod(pge_lod::LodError::Limit(limit)) => mlua::Error::external(*limit),
            other => o.error(other),
        })
}

#[cfg(test)]
mod tests {
    use pge_engine::{Engine, SessionOptions};

    fn eval(code: &str) -> pge_engine::Result<mlua::Value> {
        let engine = Engine::builder()
            .plugin(super::TreePlugin)
            .build()
            .expect("engine");
        let session = engine.session(SessionOptions::default()).expect("session");
        session.eval_value(code)
    }

    #[test]
    fn a_skeleton_built_in_lua_becomes_a_tree() {
        let code = r#"
            local s = pge.Skeleton()
            local r = s:add(0, {0, 0, 0})
            local f = s:add(r, {0, 2, 0})
            s:add(f, {-1, 3, 0})
            s:add(f, {1, 3, 0})
            assert(s:count() == 4 and #s:tips() == 2 and s:parent(1) == 0 and s:depth(4) == 1)
            local m = pge.tree{ skeleton = s, leaves = { perTip = 2 }, sides = 5 }
            return m:meshCount(), m:triangleCount()"#;
        let engine = Engine::builder()
            .plugin(super::TreePlugin)
            .build()
            .expect("engine");
        let session = engine.session(SessionOptions::default()).expect("session");
        let (meshes, triangles): (usize, usize) = session.eval(code).expect("meshes");
        assert_eq!(meshes, 2);
        assert!(triangles > 30, "{triangles}");
    }

    #[test]
    fn bad_input_names_the_option() {
        let e = eval("return pge.tree{ skeleton = 3 }").expect_err("not a skeleton");
        assert_eq!(
            e.to_string(),
            "eval:1: pge.tree: skeleton must be a skeleton (pge.Skeleton, e.g. from handle:skeleton()), got integer"
        );
        let e = eval("return pge.tree{}").expect_err("missing");
        assert_eq!(
            e.to_string(),
            "eval:1: pge.tree: skeleton is required (a pge.Skeleton)"
        );
        let e = eval("return pge.tree{ skeleton = pge.Skeleton(), bark = 1 }").expect_err("typo");
        assert!(e.to_string().contains("unknown option 'bark'"), "{e}");
        let e = eval("local s = pge.Skeleton() s:add(0, {0,0,0}) return s:position(2)")
            .expect_err("index");
        assert_eq!(
            e.to_string(),
            "eval:1: skeleton:position(i): expected a node index between 1 and 1, got 2"
        );
    }
}
