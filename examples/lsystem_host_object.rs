//! A host application hands its own modeller to an L-system script, as the PGE thesis'
//! wrappers do: the host's `Scaffold` (a builder of beams, with a cursor it moves and turns)
//! becomes the L-system's instance (`createInstance` returns `pge.scaffold()`), the script's
//! interpretation rules (IRules) drive it, and the rewriting rules (RRules) may only read it:
//! its mutating methods call [`pge_engine::lua::check_mutable`], so a rule that tried to build
//! during derivation would fail with an error naming the rule.
//!
//! ```text
//! cargo run --example lsystem_host_object
//! ```

use glam::{Mat3, Vec3};
use mlua::{Lua, Table, UserData, UserDataMethods};
use pge_engine::geometry::{Material, Mesh, Model};
use pge_engine::lua::LuaModel;
use pge_engine::{Plugin, SessionOptions};

/// The host's modeller: beams from a cursor that moves, turns and can be saved and restored.
#[derive(Default)]
struct Scaffold {
    position: Vec3,
    /// The cursor's orientation (its Y axis is the direction of the next beam).
    frame: Mat3,
    stack: Vec<(Vec3, Mat3)>,
    beams: Vec<(Vec3, Vec3, f32)>,
}

impl Scaffold {
    fn new() -> Scaffold {
        Scaffold {
            frame: Mat3::IDENTITY,
            ..Scaffold::default()
        }
    }

    /// A square beam of `thickness` from the cursor, `length` along its direction.
    fn beam(&mut self, length: f32, thickness: f32) {
        let end = self.position + self.frame.y_axis * length;
        self.beams.push((self.position, end, thickness));
        self.position = end;
    }

    /// The beams as one mesh: a box per beam.
    fn mesh(&self) -> Mesh {
        let mut positions = Vec::new();
        let mut indices = Vec::new();
        for (a, b, t) in &self.beams {
            let dir = (*b - *a).normalize_or_zero();
            let side = dir.any_orthonormal_vector() * (t / 2.0);
            let other = dir.cross(side);
            let base = positions.len() as u32;
            for end in [a, b] {
                for (s, o) in [(1.0, 1.0), (-1.0, 1.0), (-1.0, -1.0), (1.0, -1.0)] {
                    positions.push(*end + side * s + other * o);
                }
            }
            for k in 0..4u32 {
                let (i, j) = (k, (k + 1) % 4);
                indices.extend([
                    base + i,
                    base + j,
                    base + 4 + j,
                    base + i,
                    base + 4 + j,
                    base + 4 + i,
                ]);
            }
            indices.extend([base, base + 2, base + 1, base, base + 3, base + 2]);
            indices.extend([base + 4, base + 5, base + 6, base + 4, base + 6, base + 7]);
        }
        let mut mesh = Mesh::from_triangles(positions, indices).unwrap_or_default();
        mesh.compute_normals();
        if let Ok(m) = Material::from_hex("steel", "#8a9bb0") {
            mesh.material = m.into();
        }
        mesh
    }
}

impl UserData for Scaffold {
    fn add_methods<M: UserDataMethods<Self>>(m: &mut M) {
        m.add_method_mut("beam", |lua, s, (length, thickness): (f32, Option<f32>)| {
            pge_engine::lua::check_mutable(lua, "scaffold:beam")?;
            s.beam(length, thickness.unwrap_or(0.1));
            Ok(())
        });
        m.add_method_mut("turn", |lua, s, degrees: f32| {
            pge_engine::lua::check_mutable(lua, "scaffold:turn")?;
            s.frame *= Mat3::from_rotation_z(degrees.to_radians());
            Ok(())
        });
        m.add_method_mut("spin", |lua, s, degrees: f32| {
            pge_engine::lua::check_mutable(lua, "scaffold:spin")?;
            s.frame *= Mat3::from_rotation_y(degrees.to_radians());
            Ok(())
        });
        m.add_method_mut("save", |lua, s, ()| {
            pge_engine::lua::check_mutable(lua, "scaffold:save")?;
            s.stack.push((s.position, s.frame));
            Ok(())
        });
        m.add_method_mut("restore", |lua, s, ()| {
            pge_engine::lua::check_mutable(lua, "scaffold:restore")?;
            let (p, f) = s
                .stack
                .pop()
                .ok_or_else(|| mlua::Error::runtime("restore without save"))?;
            s.position = p;
            s.frame = f;
            Ok(())
        });
        m.add_method_mut("reset", |lua, s, ()| {
            pge_engine::lua::check_mutable(lua, "scaffold:reset")?;
            *s = Scaffold::new();
            Ok(())
        });
        // Reading is allowed during derivation: an open L-system can ask where it is.
        m.add_method("height", |_, s, ()| Ok(s.position.y));
        m.add_method("model", |_, s, ()| Ok(LuaModel(Model::from_mesh(s.mesh()))));
    }
}

/// The plugin that gives scripts `pge.scaffold()`.
struct ScaffoldPlugin;

impl Plugin for ScaffoldPlugin {
    fn name(&self) -> &str {
        "scaffold"
    }
    fn register(&self, lua: &Lua, pge: &Table) -> mlua::Result<()> {
        pge.set(
            "scaffold",
            lua.create_function(|_, ()| Ok(Scaffold::new()))?,
        )
    }
}

/// A tower of beams that branches into a crown and stops above a height it asks the host.
const SCRIPT: &str = r#"
local tower = pge.LSystem("tower")
tower:createInstance(function() return pge.scaffold() end)
tower:axiom{ Mast{ len = 2 } }
tower:RRule("Mast", function(m)
  if this:height() > 9 then return Tip{} end       -- reading the host object is allowed
  return { Beam{ m.len, 0.25 }, { Turn{ 35 }, Mast{ len = m.len * 0.7 } },
           Spin{ 120 }, { Turn{ -35 }, Mast{ len = m.len * 0.7 } },
           Spin{ 120 }, Mast{ len = m.len * 0.9 } }
end)
tower:IRule("Beam", function(b) this:beam(b[1], b[2]) return true end)
tower:IRule("Turn", function(t) this:turn(t[1]) return true end)
tower:IRule("Spin", function(t) this:spin(t[1]) return true end)
tower:IRule("[", function() this:save() return true end)
tower:IRule("]", function() this:restore() return true end)
tower:iterations(8)
return tower
"#;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let engine = pge::default_engine().plugin(ScaffoldPlugin).build()?;
    let session = engine.session(SessionOptions::default())?;
    let value = session.eval_value(SCRIPT)?;
    let mut algorithm = session.algorithm_from(value)?;
    let model = pge_engine::algorithm::run(&mut *algorithm, &session.context(), &mut |_| {})?;
    model.validate()?;
    println!(
        "the script drove the host's scaffold: {} modules, {} triangles",
        model.stats.modules,
        model.triangle_count()
    );
    let glb = pge_engine::export::glb_bytes(&model, &Default::default())?;
    std::fs::write("lsystem_host_object.glb", glb)?;
    println!("wrote lsystem_host_object.glb");
    Ok(())
}
