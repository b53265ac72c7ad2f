//! What a forest run is given: the world and its layers ([`Forest`]), where each layer's
//! trees come from ([`Species`]), the levels of detail ([`ForestLod`]), the tile to make,
//! and where the forest was described (a script's lines, for its errors and warnings).

use std::fmt;
use std::rc::Rc;

use pge_engine::geometry::Model;
use pge_engine::{Location, RunContext};

use crate::{Forest, ForestError, ForestLod, Layer, Terrain, Tile};

/// Bytes a listed tile is counted in a memory budget: the tile and what a caller makes of
/// it (a Lua table, a JSON object).
pub const TILE_BYTES: u64 = 256;

/// A species grown from a script: the script's path (as its session is given it: errors
/// name it, and the variant cache reads it) and its parameter overrides (as `--set`
/// strings, sorted by name). Its variants are grown by the run's
/// [`SpeciesGrower`](crate::SpeciesGrower).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ScriptSpecies {
    /// The script.
    pub path: String,
    /// `NAME=VALUE` overrides of the parameters it declares.
    pub params: Vec<(String, String)>,
}

impl ScriptSpecies {
    /// The script at `path` with `params` (sorted here, so two lists of the same overrides
    /// name the same variants).
    #[must_use]
    pub fn new(path: impl Into<String>, params: &[(&str, &str)]) -> ScriptSpecies {
        let mut params: Vec<(String, String)> = params
            .iter()
            .map(|(k, v)| ((*k).to_string(), (*v).to_string()))
            .collect();
        params.sort();
        ScriptSpecies {
            path: path.into(),
            params,
        }
    }
}

/// Grows one variant from its seed, on the thread that runs the forest.
pub type VariantFn = dyn Fn(u64, &RunContext) -> pge_engine::Result<Model>;

/// Where a layer's trees come from.
#[derive(Clone)]
pub enum Species {
    /// A script: every variant grown by the run's grower, in parallel, each on its own.
    Script(ScriptSpecies),
    /// A function of the variant's seed, called for each variant in order on the thread
    /// that runs the forest (a script's function, which must stay on its Lua state's
    /// thread).
    Function(Rc<VariantFn>),
}

impl fmt::Debug for Species {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Species::Script(s) => f.debug_tuple("Script").field(s).finish(),
            Species::Function(_) => write!(f, "Function"),
        }
    }
}

/// A forest to run: the world and its layers, each with its [`Species`], the levels of
/// detail, the tile to make (the whole world when none), and where it was described.
///
/// ```
/// use pge_forest::{ForestSpec, Layer, ScriptSpecies, Species};
///
/// let mut spec = ForestSpec::new([200.0, 200.0], 7, Some(100.0)).unwrap();
/// let oak = Species::Script(ScriptSpecies::new("scripts/species/oak.lua", &[("points", "300")]));
/// spec.add_layer(Layer::new("oak", 9.0), oak).unwrap();
/// spec.select_tile(1, 0).unwrap();
/// assert_eq!(spec.tiles(&pge_engine::Budget::default()).unwrap().len(), 4);
/// assert!(spec.select_tile(2, 0).is_err());
/// ```
#[derive(Clone, Debug)]
pub struct ForestSpec {
    forest: Forest,
    species: Vec<Species>,
    origins: Vec<Option<Location>>,
    origin: Option<Location>,
    tile: Option<(usize, usize)>,
    /// Levels of detail for the variants and a leaf budget for a camera.
    pub lod: ForestLod,
}

impl ForestSpec {
    /// A flat world of `size` metres (x by z) without layers, cut into tiles of `tile`
    /// metres if given (both must be positive).
    pub fn new(size: [f64; 2], seed: u64, tile: Option<f64>) -> Result<ForestSpec, ForestError> {
        Ok(ForestSpec {
            forest: Forest::new(size, seed, tile)?,
            species: Vec::new(),
            origins: Vec::new(),
            origin: None,
            tile: None,
            lod: ForestLod::default(),
        })
    }

    /// The place that described the forest (a script's `pge.Forest{...}`): errors of the
    /// whole forest point at it.
    #[must_use]
    pub fn described_at(mut self, origin: Location) -> ForestSpec {
        self.origin = Some(origin);
        self
    }

    /// The world, its terrain and layers.
    #[must_use]
    pub fn forest(&self) -> &Forest {
        &self.forest
    }

    /// The species of every layer, in order.
    #[must_use]
    pub fn species(&self) -> &[Species] {
        &self.species
    }

    /// Sets the ground.
    pub fn set_terrain(&mut self, terrain: Terrain) {
        self.forest.terrain = terrain;
    }

    /// Adds a layer and where its trees come from, after checking its options; returns its
    /// index.
    pub fn add_layer(&mut self, layer: Layer, species: Species) -> Result<usize, ForestError> {
        layer.check()?;
        self.forest.layers.push(layer);
        self.species.push(species);
        self.origins.push(None);
        Ok(self.forest.layers.len() - 1)
    }

    /// [`add_layer`](ForestSpec::add_layer), described at `origin` (a script's
    /// `forest:scatter{...}`): errors of its species and its warnings point there.
    pub fn add_layer_at(
        &mut self,
        layer: Layer,
        species: Species,
        origin: Location,
    ) -> Result<usize, ForestError> {
        let l = self.add_layer(layer, species)?;
        self.origins[l] = Some(origin);
        Ok(l)
    }

    /// Every tile of the world, `i` fastest; [`ForestError::NotTiled`] without `tile`, and
    /// an [`pge_engine::Error::MemoryLimit`] naming `tile` (in [`ForestError::Script`]) when
    /// the list would not fit in `budget` (a listed tile, with what its callers make of it,
    /// counts [`TILE_BYTES`]).
    pub fn tiles(&self, budget: &pge_engine::Budget) -> Result<Vec<Tile>, ForestError> {
        let n = self.forest.tile_counts().ok_or(ForestError::NotTiled)?;
        let count = (n[0] as u64).saturating_mul(n[1] as u64);
        budget
            .check(count.saturating_mul(TILE_BYTES), &self.origin(), || {
                format!(
                    "tile = {} makes {} x {} tiles, too many to list",
                    self.forest.tile.unwrap_or_default(),
                    n[0],
                    n[1]
                )
            })
            .map_err(ForestError::Script)?;
        self.forest.tiles().ok_or(ForestError::NotTiled)
    }

    /// Makes the run make tile `(i, j)` alone (its terrain patch and the trees whose trunk
    /// is inside it); an error when the forest has no tiles or the index is outside them.
    pub fn select_tile(&mut self, i: usize, j: usize) -> Result<(), ForestError> {
        self.forest.tile_rect(i, j)?;
        self.tile = Some((i, j));
        Ok(())
    }

    /// The tile the run makes, `None` for the whole world.
    #[must_use]
    pub fn tile(&self) -> Option<(usize, usize)> {
        self.tile
    }

    /// Where the forest was described: the script's line, or `forest` for a spec built in
    /// Rust.
    #[must_use]
    pub fn origin(&self) -> Location {
        self.origin.clone().unwrap_or_else(|| Location {
            file: "forest".into(),
            line: None,
        })
    }

    /// Where layer `l` was described: the script's line, or `forest layer N (NAME)` for a
    /// layer added in Rust.
    #[must_use]
    pub fn layer_origin(&self, l: usize) -> Location {
        match self.origins.get(l).cloned().flatten() {
            Some(origin) => origin,
            None => Location {
                file: format!(
                    "forest layer {} ({})",
                    l + 1,
                    self.forest.layers.get(l).map_or("", |x| x.name.as_str())
                ),
                line: None,
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layers_keep_their_species_and_origins_and_bad_ones_are_refused() {
        let mut spec = ForestSpec::new([60.0, 60.0], 3, None).expect("spec");
        let stick = Species::Script(ScriptSpecies::new("stick.lua", &[("b", "2"), ("a", "1")]));
        let l = spec
            .add_layer_at(Layer::new("stick", 3.0), stick, Location::new("f.lua", 2))
            .expect("layer");
        assert_eq!(l, 0);
        let Species::Script(s) = &spec.species()[0] else {
            panic!("a script");
        };
        assert_eq!(s.params[0], ("a".to_string(), "1".to_string()));
        assert_eq!(spec.layer_origin(0).to_string(), "f.lua:2");
        let none = Species::Function(Rc::new(|_, _| Ok(Model::new())));
        assert!(
            spec.add_layer(Layer::new("bad", 0.0), none.clone())
                .is_err()
        );
        assert_eq!(
            spec.forest().layers.len(),
            1,
            "a refused layer is not added"
        );
        spec.add_layer(Layer::new("rust", 4.0), none)
            .expect("layer");
        assert_eq!(spec.layer_origin(1).to_string(), "forest layer 2 (rust)");
        assert_eq!(spec.origin().to_string(), "forest");
        assert!(matches!(
            spec.tiles(&pge_engine::Budget::default()),
            Err(ForestError::NotTiled)
        ));
        assert!(matches!(spec.select_tile(0, 0), Err(ForestError::NotTiled)));
        assert_eq!(spec.tile(), None);
    }
}
