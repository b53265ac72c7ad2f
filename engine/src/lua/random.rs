//! Randomness: `pge.seed`, `pge.random`, `pge.rng` (MT19937), and a deterministic
//! `math.random`.

use mlua::{Lua, Table, UserData, UserDataMethods, Value};
use rand_mt::Mt;

use super::errors::script_error;
use super::state::SessionState;
use crate::random::{int_in, mt_from_seed, normal, uniform};

/// The generator `pge.random()` and `math.random()` draw from: made from the run's seed at
/// the first draw (seeding an MT19937 costs a session a few microseconds, and most scripts
/// never draw).
pub(crate) struct CurrentRng {
    seed: u64,
    rng: Option<Mt>,
}

impl CurrentRng {
    /// The generator of `seed`, made when first drawn from.
    pub fn from_seed(seed: u64) -> CurrentRng {
        CurrentRng { seed, rng: None }
    }

    fn get(&mut self) -> &mut Mt {
        let seed = self.seed;
        self.rng.get_or_insert_with(|| mt_from_seed(seed))
    }
}

/// Replaces the generator `pge.random()` draws from and returns the previous one. An
/// L-system swaps its instance's generator in around its rule calls.
pub fn swap_rng(lua: &Lua, rng: Mt) -> Mt {
    match lua.app_data_mut::<CurrentRng>() {
        Some(mut cur) => std::mem::replace(cur.get(), rng),
        None => {
            lua.set_app_data(CurrentRng {
                seed: 0,
                rng: Some(rng),
            });
            Mt::new(5489)
        }
    }
}

/// A uniform number in [0, 1) from the generator `pge.random()` draws from (inside an
/// L-system's rules: that instance's generator). Scripts cannot replace it: redefining
/// `pge.random` changes only what the script itself calls.
#[inline]
pub fn current_uniform(lua: &Lua) -> f64 {
    draw(lua, uniform)
}

fn draw<R>(lua: &Lua, f: impl FnOnce(&mut Mt) -> R) -> R {
    match lua.app_data_mut::<CurrentRng>() {
        Some(mut cur) => f(cur.get()),
        None => f(&mut Mt::new(5489)),
    }
}

/// `pge.rng(seed)`: an independent Mersenne Twister.
pub struct LuaRng(pub Mt);

impl UserData for LuaRng {
    fn add_methods<M: UserDataMethods<Self>>(m: &mut M) {
        m.add_method_mut("uniform", |_, r, ()| Ok(uniform(&mut r.0)));
        m.add_method_mut("range", |_, r, (a, b): (f64, f64)| {
            Ok(a + (b - a) * uniform(&mut r.0))
        });
        m.add_method_mut("int", |lua, r, (a, b): (i64, i64)| {
            if a > b {
                return Err(script_error(
                    lua,
                    format!("rng:int({a}, {b}): the first bound exceeds the second"),
                ));
            }
            Ok(int_in(&mut r.0, a, b))
        });
        m.add_method_mut("normal", |_, r, (mu, sigma): (Option<f64>, Option<f64>)| {
            Ok(normal(&mut r.0, mu.unwrap_or(0.0), sigma.unwrap_or(1.0)))
        });
        m.add_method_mut("choice", |lua, r, t: Table| {
            let n = t.raw_len() as i64;
            if n == 0 {
                return Err(script_error(lua, "rng:choice: the array is empty"));
            }
            t.raw_get::<Value>(int_in(&mut r.0, 1, n))
        });
    }
}

pub(crate) fn register(lua: &Lua, pge: &Table) -> mlua::Result<()> {
    pge.set(
        "seed",
        lua.create_function(|lua, ()| {
            Ok(lua.app_data_ref::<SessionState>().map_or(1, |s| s.ctx.seed) as i64)
        })?,
    )?;
    pge.set(
        "random",
        lua.create_function(|lua, ()| Ok(draw(lua, uniform)))?,
    )?;
    pge.set(
        "rng",
        lua.create_function(|lua, seed: Option<Value>| {
            let seed = match seed {
                None | Some(Value::Nil) => {
                    lua.app_data_ref::<SessionState>().map_or(1, |s| s.ctx.seed)
                }
                Some(Value::Integer(i)) => i as u64,
                Some(Value::Number(n)) if n.is_finite() => n as i64 as u64,
                Some(other) => {
                    return Err(script_error(
                        lua,
                        format!(
                            "pge.rng: the seed must be a number, not {}",
                            other.type_name()
                        ),
                    ));
                }
            };
            Ok(LuaRng(mt_from_seed(seed)))
        })?,
    )?;
    // math.random as in Lua 5.4, but drawing from the run's generator so runs repeat.
    let math: Table = lua.globals().get("math")?;
    math.set(
        "random",
        lua.create_function(|lua, (m, n): (Option<i64>, Option<i64>)| {
            Ok(match (m, n) {
                (None, _) => Value::Number(draw(lua, uniform)),
                (Some(m), None) if m >= 1 => Value::Integer(draw(lua, |r| int_in(r, 1, m))),
                (Some(m), Some(n)) if m <= n => Value::Integer(draw(lua, |r| int_in(r, m, n))),
                _ => return Err(script_error(lua, "math.random: interval is empty")),
            })
        })?,
    )?;
    math.set(
        "randomseed",
        lua.create_function(|lua, seed: Option<i64>| {
            swap_rng(lua, mt_from_seed(seed.unwrap_or(0) as u64));
            Ok(())
        })?,
    )?;
    Ok(())
}
