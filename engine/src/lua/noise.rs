//! `pge.noise`: Perlin, simplex and fBm noise (the `noise` crate), seeded by the run.

use mlua::{Lua, Table};
use noise::{Fbm, MultiFractal, NoiseFn, Perlin, Seedable, Simplex};

use super::errors::script_error;
use super::state::SessionState;

/// Generators kept between calls (building one shuffles a permutation table).
struct NoiseCache {
    perlin: Perlin,
    simplex: Simplex,
    fbm: Option<(FbmKey, Fbm<Perlin>)>,
}

#[derive(Clone, Copy, PartialEq)]
struct FbmKey {
    seed: u32,
    octaves: usize,
    frequency: f64,
    lacunarity: f64,
    persistence: f64,
}

fn run_seed(lua: &Lua) -> u32 {
    lua.app_data_ref::<SessionState>()
        .map_or(1, |s| s.ctx.seed as u32)
}

fn with_cache<R>(lua: &Lua, f: impl FnOnce(&mut NoiseCache) -> R) -> R {
    if lua.app_data_ref::<NoiseCache>().is_none() {
        let seed = run_seed(lua);
        lua.set_app_data(NoiseCache {
            perlin: Perlin::new(seed),
            simplex: Simplex::new(seed),
            fbm: None,
        });
    }
    match lua.app_data_mut::<NoiseCache>() {
        Some(mut c) => f(&mut c),
        None => {
            let seed = run_seed(lua);
            f(&mut NoiseCache {
                perlin: Perlin::new(seed),
                simplex: Simplex::new(seed),
                fbm: None,
            })
        }
    }
}

fn sample<N: NoiseFn<f64, 2> + NoiseFn<f64, 3>>(n: &N, x: f64, y: f64, z: Option<f64>) -> f64 {
    match z {
        Some(z) => n.get([x, y, z]),
        None => n.get([x, y]),
    }
}

/// The largest coordinate the noise generators take (after an fBm's frequency and
/// lacunarity): beyond it their lattice index no longer fits an integer (the `noise` crate
/// panics), and doubles have no fractional digits left anyway.
const REACH: f64 = 1e12;

fn check(lua: &Lua, what: &str, x: f64, y: f64, z: Option<f64>) -> mlua::Result<()> {
    let within = |c: f64| c.is_finite() && c.abs() <= REACH;
    if within(x) && within(y) && z.is_none_or(within) {
        Ok(())
    } else {
        Err(script_error(
            lua,
            format!("pge.noise.{what}: coordinates must be finite numbers within ±1e12"),
        ))
    }
}

/// Checks an fBm's options: finite, and the finest octave's coordinates within [`REACH`].
fn check_fbm(lua: &Lua, key: &FbmKey, x: f64, y: f64, z: Option<f64>) -> mlua::Result<()> {
    for (name, v) in [
        ("frequency", key.frequency),
        ("lacunarity", key.lacunarity),
        ("persistence", key.persistence),
    ] {
        if !v.is_finite() {
            return Err(script_error(
                lua,
                format!("pge.noise.fbm: {name} must be a finite number, got {v}"),
            ));
        }
    }
    let largest = x.abs().max(y.abs()).max(z.map_or(0.0, f64::abs));
    let finest = key.frequency.abs() * key.lacunarity.abs().max(1.0).powi(key.octaves as i32 - 1);
    let reach = largest * finest;
    if reach.is_finite() && reach <= REACH {
        Ok(())
    } else {
        Err(script_error(
            lua,
            format!(
                "pge.noise.fbm: the finest octave samples at {reach:e} (coordinates x frequency x \
                 lacunarity^(octaves-1)), beyond ±1e12: lower frequency, lacunarity or octaves"
            ),
        ))
    }
}

pub(crate) fn register(lua: &Lua, pge: &Table) -> mlua::Result<()> {
    let t = lua.create_table()?;
    t.set(
        "perlin",
        lua.create_function(|lua, (x, y, z): (f64, f64, Option<f64>)| {
            check(lua, "perlin", x, y, z)?;
            Ok(with_cache(lua, |c| sample(&c.perlin, x, y, z)))
        })?,
    )?;
    t.set(
        "simplex",
        lua.create_function(|lua, (x, y, z): (f64, f64, Option<f64>)| {
            check(lua, "simplex", x, y, z)?;
            Ok(with_cache(lua, |c| sample(&c.simplex, x, y, z)))
        })?,
    )?;
    t.set(
        "fbm",
        lua.create_function(|lua, args: mlua::Variadic<mlua::Value>| {
            let mut nums = Vec::new();
            let mut opts: Option<Table> = None;
            for a in args.iter() {
                match a {
                    mlua::Value::Integer(i) => nums.push(*i as f64),
                    mlua::Value::Number(n) => nums.push(*n),
                    mlua::Value::Table(o) => opts = Some(o.clone()),
                    other => {
                        return Err(script_error(
                            lua,
                            format!("pge.noise.fbm: unexpected {} argument", other.type_name()),
                        ));
                    }
                }
            }
            let (x, y, z) = match nums.as_slice() {
                [x, y] => (*x, *y, None),
                [x, y, z] => (*x, *y, Some(*z)),
                _ => {
                    return Err(script_error(
                        lua,
                        "pge.noise.fbm(x, y [, z] [, options]) takes 2 or 3 coordinates",
                    ));
                }
            };
            check(lua, "fbm", x, y, z)?;
            let get = |k: &str, d: f64| -> mlua::Result<f64> {
                Ok(opts
                    .as_ref()
                    .map(|o| o.get::<Option<f64>>(k))
                    .transpose()?
                    .flatten()
                    .unwrap_or(d))
            };
            let octaves = get("octaves", 6.0)?;
            if !(1.0..=32.0).contains(&octaves) {
                return Err(script_error(
                    lua,
                    format!("pge.noise.fbm: octaves = {octaves} must be in [1, 32]"),
                ));
            }
            let key = FbmKey {
                seed: get("seed", run_seed(lua) as f64)? as u32,
                octaves: octaves as usize,
                frequency: get("frequency", 1.0)?,
                lacunarity: get("lacunarity", 2.0)?,
                persistence: get("persistence", 0.5)?,
            };
            check_fbm(lua, &key, x, y, z)?;
            Ok(with_cache(lua, |c| {
                if c.fbm.as_ref().is_none_or(|(k, _)| *k != key) {
                    let f = Fbm::<Perlin>::new(key.seed)
                        .set_octaves(key.octaves)
                        .set_frequency(key.frequency)
                        .set_lacunarity(key.lacunarity)
                        .set_persistence(key.persistence)
                        .set_seed(key.seed);
                    c.fbm = Some((key, f));
                }
                c.fbm.as_ref().map_or(0.0, |(_, f)| sample(f, x, y, z))
            }))
        })?,
    )?;
    pge.set("noise", t)
}
