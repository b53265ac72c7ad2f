//! The layout: where every tree of every layer stands, with its yaw, scale and variant,
//! for the whole world or for one tile.

use rayon::prelude::*;

use crate::ForestError;
use crate::jittered::jittered;
use crate::layer::{Density, Layer, Method, Variants};
use crate::poisson::{Rect, Sample, block_size, poisson_until};
use crate::terrain::Terrain;
use crate::trunks::Trunks;
use pge_engine::random::{SplitMix64, hash_words};
use pge_engine::{Location, RunContext};

/// The most instances a layout may hold.
pub const MAX_INSTANCES: usize = 10_000_000;

/// Bytes the layout holds per sample it draws while it runs (the sample, its candidate
/// instance, the kept trunk and its index, the instance): checked against the run's memory
/// budget before the layout starts.
const LAYOUT_BYTES: f64 = 160.0;

/// Samples between two checks of the deadline.
const CHECK_EVERY: usize = 1 << 16;

/// One tree of the layout: 28 bytes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Instance {
    /// Trunk base on the terrain.
    pub position: [f32; 3],
    /// Rotation about the vertical axis, radians.
    pub yaw: f32,
    /// Uniform scale.
    pub scale: f32,
    /// Index of the layer.
    pub layer: u32,
    /// Variant (0-based); with `"unique"` the tree's identity, from its cell (the same in
    /// every tile), which names its mesh.
    pub variant: u32,
}

/// The trees of a forest or a tile, layer by layer.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Layout {
    /// Instances, layer by layer, each layer in cell order.
    pub instances: Vec<Instance>,
    /// Instances per layer.
    pub counts: Vec<usize>,
    /// Layers that fit no tree.
    pub warnings: Vec<String>,
}

/// One tile of a tiled world.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tile {
    /// Index along x.
    pub i: usize,
    /// Index along z.
    pub j: usize,
    /// Its rectangle of ground.
    pub rect: Rect,
}

/// A forest: its world, terrain and layers.
#[derive(Clone, Debug)]
pub struct Forest {
    /// Metres along x and z.
    pub size: [f64; 2],
    /// The seed every draw derives from.
    pub seed: u64,
    /// Side of a tile in metres, if tiled.
    pub tile: Option<f64>,
    /// The ground.
    pub terrain: Terrain,
    /// Species layers, in scattering order.
    pub layers: Vec<Layer>,
}

impl Forest {
    /// A flat world without layers; `size` and `tile` must be positive.
    pub fn new(size: [f64; 2], seed: u64, tile: Option<f64>) -> Result<Forest, ForestError> {
        if !size.iter().all(|s| s.is_finite() && *s > 0.0) {
            return Err(ForestError::Option {
                option: "size",
                message: format!(
                    "must be two positive numbers of metres {{x, z}}, got {{{}, {}}}",
                    size[0], size[1]
                ),
            });
        }
        if let Some(t) = tile
            && !(t.is_finite() && t > 0.0)
        {
            return Err(ForestError::Option {
                option: "tile",
                message: format!("must be a positive number of metres, got {t}"),
            });
        }
        Ok(Forest {
            size,
            seed,
            tile,
            terrain: Terrain::flat(size),
            layers: Vec::new(),
        })
    }

    /// The world's rectangle, centred on the origin.
    #[must_use]
    pub fn world(&self) -> Rect {
        Rect::new(
            [-0.5 * self.size[0], -0.5 * self.size[1]],
            [0.5 * self.size[0], 0.5 * self.size[1]],
        )
    }

    /// How many tiles there are along x and along z, `None` when the forest is not tiled
    /// (counted, not listed: a forest of many tiny tiles costs nothing until they are).
    #[must_use]
    pub fn tile_counts(&self) -> Option<[usize; 2]> {
        let t = self.tile?;
        let n = |s: f64| (s / t - 1e-9).ceil().max(1.0) as usize;
        Some([n(self.size[0]), n(self.size[1])])
    }

    /// The rectangle of tile `(i, j)` (within [`Forest::tile_counts`]).
    fn tile_at(&self, t: f64, n: [usize; 2], i: usize, j: usize) -> Rect {
        let w = self.world();
        let min = [w.min[0] + i as f64 * t, w.min[1] + j as f64 * t];
        let max = [
            if i + 1 == n[0] { w.max[0] } else { min[0] + t },
            if j + 1 == n[1] { w.max[1] } else { min[1] + t },
        ];
        Rect::new(min, max)
    }

    /// Every tile, `i` fastest, or `None` when the forest is not tiled. The list is as long
    /// as [`Forest::tile_counts`] says: check it before asking for a world of tiny tiles.
    #[must_use]
    pub fn tiles(&self) -> Option<Vec<Tile>> {
        let t = self.tile?;
        let n = self.tile_counts()?;
        let mut out = Vec::with_capacity(n[0].saturating_mul(n[1]));
        for j in 0..n[1] {
            for i in 0..n[0] {
                out.push(Tile {
                    i,
                    j,
                    rect: self.tile_at(t, n, i, j),
                });
            }
        }
        Some(out)
    }

    /// Tile `(i, j)`, or an error when the forest has no `tile` or the index is outside.
    pub fn tile_rect(&self, i: usize, j: usize) -> Result<Rect, ForestError> {
        let (Some(t), Some(n)) = (self.tile, self.tile_counts()) else {
            return Err(ForestError::NotTiled);
        };
        if i >= n[0] || j >= n[1] {
            return Err(ForestError::TileOutOfRange {
                i,
                j,
                nx: n[0],
                nz: n[1],
            });
        }
        Ok(self.tile_at(t, n, i, j))
    }

    /// The layout of the whole forest, or of tile `(i, j)`: a tile holds the instances whose
    /// trunk is inside it, exactly as the whole forest places them. Without a time or memory
    /// limit: [`Forest::layout_within`] keeps to a run's.
    pub fn layout(&self, tile: Option<(usize, usize)>) -> Result<Layout, ForestError> {
        self.layout_within(tile, &RunContext::unlimited(), &Location::new("forest", 0))
    }

    /// The regions each layer is sampled in for `target`: each layer must be right wherever
    /// a later one reads it.
    fn regions(&self, target: Rect) -> Vec<Rect> {
        let n = self.layers.len();
        let mut regions = vec![target; n];
        for l in (0..n.saturating_sub(1)).rev() {
            regions[l] = regions[l + 1].expand(self.layers[l + 1].reach());
        }
        regions
    }

    /// About how many samples the layers draw for `target` (the whole world, or a tile and
    /// the margins its layers read): what the layout's time and memory grow with.
    #[must_use]
    pub fn estimate(&self, target: Rect) -> f64 {
        self.estimates(target).iter().sum()
    }

    /// [`Forest::estimate`] of each layer.
    fn estimates(&self, target: Rect) -> Vec<f64> {
        let world = self.world();
        self.layers
            .iter()
            .zip(self.regions(target))
            .map(|(l, region)| l.estimate(region.intersection(&world).area()))
            .collect()
    }

    /// [`Forest::layout`] within a run's limits: sizes checked against `ctx.budget` before
    /// anything is allocated, the deadline checked as the samples are drawn and kept (a
    /// limit is an engine error placed at `at`, in [`ForestError::Script`]). Only the tile's
    /// region counts: a tile of a world of any size is laid out in the time and memory of
    /// its own trees.
    pub fn layout_within(
        &self,
        tile: Option<(usize, usize)>,
        ctx: &RunContext,
        at: &Location,
    ) -> Result<Layout, ForestError> {
        self.layout_located(tile, ctx, &|_| at.clone())
    }

    /// [`Forest::layout_within`], its limits placed by `at`: `at(Some(l))` where layer `l`
    /// was described (a size past the memory budget, at the layer that draws the most
    /// samples), `at(None)` where the forest was (the deadline).
    pub fn layout_located(
        &self,
        tile: Option<(usize, usize)>,
        ctx: &RunContext,
        at: &dyn Fn(Option<usize>) -> Location,
    ) -> Result<Layout, ForestError> {
        for l in &self.layers {
            l.check()?;
        }
        let world = self.world();
        let target = match tile {
            Some((i, j)) => self.tile_rect(i, j)?,
            None => world,
        };
        let estimates = self.estimates(target);
        let estimate: f64 = estimates.iter().sum();
        let densest = estimates
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(b.1))
            .map(|(l, _)| l);
        if estimate > MAX_INSTANCES as f64 {
            return Err(ForestError::TooMany {
                estimate: estimate as u64,
                layer: densest,
            });
        }
        ctx.budget
            .check((estimate * LAYOUT_BYTES) as u64, &at(densest), || {
                format!(
                    "the layout of about {} trees needs {} MiB (raise minDistance, lower density or lay out a tile)",
                    estimate as u64,
                    (estimate * LAYOUT_BYTES / f64::from(1 << 20)).ceil()
                )
            })
            .map_err(ForestError::Script)?;
        let at = at(None);
        let check = || ctx.check_deadline(&at).map_err(ForestError::Script);
        let stopped = || ctx.check_deadline(&at).is_err();
        let regions = self.regions(target);
        let mut layout = Layout::default();
        let mut trunks = Trunks::default();
        for (l, layer) in self.layers.iter().enumerate() {
            check()?;
            let region = regions[l];
            let r = layer.min_distance;
            let index = trunks.index(r);
            let blocked = |x: f64, z: f64| index.any_within(x, z, r);
            let seed = hash_words(&[self.seed, 0x1a7e, l as u64]);
            let samples = match layer.method {
                Method::Poisson => {
                    let samples =
                        poisson_until(world, region, r, seed, &blocked, MAX_INSTANCES, &stopped);
                    check()?;
                    samples.map_err(|_| ForestError::TooMany {
                        estimate: MAX_INSTANCES as u64 + 1,
                        layer: Some(l),
                    })?
                }
                Method::Jittered { jitter } => {
                    let samples = jittered(
                        world,
                        region,
                        layer.cell(jitter),
                        jitter,
                        seed,
                        &blocked,
                        &stopped,
                    );
                    check()?;
                    samples
                }
            };
            // Cells along x, for the identity of "unique" trees.
            let across = match layer.method {
                Method::Poisson => block_size(r),
                Method::Jittered { jitter } => layer.cell(jitter),
            };
            let across = (self.size[0] / across).ceil() as u64;
            // Draws, height and slope of every sample in parallel (each from its own seed);
            // the density decides in order, as a script's density function must be called
            // on the script's thread.
            let site = Site {
                terrain: &self.terrain,
                seed: self.seed,
                layer: l,
                scale: layer.scale,
                variants: layer.variants,
                slope: layer.slope,
                altitude: layer.altitude,
            };
            let mut candidates: Vec<Option<(Instance, f64)>> = Vec::with_capacity(samples.len());
            for chunk in samples.chunks(CHECK_EVERY) {
                check()?;
                candidates.par_extend(chunk.par_iter().map(|s| site.candidate(s)));
            }
            let mut kept = Vec::new();
            let mut count = 0usize;
            for (k, (s, candidate)) in samples.into_iter().zip(candidates).enumerate() {
                if k % CHECK_EVERY == 0 {
                    check()?;
                }
                let Some((inst, keep)) = candidate else {
                    continue;
                };
                if keep >= self.density_at(layer, &s)? {
                    continue;
                }
                kept.push((s.x, s.z));
                if target.contains(s.x, s.z) {
                    let variant = match layer.variants {
                        Variants::Count(_) => inst.variant,
                        Variants::Unique => unique_id(&s, across, l)?,
                    };
                    layout.instances.push(Instance { variant, ..inst });
                    count += 1;
                    if layout.instances.len() > MAX_INSTANCES {
                        return Err(ForestError::TooMany {
                            estimate: layout.instances.len() as u64,
                            layer: Some(l),
                        });
                    }
                }
            }
            if count == 0 && tile.is_none() {
                layout.warnings.push(format!(
                    "layer {} ({}) fits no tree: its density, slope and altitude limits exclude the whole terrain",
                    l + 1,
                    layer.name
                ));
            }
            layout.counts.push(count);
            trunks.extend(kept);
        }
        Ok(layout)
    }

    /// The density of `layer` at sample `s`.
    fn density_at(&self, layer: &Layer, s: &Sample) -> Result<f64, ForestError> {
        Ok(match &layer.density {
            Density::Constant(d) => *d,
            Density::Map(m) => m.sample(
                (s.x + 0.5 * self.size[0]) / self.size[0],
                (s.z + 0.5 * self.size[1]) / self.size[1],
            ),
            Density::Function(f) => {
                let d = f(s.x, s.z).map_err(ForestError::Script)?;
                if !(0.0..=1.0).contains(&d) {
                    return Err(ForestError::Option {
                        option: "density",
                        message: format!(
                            "the function returned {d} at ({:.2}, {:.2}); it must return a number between 0 and 1",
                            s.x, s.z
                        ),
                    });
                }
                d
            }
        })
    }
}

/// What a sample of one layer needs to become an instance, shareable across threads.
struct Site<'a> {
    terrain: &'a Terrain,
    seed: u64,
    layer: usize,
    scale: [f64; 2],
    variants: Variants,
    slope: [f64; 2],
    altitude: [f64; 2],
}

impl Site<'_> {
    /// The instance sample `s` grows into and the draw its density must exceed, or `None`
    /// when the altitude or slope limits exclude it.
    fn candidate(&self, s: &Sample) -> Option<(Instance, f64)> {
        let mut rng = SplitMix64::new(hash_words(&[
            self.seed,
            0x1257,
            self.layer as u64,
            u64::from(s.cell[0]),
            u64::from(s.cell[1]),
            u64::from(s.index),
        ]));
        let keep = rng.uniform();
        let yaw = rng.uniform() * std::f64::consts::TAU;
        let scale = rng.range(self.scale[0], self.scale[1]);
        let variant = match self.variants {
            Variants::Count(n) => rng.below(n),
            Variants::Unique => 0,
        };
        let h = self.terrain.height(s.x, s.z);
        if h < self.altitude[0] || h > self.altitude[1] {
            return None;
        }
        if self.slope != [0.0, 90.0] {
            let slope = self.terrain.slope_degrees(s.x, s.z);
            if slope < self.slope[0] || slope > self.slope[1] {
                return None;
            }
        }
        let inst = Instance {
            position: [s.x as f32, h as f32, s.z as f32],
            yaw: yaw as f32,
            scale: scale as f32,
            layer: self.layer as u32,
            variant,
        };
        Some((inst, keep))
    }
}

/// The identity of a `"unique"` tree: its cell's index in the world (z, then x) and its
/// rank in the cell (a Poisson block holds 25 samples at most, one per background cell), the
/// same in a tile as in the whole forest.
fn unique_id(s: &Sample, across: u64, layer: usize) -> Result<u32, ForestError> {
    let cell = u64::from(s.cell[1]) * across + u64::from(s.cell[0]);
    u32::try_from(cell * 32 + u64::from(s.index)).map_err(|_| ForestError::TooMany {
        estimate: cell.saturating_mul(32),
        layer: Some(layer),
    })
}

/// The seed of variant `v` of layer `l`.
#[must_use]
pub fn variant_seed(forest_seed: u64, layer: usize, v: u32) -> u64 {
    hash_words(&[forest_seed, 0x5eed, layer as u64, u64::from(v)]) >> 12
}

/// The seed of a `"unique"` instance's own tree: from its position, which tiles and the
/// whole forest compute alike.
#[must_use]
pub fn unique_seed(forest_seed: u64, inst: &Instance) -> u64 {
    hash_words(&[
        forest_seed,
        0x0417,
        u64::from(inst.layer),
        u64::from(inst.position[0].to_bits()),
        u64::from(inst.position[2].to_bits()),
    ]) >> 12
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::terrain::FbmOptions;
    use pge_engine::math;

    fn forest(tile: Option<f64>) -> Forest {
        let mut f = Forest::new([120.0, 90.0], 11, tile).expect("forest");
        f.terrain = Terrain::fbm(
            f.size,
            FbmOptions {
                height: 15.0,
                scale: 60.0,
                ..FbmOptions::default()
            },
            11,
        );
        let mut oak = Layer::new("oak", 6.0);
        oak.altitude = [f64::NEG_INFINITY, 2.0];
        let mut pine = Layer::new("pine", 3.0);
        pine.density = Density::Constant(0.7);
        let mut rows = Layer::new("rows", 2.5);
        rows.method = Method::Jittered { jitter: 0.2 };
        rows.variants = Variants::Unique;
        f.layers = vec![oak, pine, rows];
        f
    }

    fn closest_within_layer(insts: &[Instance], layer: u32) -> f64 {
        let v: Vec<_> = insts.iter().filter(|i| i.layer == layer).collect();
        let mut best = f64::INFINITY;
        for (k, a) in v.iter().enumerate() {
            for b in &v[k + 1..] {
                let d = f64::from(math::hypot(
                    a.position[0] - b.position[0],
                    a.position[2] - b.position[2],
                ));
                best = best.min(d);
            }
        }
        best
    }

    #[test]
    fn layers_keep_their_distances_limits_and_density() {
        let f = forest(None);
        let layout = f.layout(None).expect("layout");
        assert_eq!(layout.counts.iter().sum::<usize>(), layout.instances.len());
        assert!(layout.counts.iter().all(|&c| c > 0), "{:?}", layout.counts);
        assert!(closest_within_layer(&layout.instances, 0) >= 6.0 - 1e-4);
        assert!(closest_within_layer(&layout.instances, 1) >= 3.0 - 1e-4);
        assert!(closest_within_layer(&layout.instances, 2) >= 2.5 - 1e-4);
        for i in &layout.instances {
            if i.layer == 0 {
                assert!(i.position[1] <= 2.0);
            }
            assert!((0.8..=1.2).contains(&i.scale));
            // Later layers keep their own distance from earlier trunks.
            for e in layout.instances.iter().filter(|e| e.layer < i.layer) {
                let d = math::hypot(e.position[0] - i.position[0], e.position[2] - i.position[2]);
                let r = f.layers[i.layer as usize].min_distance as f32;
                assert!(d >= r - 1e-3, "{d} < {r}");
            }
        }
        // Density 0.7 keeps about 70% of what density 1 keeps.
        let mut full = f.clone();
        full.layers[1].density = Density::Constant(1.0);
        let all = full.layout(None).expect("layout").counts[1] as f64;
        let ratio = layout.counts[1] as f64 / all;
        assert!((ratio - 0.7).abs() < 0.08, "{ratio}");
    }

    #[test]
    fn the_union_of_tiles_is_the_whole_forest() {
        let f = forest(Some(40.0));
        let whole = f.layout(None).expect("layout");
        let tiles = f.tiles().expect("tiled");
        assert_eq!(tiles.len(), 9);
        let mut union = Vec::new();
        for t in &tiles {
            let part = f.layout(Some((t.i, t.j))).expect("tile");
            for i in &part.instances {
                assert!(
                    t.rect
                        .contains(f64::from(i.position[0]), f64::from(i.position[2]))
                );
            }
            union.extend(part.instances);
        }
        let key = |i: &Instance| (i.layer, i.position[0].to_bits(), i.position[2].to_bits());
        // Variants too, "unique" ones (layer 2) included: they are identities, not ranks.
        let sorted = |mut v: Vec<Instance>| {
            v.sort_by_key(key);
            v
        };
        let whole = sorted(whole.instances);
        let unique: std::collections::HashSet<u32> = whole
            .iter()
            .filter(|i| i.layer == 2)
            .map(|i| i.variant)
            .collect();
        assert_eq!(unique.len(), whole.iter().filter(|i| i.layer == 2).count());
        // Trunks from different tiles keep the layer's distance across the seams.
        for (l, layer) in f.layers.iter().enumerate() {
            let d = closest_within_layer(&union, l as u32);
            assert!(d >= layer.min_distance - 1e-4, "layer {l}: {d}");
        }
        assert_eq!(sorted(union), whole);
    }

    #[test]
    fn bad_options_and_tiles_are_errors() {
        let mut f = forest(None);
        f.layers[0].min_distance = 0.0;
        assert!(matches!(
            f.layout(None),
            Err(ForestError::Option {
                option: "minDistance",
                ..
            })
        ));
        let mut f = forest(None);
        f.layers[1].slope = [30.0, 10.0];
        assert!(matches!(
            f.layout(None),
            Err(ForestError::Option {
                option: "slope",
                ..
            })
        ));
        let mut f = forest(None);
        f.layers[1].density = Density::Constant(1.5);
        assert!(matches!(
            f.layout(None),
            Err(ForestError::Option {
                option: "density",
                ..
            })
        ));
        let f = forest(None);
        assert!(matches!(f.layout(Some((0, 0))), Err(ForestError::NotTiled)));
        let f = forest(Some(40.0));
        assert!(matches!(
            f.layout(Some((3, 0))),
            Err(ForestError::TileOutOfRange { .. })
        ));
        let mut f = Forest::new([10_000.0, 10_000.0], 1, None).expect("forest");
        f.layers.push(Layer::new("grass", 0.5));
        assert!(matches!(f.layout(None), Err(ForestError::TooMany { .. })));
        assert!(Forest::new([0.0, 10.0], 1, None).is_err());
    }

    #[test]
    fn a_layer_that_fits_nowhere_is_a_warning() {
        let mut f = forest(None);
        f.layers[0].altitude = [500.0, 600.0];
        let layout = f.layout(None).expect("layout");
        assert_eq!(layout.counts[0], 0);
        assert_eq!(layout.warnings.len(), 1);
        assert!(layout.warnings[0].contains("oak"));
    }
}
