//! The root's (and every scene's) `extras.pge`, serialized in one pass from borrowed views of
//! the run's meta and the model: no `Map` of the params (hashed and cloned), no `Value` tree.
//! The text is the one the `Map` built entry by entry gave: generator, seed, params (a
//! duplicate name where it first appears, with its last value), stats, the environment, then
//! the model's own extras but for those the run's keys already hold, `stages` in the place
//! of the model's own `stages` or last.

use serde::ser::{Serialize, SerializeMap, Serializer};
use serde_json::{Map, Value as JsonValue};

use super::{ExportMeta, GENERATOR};
use crate::Result;

/// The root's `extras.pge`, borrowed.
pub(super) struct RootExtras<'a> {
    /// The run's seed and parameters.
    pub(super) meta: &'a ExportMeta,
    /// Vertices, triangles, nodes, leaves and modules.
    pub(super) stats: [u64; 5],
    /// The environment's image, if the model has one.
    pub(super) environment: Option<usize>,
    /// The model's own extras.
    pub(super) extras: &'a Map<String, JsonValue>,
    /// The stages' summary (`pge run --stages`).
    pub(super) stages: Option<&'a JsonValue>,
}

impl RootExtras<'_> {
    /// `{"pge": {...}}` as raw JSON.
    pub(super) fn extras(&self) -> Result<gltf_json::Extras> {
        serde_json::value::to_raw_value(&Pge(self))
            .map(Some)
            .map_err(|e| crate::Error::Export(e.to_string()))
    }

    /// Whether the run's entries hold `key` (the model's own entry of that name is not
    /// written).
    fn holds(&self, key: &str) -> bool {
        matches!(key, "generator" | "seed" | "params" | "stats")
            || (key == "environment" && self.environment.is_some())
    }
}

/// `{"pge": ...}`.
struct Pge<'r, 'a>(&'r RootExtras<'a>);

impl Serialize for Pge<'_, '_> {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        let mut map = s.serialize_map(Some(1))?;
        map.serialize_entry("pge", &Inner(self.0))?;
        map.end()
    }
}

/// The object under `pge`.
struct Inner<'r, 'a>(&'r RootExtras<'a>);

impl Serialize for Inner<'_, '_> {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        let r = self.0;
        let mut map = s.serialize_map(None)?;
        map.serialize_entry("generator", GENERATOR)?;
        map.serialize_entry("seed", &r.meta.seed)?;
        map.serialize_entry("params", &Params(&r.meta.params))?;
        let [vertices, triangles, nodes, leaves, modules] = r.stats;
        map.serialize_entry(
            "stats",
            &Entries([
                ("vertices", vertices),
                ("triangles", triangles),
                ("nodes", nodes),
                ("leaves", leaves),
                ("modules", modules),
            ]),
        )?;
        if let Some(image) = r.environment {
            map.serialize_entry("environment", &Environment(image))?;
        }
        let mut stages = r.stages;
        for (key, value) in r.extras {
            if r.holds(key) {
                continue;
            }
            match (key.as_str(), stages) {
                ("stages", Some(s)) => {
                    map.serialize_entry(key, s)?;
                    stages = None;
                }
                _ => map.serialize_entry(key, value)?,
            }
        }
        if let Some(s) = stages {
            map.serialize_entry("stages", s)?;
        }
        map.end()
    }
}

/// The parameters in order, a name given twice where it first appears, with its last value.
struct Params<'a>(&'a [(String, JsonValue)]);

impl Serialize for Params<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        let params = self.0;
        let mut map = s.serialize_map(None)?;
        for (i, (name, value)) in params.iter().enumerate() {
            if params[..i].iter().any(|(n, _)| n == name) {
                continue;
            }
            let last = params[i + 1..]
                .iter()
                .rev()
                .find(|(n, _)| n == name)
                .map_or(value, |(_, v)| v);
            map.serialize_entry(name, last)?;
        }
        map.end()
    }
}

/// `{"image": .., "mapping": "equirectangular"}`.
struct Environment(usize);

impl Serialize for Environment {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        let mut map = s.serialize_map(Some(2))?;
        map.serialize_entry("image", &self.0)?;
        map.serialize_entry("mapping", "equirectangular")?;
        map.end()
    }
}

/// A JSON object of the given entries, in order.
struct Entries<const N: usize>([(&'static str, u64); N]);

impl<const N: usize> Serialize for Entries<N> {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        let mut map = s.serialize_map(Some(N))?;
        for (key, value) in &self.0 {
            map.serialize_entry(key, value)?;
        }
        map.end()
    }
}

/// The extras as the `Map` built entry by entry wrote them (the text the tests compare with).
#[cfg(test)]
fn by_map(r: &RootExtras) -> Result<gltf_json::Extras> {
    use serde_json::json;
    let params: Map<String, JsonValue> = r.meta.params.iter().cloned().collect();
    let mut pge = Map::new();
    pge.insert("generator".into(), GENERATOR.into());
    pge.insert("seed".into(), r.meta.seed.into());
    pge.insert("params".into(), JsonValue::Object(params));
    let [v, t, n, l, m] = r.stats;
    pge.insert(
        "stats".into(),
        json!({ "vertices": v, "triangles": t, "nodes": n, "leaves": l, "modules": m }),
    );
    if let Some(image) = r.environment {
        pge.insert(
            "environment".into(),
            json!({ "image": image, "mapping": "equirectangular" }),
        );
    }
    for (k, v) in r.extras {
        pge.entry(k.clone()).or_insert_with(|| v.clone());
    }
    if let Some(stages) = r.stages {
        pge.insert("stages".into(), stages.clone());
    }
    super::raw(&json!({ "pge": pge }))
}

#[cfg(test)]
mod tests {
    use serde_json::json;

    use super::*;

    fn text(extras: &gltf_json::Extras) -> String {
        extras
            .as_ref()
            .map(|r| r.get().to_owned())
            .unwrap_or_default()
    }

    #[test]
    fn the_text_is_the_maps() {
        let params = [
            vec![],
            vec![("h".to_string(), json!(2.5))],
            vec![
                ("a\"b\n".to_string(), json!("x\u{1}é")),
                ("w".to_string(), json!(1e-7)),
                ("a\"b\n".to_string(), json!([1, -0.0, null])),
                ("z".to_string(), json!({"k": 0.1})),
                ("w".to_string(), json!(u64::MAX)),
                ("w".to_string(), json!(-3)),
            ],
        ];
        let own = [
            json!({}),
            json!({"leaves": 3, "note": "n"}),
            json!({"stages": "own", "generator": "x", "seed": 1, "params": {}, "stats": 0,
                   "environment": "e", "after": [true]}),
            json!({"environment": 2, "stages": [1], "b": null}),
        ];
        let stages = [None, Some(json!([{"name": "step 1", "vertices": 3}]))];
        let mut checked = 0;
        for params in &params {
            let meta = ExportMeta {
                seed: u64::MAX - 3,
                params: params.clone(),
            };
            for own in &own {
                let extras = own.as_object().expect("object");
                for stages in &stages {
                    for environment in [None, Some(0), Some(7)] {
                        let r = RootExtras {
                            meta: &meta,
                            stats: [3, 1, u64::MAX, 0, 12],
                            environment,
                            extras,
                            stages: stages.as_ref(),
                        };
                        let (one, map) = (r.extras().expect("one"), by_map(&r).expect("map"));
                        assert_eq!(text(&one), text(&map));
                        checked += 1;
                    }
                }
            }
        }
        assert_eq!(checked, 3 * 4 * 2 * 3);
    }

    #[test]
    fn a_name_given_twice_keeps_its_first_place_and_last_value() {
        let meta = ExportMeta {
            seed: 1,
            params: vec![
                ("a".into(), json!(1)),
                ("b".into(), json!(2)),
                ("a".into(), json!(3)),
            ],
        };
        let extras = Map::new();
        let r = RootExtras {
            meta: &meta,
            stats: [0; 5],
            environment: None,
            extras: &extras,
            stages: None,
        };
        assert!(text(&r.extras().expect("extras")).contains(r#""params":{"a":3,"b":2}"#));
    }
}
