//! What a forest's model records about the forest: its size, seed and tiling, how many trees
//! of each species stand in it ([`ForestStats`], written as the root `extras.pge.forest`),
//! and what one instance of each shared variant stands for ([`VariantCounts`]).

/// The forest a model is (a whole forest, one tile of it, or tiles merged), written by the
/// glTF writer as `extras.pge.forest = {size, seed, tile, tileIndex, instances, species}`
/// (merged tiles: `{size, seed, tile, species, instances, tiles}`).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ForestStats {
    /// The forest's extent in metres along x and z.
    pub size: [f64; 2],
    /// The forest's seed.
    pub seed: u64,
    /// The side of its tiles in metres, `None` when it is not tiled.
    pub tile: Option<f64>,
    /// Which part of the forest the model holds.
    pub part: ForestPart,
    /// Trees placed in the model.
    pub instances: u64,
    /// Per species (layer), in the forest's order.
    pub species: Vec<SpeciesCount>,
}

/// Which part of a forest a model holds.
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum ForestPart {
    /// The whole forest (`None`) or the tile `(i, j)` of it (`tileIndex`).
    Tile(Option<[u64; 2]>),
    /// Tiles merged (`pge merge`), in the order they were added (`tiles`).
    Merged(Vec<[u64; 2]>),
}

impl Default for ForestPart {
    fn default() -> Self {
        ForestPart::Tile(None)
    }
}

/// The trees of one species of a forest.
#[derive(Clone, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct SpeciesCount {
    /// The species' name (its script's file stem, or `layerN`).
    pub name: String,
    /// How many variants it was grown as (its instances for `"unique"` trees).
    pub variants: u64,
    /// Its trees placed in the model.
    pub count: u64,
}

/// What one instance of a shared variant stands for: the skeleton nodes and leaves of the
/// tree it draws.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct VariantCounts {
    /// Skeleton nodes.
    pub nodes: u64,
    /// Leaves.
    pub leaves: u64,
}

impl ForestStats {
    /// Adds another tile's trees to these (tiles merged): its instances, and each species'
    /// count where both list it.
    pub fn add_tile(&mut self, tile: &ForestStats) {
        // Saturating: the counts come from files (a tampered tile must not wrap them).
        self.instances = self.instances.saturating_add(tile.instances);
        for (a, b) in self.species.iter_mut().zip(&tile.species) {
            a.count = a.count.saturating_add(b.count);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tiles_add_up() {
        let tile = |n| ForestStats {
            size: [60.0, 60.0],
            seed: 3,
            tile: Some(30.0),
            part: ForestPart::Tile(Some([0, 1])),
            instances: n,
            species: vec![SpeciesCount {
                name: "oak".into(),
                variants: 2,
                count: n,
            }],
        };
        let mut world = tile(4);
        world.add_tile(&tile(5));
        assert_eq!(world.instances, 9);
        assert_eq!(world.species[0].count, 9);
        // A species the other tile does not list keeps its count.
        let mut more = tile(1);
        more.species.push(SpeciesCount {
            name: "pine".into(),
            variants: 1,
            count: 7,
        });
        more.add_tile(&tile(2));
        assert_eq!(more.species[0].count, 3);
        assert_eq!(more.species[1].count, 7);
    }
}
