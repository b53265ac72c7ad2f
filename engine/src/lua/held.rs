//! The buffers a script keeps on the Rust side through its models and meshes: their meshes'
//! vertex arrays, their textures and the skeletons their meshes carry. Values share them
//! (`mesh:model()` shares the mesh, a tree's texture set comes from the process's texture
//! cache, `model:add` shares the other model's meshes), so each buffer is charged to the
//! run's memory budget once, however many values hold it, for as long as it lives.

use std::collections::{HashMap, HashSet};
use std::sync::{Arc, Weak};

use mlua::Lua;

use super::errors::caller_location;
use crate::Charge;
use crate::geometry::{Mesh, Model, Skeleton, Texture};

/// A charged buffer, known by a weak reference: its charge is given back once nothing holds
/// it any more (found when the list is swept).
enum Buffer {
    Mesh(Weak<Mesh>),
    Texture(Weak<Texture>),
    Skeleton(Weak<Skeleton>),
}

impl Buffer {
    fn alive(&self) -> bool {
        match self {
            Buffer::Mesh(w) => w.strong_count() > 0,
            Buffer::Texture(w) => w.strong_count() > 0,
            Buffer::Skeleton(w) => w.strong_count() > 0,
        }
    }
}

/// The buffers a Lua state's values hold, charged, by address (the state's app data, so
/// the charges are given back with the state).
#[derive(Default)]
pub(crate) struct HeldBuffers {
    charged: HashMap<usize, (Buffer, Charge)>,
    /// How many were listed after the last sweep: the next sweep waits for twice as many,
    /// so sweeping costs a constant per buffer charged.
    swept: usize,
}

impl HeldBuffers {
    fn holds(&self, key: usize) -> bool {
        self.charged.get(&key).is_some_and(|(b, _)| b.alive())
    }

    /// Gives back the charges of the buffers nothing holds any more.
    fn sweep(&mut self) {
        self.charged.retain(|_, (b, _)| b.alive());
        self.swept = self.charged.len();
    }
}

/// A buffer not charged yet.
struct Uncharged {
    key: usize,
    buffer: Buffer,
    bytes: usize,
}

fn key<T>(arc: &Arc<T>) -> usize {
    Arc::as_ptr(arc) as usize
}

/// The buffers of a model that `held` does not charge yet, each once.
struct List<'a> {
    held: Option<&'a HeldBuffers>,
    seen: HashSet<usize>,
    out: Vec<Uncharged>,
}

impl List<'_> {
    fn add(&mut self, key: usize, bytes: usize, buffer: impl FnOnce() -> Buffer) {
        if bytes > 0 && !self.held.is_some_and(|h| h.holds(key)) && self.seen.insert(key) {
            self.out.push(Uncharged {
                key,
                buffer: buffer(),
                bytes,
            });
        }
    }

    fn texture(&mut self, t: &Arc<Texture>) {
        self.add(key(t), t.heap_bytes(), || {
            Buffer::Texture(Arc::downgrade(t))
        });
    }
}

fn uncharged(
    meshes: &[Arc<Mesh>],
    environment: Option<&Arc<Texture>>,
    held: Option<&HeldBuffers>,
) -> Vec<Uncharged> {
    let mut list = List {
        held,
        seen: HashSet::new(),
        out: Vec::new(),
    };
    for mesh in meshes {
        list.add(key(mesh), mesh.heap_bytes(), || {
            Buffer::Mesh(Arc::downgrade(mesh))
        });
        let m = &mesh.material;
        for t in [&m.texture, &m.normal_texture, &m.metallic_roughness_texture]
            .into_iter()
            .flatten()
        {
            list.texture(t);
        }
        if let Some(s) = &mesh.skeleton {
            list.add(key(s), s.heap_bytes(), || {
                Buffer::Skeleton(Arc::downgrade(s))
            });
        }
    }
    if let Some(t) = environment {
        list.texture(t);
    }
    list.out
}

/// Charges the buffers of `model` (a value the script now holds) that no value of this Lua
/// state holds yet. When the budget is short, Lua's garbage is collected first (values
/// nothing uses may still hold buffers); then an [`crate::Error::MemoryLimit`] at the
/// calling line.
pub(crate) fn charge_model(lua: &Lua, model: &Model) -> mlua::Result<()> {
    charge(
        lua,
        &model.meshes,
        model.environment.as_ref(),
        "the meshes and textures of a model",
    )
}

/// Charges the buffers of `mesh` (a value the script now holds), as [`charge_model`] does.
pub(crate) fn charge_mesh(lua: &Lua, mesh: &Arc<Mesh>) -> mlua::Result<()> {
    charge(
        lua,
        std::slice::from_ref(mesh),
        None,
        "the meshes and textures of a mesh",
    )
}

/// Charges the bytes of `texture` (a value the script now holds), as [`charge_model`] does.
pub(crate) fn charge_texture(lua: &Lua, texture: &Arc<Texture>) -> mlua::Result<()> {
    charge(lua, &[], Some(texture), "a texture")
}

/// `what` names what is charged in the error ("the meshes and textures of a model").
fn charge(
    lua: &Lua,
    meshes: &[Arc<Mesh>],
    environment: Option<&Arc<Texture>>,
    what: &str,
) -> mlua::Result<()> {
    let list = uncharged(
        meshes,
        environment,
        lua.app_data_ref::<HeldBuffers>().as_deref(),
    );
    let total: usize = list.iter().map(|u| u.bytes).sum();
    if total == 0 {
        return Ok(());
    }
    let budget = super::run_context(lua).budget;
    let attempt = || {
        super::sync_lua_memory(lua);
        budget.charge(total, &caller_location(lua), || {
            format!("{what} ({} MiB)", total.div_ceil(1 << 20))
        })
    };
    let mut charge = match attempt() {
        Ok(c) => c,
        Err(_) => {
            lua.gc_collect()?;
            lua.gc_collect()?;
            if let Some(mut held) = lua.app_data_mut::<HeldBuffers>() {
                held.sweep();
            }
            attempt().map_err(mlua::Error::external)?
        }
    };
    if lua.app_data_ref::<HeldBuffers>().is_none() {
        lua.set_app_data(HeldBuffers::default());
    }
    let Some(mut held) = lua.app_data_mut::<HeldBuffers>() else {
        return Ok(());
    };
    for u in list {
        let part = charge.split(u.bytes);
        held.charged.insert(u.key, (u.buffer, part));
    }
    if held.charged.len() > (2 * held.swept).max(64) {
        held.sweep();
    }
    Ok(())
}

/// How many buffers this Lua state's values hold charged, and their bytes (for tests).
#[cfg(test)]
pub(crate) fn held(lua: &Lua) -> (usize, usize) {
    lua.app_data_mut::<HeldBuffers>().map_or((0, 0), |mut h| {
        h.sweep();
        (
            h.charged.len(),
            h.charged.values().map(|(_, c)| c.bytes()).sum(),
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Material;
    use crate::lua::LuaModel;
    use crate::{Budget, Engine, Error, SessionOptions};
    use mlua::IntoLua;

    fn texture(bytes: usize) -> Arc<Texture> {
        Arc::new(Texture {
            name: "bark".into(),
            width: 1,
            height: 1,
            encoded: vec![7; bytes],
        })
    }

    /// A one-triangle model whose material has `tex`.
    fn model(tex: &Arc<Texture>) -> Model {
        let mut mesh = Mesh::from_triangles(
            vec![glam::Vec3::ZERO, glam::Vec3::X, glam::Vec3::Y],
            vec![0, 1, 2],
        )
        .expect("mesh");
        mesh.material = Arc::new(Material {
            texture: Some(tex.clone()),
            ..Material::default()
        });
        Model::from_mesh(mesh)
    }

    #[test]
    fn a_texture_shared_by_models_is_charged_once_while_it_lives() {
        let engine = Engine::builder().build().expect("engine");
        let budget = Budget::new(64 << 20);
        let session = engine
            .session(SessionOptions {
                budget: Some(budget.clone()),
                ..SessionOptions::default()
            })
            .expect("session");
        let lua = session.lua();
        let set = texture(4 << 20);
        let keep = lua.create_table().expect("table");
        // Ten models of one texture set (a tree's, from the texture cache): one charge.
        for i in 1..=10 {
            let value = LuaModel(model(&set)).into_lua(lua).expect("charged");
            keep.raw_set(i, value).expect("kept");
        }
        let (count, bytes) = held(lua);
        assert_eq!(count, 11, "ten meshes and one texture");
        assert!((4 << 20..5 << 20).contains(&bytes), "{bytes}");
        // Distinct sets are charged each, up to the budget.
        let err = (11..=30)
            .map(|i| {
                let value = LuaModel(model(&texture(4 << 20))).into_lua(lua)?;
                keep.raw_set(i, value)
            })
            .find_map(Result::err)
            .expect("past the budget");
        let err = crate::lua::engine_error_of(&err).expect("typed");
        assert!(matches!(err, Error::MemoryLimit { .. }), "{err:?}");
        assert!(held(lua).1 > 48 << 20);
        // Values that are collected give their buffers back, except what still lives
        // elsewhere (the cache's set).
        drop(keep);
        lua.gc_collect().expect("gc");
        lua.gc_collect().expect("gc");
        assert_eq!(held(lua), (1, 4 << 20));
        drop(set);
        assert_eq!(held(lua), (0, 0));
    }

    #[test]
    fn a_mesh_past_the_budget_is_named_a_mesh() {
        let engine = Engine::builder().build().expect("engine");
        let session = engine
            .session(SessionOptions {
                budget: Some(Budget::new(1 << 20)),
                ..SessionOptions::default()
            })
            .expect("session");
        let lua = session.lua();
        let big = texture(2 << 20);
        let mesh = model(&big).meshes[0].clone();
        let err = crate::lua::LuaMesh(mesh)
            .into_lua(lua)
            .expect_err("past the budget");
        let err = crate::lua::engine_error_of(&err).expect("typed");
        assert!(matches!(err, Error::MemoryLimit { .. }), "{err:?}");
        assert!(
            err.to_string()
                .contains("the meshes and textures of a mesh ("),
            "{err}"
        );
        let err = LuaModel(model(&big))
            .into_lua(lua)
            .expect_err("past the budget");
        let err = crate::lua::engine_error_of(&err).expect("typed");
        assert!(
            err.to_string()
                .contains("the meshes and textures of a model ("),
            "{err}"
        );
    }
}
