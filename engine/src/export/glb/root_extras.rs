//! The root's (and every scene's) `extras.pge`, serialized in one pass from borrowed views of
//! the run's meta and the model: no `Map` of the params (hashed and cloned), no `Value` tree.
//! The text is the one the `Map` built entry by entry gave: generator, seed, params (a
//! duplicate name where it first appears, with its last value), stats, the environment, the
//! forest, then the model's own extras but for those the run's keys already hold, `stages`
//! in the place of the model's own `stages` or last.

use serde::ser::{Serialize, SerializeMap, Serializer};
use serde_json::{Map, Value as JsonValue};

use super::{ExportMeta, GENERATOR};
use crate::Result;
use crate::geometry::{ForestPart, ForestStats, SpeciesCount};

/// The root's `extras.pge`, borrowed.
pub(super) struct RootExtras<'a> {
    /// The run's seed and parameters.
    pub(super) meta: &'a ExportMeta,
    /// Vertices, triangles, nodes, leaves and modules.
    pub(super) stats: [u64; 5],
    /// The environment's image, if the model has one.
    pub(super) environment: Option<usize>,
    /// The forest the model is, if it is one.
    pub(super) forest: Option<&'a ForestStats>,
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
            || (key == "forest" && self.forest.is_some())
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
        if let Some(forest) = r.forest {
            map.serialize_entry("forest", &Forest(forest))?;
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

/// `{size, seed, tile, tileIndex, instances, species}` of a forest or a tile, `{size, seed,
/// tile, species, instances, tiles}` of merged tiles (the order `pge merge` has written).
struct Forest<'a>(&'a ForestStats);

impl Serialize for Forest<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        let f = self.0;
        let mut map = s.serialize_map(Some(6))?;
        map.serialize_entry("size", &f.size)?;
        map.serialize_entry("seed", &f.seed)?;
        map.serialize_entry("tile", &f.tile)?;
        match &f.part {
            ForestPart::Tile(index) => {
                map.serialize_entry("tileIndex", index)?;
                map.serialize_entry("instances", &f.instances)?;
                map.serialize_entry("species", &Species(&f.species))?;
            }
            ForestPart::Merged(tiles) => {
                map.serialize_entry("species", &Species(&f.species))?;
                map.serialize_entry("instances", &f.instances)?;
                map.serialize_entry("tiles", tiles)?;
            }
        }
        map.end()
    }
}

/// `[{name, variants, count}, ...]`.
struct Species<'a>(&'a [SpeciesCount]);

impl Serialize for Species<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        s.collect_seq(self.0.iter().map(SpeciesEntry))
    }
}

struct SpeciesEntry<'a>(&'a SpeciesCount);

impl Serialize for SpeciesEntry<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        let mut map = s.serialize_map(Some(3))?;
        map.serialize_entry("name", &self.0.name)?;
        map.serialize_entry("variants", &self.0.variants)?;
        map.serialize_entry("count", &self.0.count)?;
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
                            forest: None,
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
            forest: None,
            extras: &extras,
            stages: None,
        };
        assert!(text(&r.extras().expect("extras")).contains(r#""params":{"a":3,"b":2}"#));
    }

    #[test]
    fn the_forest_is_written_as_its_map_was() {
        let mut forest = ForestStats {
            size: [60.0, 0.1],
            seed: 7,
            tile: Some(30.0),
            part: ForestPart::Tile(Some([1, 0])),
            instances: 12,
            species: vec![
                SpeciesCount {
                    name: "oak".into(),
                    variants: 2,
                    count: 9,
                },
                SpeciesCount {
                    name: "layer2".into(),
                    variants: 3,
                    count: 3,
                },
            ],
        };
        let species = json!([
            {"name": "oak", "variants": 2, "count": 9},
            {"name": "layer2", "variants": 3, "count": 3},
        ]);
        let mut map = json!({
            "size": [60.0, 0.1], "seed": 7, "tile": 30.0, "tileIndex": [1, 0],
            "instances": 12, "species": species,
        });
        let meta = ExportMeta::default();
        let extras = Map::new();
        let written = |forest: &ForestStats| {
            let r = RootExtras {
                meta: &meta,
                stats: [0; 5],
                environment: None,
                forest: Some(forest),
                extras: &extras,
                stages: None,
            };
            text(&r.extras().expect("extras"))
        };
        let inner = |map: &JsonValue| format!(r#""forest":{}}}}}"#, map);
        assert!(
            written(&forest).ends_with(&inner(&map)),
            "{}",
            written(&forest)
        );
        // Merged tiles: what `pge merge` made of the map (the tile index removed, the last
        // entry taking its place, the tiles appended).
        let object = map.as_object_mut().expect("object");
        object.remove("tileIndex");
        object.insert("tiles".into(), json!([[0, 0], [1, 0]]));
        forest.part = ForestPart::Merged(vec![[0, 0], [1, 0]]);
        assert!(
            written(&forest).ends_with(&inner(&map)),
            "{}",
            written(&forest)
        );
        // A whole forest, untiled.
        forest.tile = None;
        forest.part = ForestPart::Tile(None);
        assert!(written(&forest).contains(r#""tile":null,"tileIndex":null,"instances":12"#));
    }
}
