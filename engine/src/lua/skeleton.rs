//! `pge.Skeleton`: the branch graph every tree generator produces, as a Lua value.
//!
//! `handle:skeleton()` on a space colonization, a growth or an L-system's algorithm, and
//! `turtle:skeleton()`, return one; `pge.SpaceColonization{start = s}` and
//! `pge.Growth{start = s}` grow on from it, and `pge.tree{skeleton = s}` meshes it. Nodes are
//! 1-based in Lua; a root's parent is 0.

use mlua::{Lua, Table, UserData, UserDataMethods, Value};

use super::errors::script_error;
use super::math::LuaVec3;
use crate::geometry::{Model, Skeleton};

/// How far from the origin a skeleton node may be placed, in metres (10 000 km).
const SKELETON_REACH: f32 = 1e7;

/// A skeleton in Lua.
#[derive(Clone, Debug, Default)]
pub struct LuaSkeleton {
    /// The skeleton.
    pub skeleton: Skeleton,
    /// Fork depths, computed on first use and dropped when a node is added.
    depths: Option<Vec<u32>>,
}

impl LuaSkeleton {
    /// Wraps a skeleton.
    #[must_use]
    pub fn new(skeleton: Skeleton) -> LuaSkeleton {
        LuaSkeleton {
            skeleton,
            depths: None,
        }
    }

    /// The skeleton as a Lua value, its buffers charged to the run's memory budget for as
    /// long as the script keeps it ([`super::charge`]).
    pub fn into_lua_charged(self, lua: &Lua) -> mlua::Result<mlua::AnyUserData> {
        let bytes = self.skeleton.heap_bytes();
        let value = lua.create_userdata(self)?;
        super::charge(lua, &value, bytes, "pge.Skeleton")?;
        Ok(value)
    }
}

/// The skeleton a script value holds, if it is a `pge.Skeleton`.
#[must_use]
pub fn skeleton_from_value(value: &Value) -> Option<Skeleton> {
    match value {
        Value::UserData(ud) => ud.borrow::<LuaSkeleton>().ok().map(|s| s.skeleton.clone()),
        _ => None,
    }
}

/// The skeletons carried by a model's bark meshes, joined into one (each placed by its
/// instances' transforms), or `None` when no mesh carries one.
#[must_use]
pub fn skeleton_of_model(model: &Model) -> Option<Skeleton> {
    let mut joined: Option<Skeleton> = None;
    for instance in &model.instances {
        if let Some(s) = &model.meshes[instance.mesh].skeleton {
            joined
                .get_or_insert_with(Skeleton::new)
                .append(s, &instance.transform);
        }
    }
    joined
}

/// A 1-based node index from Lua, checked against the node count; `what` names the method.
fn index(lua: &Lua, s: &Skeleton, v: &Value, what: &str) -> mlua::Result<usize> {
    let n = s.len();
    let bad = |got: String| {
        let range = if n == 0 {
            "the skeleton has no node".to_string()
        } else {
            format!("a node index between 1 and {n}")
        };
        script_error(lua, format!("{what}: expected {range}, got {got}"))
    };
    let i = match v {
        Value::Integer(i) => *i,
        Value::Number(x) if x.fract() == 0.0 && x.abs() < 1e15 => *x as i64,
        Value::Number(x) => return Err(bad(x.to_string())),
        other => return Err(bad(other.type_name().to_string())),
    };
    if i < 1 || i as usize > n {
        return Err(bad(i.to_string()));
    }
    Ok(i as usize - 1)
}

impl UserData for LuaSkeleton {
    fn add_methods<M: UserDataMethods<Self>>(m: &mut M) {
        m.add_method("count", |_, me, ()| Ok(me.skeleton.len()));
        m.add_method("position", |lua, me, i: Value| {
            let i = index(lua, &me.skeleton, &i, "skeleton:position(i)")?;
            Ok(LuaVec3(me.skeleton.positions[i]))
        });
        m.add_method("parent", |lua, me, i: Value| {
            let i = index(lua, &me.skeleton, &i, "skeleton:parent(i)")?;
            Ok(me.skeleton.parents[i].map_or(0, |p| p as usize + 1))
        });
        m.add_method("radius", |lua, me, i: Value| {
            let i = index(lua, &me.skeleton, &i, "skeleton:radius(i)")?;
            Ok(me.skeleton.radii[i])
        });
        m.add_method("order", |lua, me, i: Value| {
            let i = index(lua, &me.skeleton, &i, "skeleton:order(i)")?;
            Ok(me.skeleton.orders[i])
        });
        m.add_method_mut("depth", |lua, me, i: Value| {
            let i = index(lua, &me.skeleton, &i, "skeleton:depth(i)")?;
            let skeleton = &me.skeleton;
            let depths = me.depths.get_or_insert_with(|| skeleton.fork_depths());
            Ok(depths[i])
        });
        m.add_method("tips", |lua, me, ()| {
            let t = lua.create_table()?;
            for (k, tip) in me.skeleton.tips().iter().enumerate() {
                t.raw_set(k + 1, *tip as usize + 1)?;
            }
            Ok(t)
        });
        m.add_method("children", |lua, me, i: Value| {
            let i = index(lua, &me.skeleton, &i, "skeleton:children(i)")?;
            let t = lua.create_table()?;
            let mut k = 1;
            for (c, p) in me.skeleton.parents.iter().enumerate().skip(i + 1) {
                if *p == Some(i as u32) {
                    t.raw_set(k, c + 1)?;
                    k += 1;
                }
            }
            Ok(t)
        });
        m.add_method_mut(
            "add",
            |lua, me, (parent, position, radius): (Value, Value, Option<Value>)| {
                let w = "skeleton:add(parent, position [, radius])";
                let parent = match parent {
                    Value::Integer(0) => None,
                    Value::Number(0.0) => None,
                    v => Some(index(lua, &me.skeleton, &v, w)? as u32),
                };
                let LuaVec3(p) = mlua::FromLua::from_lua(position, lua).map_err(|e| {
                    script_error(
                        lua,
                        format!("{w}: position must be a vector {{x, y, z}}: {e}"),
                    )
                })?;
                // Far enough for any world; farther, the mesh's lengths and texture
                // coordinates would overflow.
                if !p.is_finite() || p.abs().max_element() > SKELETON_REACH {
                    return Err(script_error(
                        lua,
                        format!(
                            "{w}: position must lie within {SKELETON_REACH:e} m of the origin, \
                             got {{{:?}, {:?}, {:?}}}",
                            p.x, p.y, p.z
                        ),
                    ));
                }
                let r = match radius {
                    None | Some(Value::Nil) => 0.0,
                    Some(v) => {
                        let r = super::finite_number(lua, &v, w)?;
                        if r < 0.0 {
                            return Err(script_error(
                                lua,
                                format!("{w}: radius must be a number >= 0, got {r}"),
                            ));
                        }
                        r as f32
                    }
                };
                let order = parent.map_or(0, |q| me.skeleton.orders[q as usize]);
                let i = me.skeleton.push(p, parent, r, order);
                me.depths = None;
                Ok(i as usize + 1)
            },
        );
        m.add_method("copy", |lua, me, ()| {
            LuaSkeleton::new(me.skeleton.clone()).into_lua_charged(lua)
        });
        m.add_method("leafCount", |_, me, ()| Ok(me.skeleton.leaves.len()));
    }
}

/// Registers `pge.Skeleton` (callable: `pge.Skeleton()` is an empty skeleton, as is
/// `pge.Skeleton.new()`).
pub(crate) fn register(lua: &Lua, pge: &Table) -> mlua::Result<()> {
    let class = lua.create_table()?;
    class.set(
        "new",
        lua.create_function(|_, ()| Ok(LuaSkeleton::default()))?,
    )?;
    let meta = lua.create_table()?;
    meta.set(
        "__call",
        lua.create_function(|_, _: Value| Ok(LuaSkeleton::default()))?,
    )?;
    class.set_metatable(Some(meta))?;
    pge.set("Skeleton", class)
}
