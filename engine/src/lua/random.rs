//! Randomness: `pge.seed`, `pge.random`, `pge.rng` (MT19937), and a deterministic
//! `math.random`.

use mlua::{Lua, Table, UserData, UserDataMethods, Value};
use rand_mt::Mt;

use super::errors::script_error;
use super::state::SessionState;

/// The generator `pge.random()` and `math.random()` draw from.
pub(crate) struct CurrentRng(pub Mt);

/// A uniform number in [0, 1) with 53 random bits (MT19937's `genrand_res53`).
pub fn uniform(rng: &mut Mt) -> f64 {
    let a = (rng.next_u32() >> 5) as f64;
    let b = (rng.next_u32() >> 6) as f64;
    (a * 67_108_864.0 + b) / 9_007_199_254_740_992.0
}

/// An integer in `[a, b]` (inclusive).
fn int_in(rng: &mut Mt, a: i64, b: i64) -> i64 {
    let span = (b - a) as f64 + 1.0;
    (a + (uniform(rng) * span).floor() as i64).min(b)
}

fn normal(rng: &mut Mt, mu: f64, sigma: f64) -> f64 {
    let u1 = 1.0 - uniform(rng);
    let u2 = uniform(rng);
    mu + sigma * (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

/// The MT19937 of a seed (both halves of a 64-bit seed are used).
#[must_use]
pub(crate) fn mt_from_seed(seed: u64) -> Mt {
    Mt::new_with_key([seed as u32, (seed >> 32) as u32])
}

/// Replaces the generator `pge.random()` draws from and returns the previous one. An
/// L-system swaps its instance's generator in around its rule calls.
pub fn swap_rng(lua: &Lua, rng: Mt) -> Mt {
    match lua.app_data_mut::<CurrentRng>() {
        Some(mut cur) => std::mem::replace(&mut cur.0, rng),
        None => {
            lua.set_app_data(CurrentRng(rng));
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
        Some(mut cur) => f(&mut cur.0),
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_is_in_range_and_repeatable() {
        let mut a = mt_from_seed(7);
        let mut b = mt_from_seed(7);
        for _ in 0..1000 {
            let x = uniform(&mut a);
            assert!((0.0..1.0).contains(&x));
            assert_eq!(x, uniform(&mut b));
        }
    }

    #[test]
    fn int_is_inclusive() {
        let mut r = mt_from_seed(1);
        let mut seen = [false; 3];
        for _ in 0..200 {
            let v = int_in(&mut r, 1, 3);
            seen[(v - 1) as usize] = true;
        }
        assert_eq!(seen, [true; 3]);
    }
}
