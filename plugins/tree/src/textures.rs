//! Procedural PBR textures: bark and leaves as sets of three maps (base colour, tangent-space
//! normal, roughness), so a tree needs no image files.
//!
//! Every map is a pure function of its parameters ([`BarkParams`], [`LeafParams`]): a height
//! field from fast hashed noise (periodic value noise and stretched cellular noise), the
//! normal map derived from that height field by central differences, colour and roughness
//! from the same field. Rows are computed in parallel (rayon) and the three maps are
//! PNG-encoded in parallel with fast compression; none of it depends on the thread count.
//!
//! Sets are generated once per distinct parameter set and process ([`TextureCache`]): the
//! variants of a forest, built in parallel sessions, share one set per species. Bark tiles
//! in `u` (around the branch) and `v` (along it).

use std::collections::HashMap;
use std::f32::consts::{PI, TAU};
use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex, OnceLock};

use pge_engine::geometry::Texture;
use rayon::prelude::*;

use crate::TreeError;
use crate::options::{BarkStyle, LeafShape};

/// The parameters a bark texture set is made from: its cache key.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BarkParams {
    /// The pattern.
    pub style: BarkStyle,
    /// The bark colour (linear RGBA): the colour of the ridges' sides; furrows are darker,
    /// ridge tops lighter.
    pub color: [f32; 4],
    /// Side of every map in pixels.
    pub size: u32,
    /// Relief: how deep furrows and cracks look in the normal map (0 flat, 1 the style's
    /// own, up to 4).
    pub depth: f32,
}

/// The parameters a leaf texture set is made from: its cache key.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LeafParams {
    /// The silhouette and its veins.
    pub shape: LeafShape,
    /// Side of every map in pixels.
    pub size: u32,
}

/// One material's maps.
#[derive(Clone, Debug, PartialEq)]
pub struct TextureSet {
    /// Base colour (sRGB; RGBA with the silhouette in alpha for leaves).
    pub color: Arc<Texture>,
    /// Tangent-space normal map (glTF convention: +X right, +Y up in the image).
    pub normal: Arc<Texture>,
    /// glTF metallic-roughness map: roughness in G, metalness (0) in B.
    pub roughness: Arc<Texture>,
}

type Cell = Arc<OnceLock<Result<Arc<TextureSet>, String>>>;

/// Texture sets by parameter set, each generated once however many sessions ask for it at
/// the same time: the first asker generates, the others wait for its result (one
/// generate-once cell per key, the map locked only to find the cell).
#[derive(Default)]
pub struct TextureCache {
    cells: Mutex<HashMap<String, Cell>>,
    generated: AtomicU64,
}

impl TextureCache {
    /// The process's cache, shared by every session and tree.
    pub fn global() -> &'static TextureCache {
        static CACHE: OnceLock<TextureCache> = OnceLock::new();
        CACHE.get_or_init(TextureCache::default)
    }

    /// How many sets this cache has generated (not counting the ones it handed out again).
    pub fn generated(&self) -> u64 {
        self.generated.load(Ordering::Relaxed)
    }

    /// The bark set of `params`, generated on first use.
    pub fn bark(&self, params: &BarkParams) -> Result<Arc<TextureSet>, TreeError> {
        self.get(format!("bark {params:?}"), || bark_set(params))
    }

    /// The leaf set of `params`, generated on first use.
    pub fn leaf(&self, params: &LeafParams) -> Result<Arc<TextureSet>, TreeError> {
        self.get(format!("leaf {params:?}"), || leaf_set(params))
    }

    fn get(
        &self,
        key: String,
        make: impl FnOnce() -> Result<TextureSet, TreeError>,
    ) -> Result<Arc<TextureSet>, TreeError> {
        let cell = {
            let mut cells = self.cells.lock().unwrap_or_else(|e| e.into_inner());
            cells.entry(key).or_default().clone()
        };
        cell.get_or_init(|| {
            self.generated.fetch_add(1, Ordering::Relaxed);
            make().map(Arc::new).map_err(|e| e.to_string())
        })
        .clone()
        .map_err(TreeError::Generated)
    }
}

/// The bark set of `params` from the process's cache.
pub fn bark_textures(params: &BarkParams) -> Result<Arc<TextureSet>, TreeError> {
    TextureCache::global().bark(params)
}

/// The leaf set of `params` from the process's cache.
pub fn leaf_textures(params: &LeafParams) -> Result<Arc<TextureSet>, TreeError> {
    TextureCache::global().leaf(params)
}

// ---------------------------------------------------------------------------------------
// Noise: hashed, periodic, cheap.

/// A 32-bit hash of a lattice point and a seed (integer mixing, no tables).
fn hash(x: u32, y: u32, seed: u32) -> u32 {
    let mut h =
        x.wrapping_mul(0x8da6_b343) ^ y.wrapping_mul(0xd816_3841) ^ seed.wrapping_mul(0xcb1a_b31f);
    h ^= h >> 15;
    h = h.wrapping_mul(0x2c1b_3c6d);
    h ^= h >> 12;
    h = h.wrapping_mul(0x297a_2d39);
    h ^ (h >> 15)
}

/// A hash as a number in `[0, 1)`.
fn unit(h: u32) -> f32 {
    (h >> 8) as f32 / (1u32 << 24) as f32
}

/// The largest integer not above `x` (for `|x|` below 2^31), without the `floorf` call that
/// `f32::floor` is on x86-64 without SSE 4.1.
#[inline]
fn floor(x: f32) -> i64 {
    let i = x as i64;
    if (i as f32) > x { i - 1 } else { i }
}

/// `i` modulo `n` in `0..n`, without a division for the values noise lookups meet (one
/// period either side).
#[inline]
fn wrap(i: i64, n: u32) -> u32 {
    let n = i64::from(n);
    if (0..n).contains(&i) {
        i as u32
    } else if (-n..0).contains(&i) {
        (i + n) as u32
    } else if (n..2 * n).contains(&i) {
        (i - n) as u32
    } else {
        i.rem_euclid(n) as u32
    }
}

#[inline]
fn smooth(t: f32) -> f32 {
    t * t * (3.0 - 2.0 * t)
}

#[inline]
fn smoothstep(a: f32, b: f32, x: f32) -> f32 {
    // A product, not a quotient: with constant edges the reciprocal folds away.
    smooth(((x - a) * (1.0 / (b - a))).clamp(0.0, 1.0))
}

/// Periodic value noise in `[0, 1]` with `px x py` lattice cells over the unit square (so it
/// tiles), its lattice values hashed once into a table: a lookup is four loads and a
/// bilinear blend. `(u, v)` may lie outside `[0, 1)`.
struct Lattice {
    px: u32,
    py: u32,
    values: Vec<f32>,
}

impl Lattice {
    fn new(px: u32, py: u32, seed: u32) -> Lattice {
        let values = (0..py)
            .flat_map(|y| (0..px).map(move |x| unit(hash(x, y, seed))))
            .collect();
        Lattice { px, py, values }
    }

    /// The noise along the row at `v`: its two lattice rows and the blend between them
    /// found once, so a lookup is two loads per lattice row and three blends.
    fn row(&self, v: f32) -> LatticeRow<'_> {
        let y = v * self.py as f32;
        let fy = floor(y);
        let iy = wrap(fy, self.py);
        let jy = if iy + 1 == self.py { 0 } else { iy + 1 };
        let px = self.px as usize;
        LatticeRow {
            px: self.px,
            top: &self.values[iy as usize * px..][..px],
            bottom: &self.values[jy as usize * px..][..px],
            ty: smooth(y - fy as f32),
        }
    }
}

/// One row of a [`Lattice`] (see [`Lattice::row`]).
struct LatticeRow<'a> {
    px: u32,
    top: &'a [f32],
    bottom: &'a [f32],
    ty: f32,
}

impl LatticeRow<'_> {
    #[inline]
    fn at(&self, u: f32) -> f32 {
        let x = u * self.px as f32;
        let fx = floor(x);
        let tx = smooth(x - fx as f32);
        let ix = wrap(fx, self.px) as usize;
        let jx = if ix + 1 == self.px as usize {
            0
        } else {
            ix + 1
        };
        let top = self.top[ix] + (self.top[jx] - self.top[ix]) * tx;
        let bottom = self.bottom[ix] + (self.bottom[jx] - self.bottom[ix]) * tx;
        top + (bottom - top) * self.ty
    }
}

/// Periodic fractal value noise in `[0, 1]`: octave `o` has `2^o` times the lattice cells
/// of the first, half its amplitude and its own seed.
struct Fractal {
    octaves: Vec<Lattice>,
    norm: f32,
}

impl Fractal {
    fn new(px: u32, py: u32, octaves: u32, seed: u32) -> Fractal {
        let octaves: Vec<Lattice> = (0..octaves)
            .map(|o| Lattice::new(px << o, py << o, seed + o))
            .collect();
        let weight: f32 = (0..octaves.len()).map(|o| 0.5f32.powi(o as i32)).sum();
        Fractal {
            octaves,
            norm: 1.0 / weight,
        }
    }

    /// The noise along the row at `v` (see [`Lattice::row`]).
    fn row(&self, v: f32) -> FractalRow<'_> {
        FractalRow {
            octaves: self.octaves.iter().map(|o| o.row(v)).collect(),
            norm: self.norm,
        }
    }
}

/// One row of a [`Fractal`].
struct FractalRow<'a> {
    octaves: Vec<LatticeRow<'a>>,
    norm: f32,
}

impl FractalRow<'_> {
    #[inline]
    fn at(&self, u: f32) -> f32 {
        let (mut sum, mut amp) = (0.0, 1.0);
        for octave in &self.octaves {
            sum += amp * octave.at(u);
            amp *= 0.5;
        }
        sum * self.norm
    }
}

/// Periodic cellular (Worley) noise with `nx x ny` cells over the unit square, one feature
/// point per cell, the points hashed once into a table with a border of one cell (wrapped
/// copies), so the 3 x 3 neighbourhood of a cell is nine loads with no wrapping. Distances
/// are measured in cell units (cells wider in `v` than in `u` are stretched along `v`).
struct Cells {
    nx: u32,
    ny: u32,
    /// `(nx + 2) x (ny + 2)` points: feature position inside its cell, and the cell's hash.
    points: Vec<(f32, f32, u32)>,
}

impl Cells {
    fn new(nx: u32, ny: u32, seed: u32) -> Cells {
        let points = (-1..=ny as i64)
            .flat_map(|gy| {
                (-1..=nx as i64).map(move |gx| {
                    let h = hash(wrap(gx, nx), wrap(gy, ny), seed);
                    (0.1 + 0.8 * unit(h), 0.1 + 0.8 * unit(h.rotate_left(16)), h)
                })
            })
            .collect();
        Cells { nx, ny, points }
    }

    /// The nearest and second-nearest feature distances at `(u, v)` and the nearest cell's
    /// hash.
    #[inline]
    fn at(&self, u: f32, v: f32) -> (f32, f32, u32) {
        let (x, y) = (
            u.rem_euclid_unit() * self.nx as f32,
            v.rem_euclid_unit() * self.ny as f32,
        );
        let cx = (x as u32).min(self.nx - 1);
        let cy = (y as u32).min(self.ny - 1);
        let (rx, ry) = (x - cx as f32, y - cy as f32);
        let stride = self.nx as usize + 2;
        let (mut f1, mut f2, mut id) = (f32::MAX, f32::MAX, 0);
        for dy in 0..3 {
            let row = &self.points[(cy as usize + dy) * stride + cx as usize..][..3];
            let oy = dy as f32 - 1.0 - ry;
            for (dx, &(px, py, h)) in row.iter().enumerate() {
                let ex = dx as f32 - 1.0 - rx + px;
                let ey = oy + py;
                let d = ex * ex + ey * ey;
                if d < f1 {
                    f2 = f1;
                    f1 = d;
                    id = h;
                } else if d < f2 {
                    f2 = d;
                }
            }
        }
        (f1.sqrt(), f2.sqrt(), id)
    }
}

/// A coordinate wrapped into `[0, 1)`.
trait UnitWrap {
    fn rem_euclid_unit(self) -> Self;
}

impl UnitWrap for f32 {
    #[inline]
    fn rem_euclid_unit(self) -> f32 {
        if (0.0..1.0).contains(&self) {
            self
        } else {
            let f = self - floor(self) as f32;
            if f < 1.0 { f } else { 0.0 }
        }
    }
}

// ---------------------------------------------------------------------------------------
// Bark.

/// What one bark pixel is made of: height in `[0, 1]`, a colour factor and roughness.
struct Sample {
    height: f32,
    shade: [f32; 3],
    roughness: f32,
}

/// `a` blended towards `b` by `t`.
fn mix(a: [f32; 3], b: [f32; 3], t: f32) -> [f32; 3] {
    [0, 1, 2].map(|i| a[i] + (b[i] - a[i]) * t)
}

/// Fills the bark maps of an `n x n` tile in parallel rows: `row(v)` prepares what a row
/// shares and returns the sample at each `u` of it.
fn fill_bark<R, S>(n: usize, row: R) -> (Vec<f32>, Vec<u8>, Vec<u8>)
where
    R: Fn(f32) -> S + Sync,
    S: Fn(f32) -> Sample,
{
    let mut heights = vec![0.0f32; n * n];
    let mut color = vec![0u8; n * n * 3];
    let mut rough = vec![0u8; n * n * 3];
    heights
        .par_chunks_mut(n)
        .zip(color.par_chunks_mut(n * 3))
        .zip(rough.par_chunks_mut(n * 3))
        .enumerate()
        .for_each(|(y, ((h, c), r))| {
            let sample = row((y as f32 + 0.5) / n as f32);
            for x in 0..n {
                let s = sample((x as f32 + 0.5) / n as f32);
                h[x] = s.height;
                for i in 0..3 {
                    c[x * 3 + i] = linear_to_srgb8(s.shade[i]);
                }
                r[x * 3 + 1] = (s.roughness.clamp(0.0, 1.0) * 255.0 + 0.5) as u8;
            }
        });
    (heights, color, rough)
}

/// Each style's pattern over the `n x n` tile: heights, colour and roughness pixels. The
/// noise tables are made once per call, the per-row terms once per row.
fn bark_pixels(style: BarkStyle, color: [f32; 4], n: usize) -> (Vec<f32>, Vec<u8>, Vec<u8>) {
    let c = [color[0], color[1], color[2]];
    let l = 0.3 * c[0] + 0.55 * c[1] + 0.15 * c[2];
    let grey = |k: f32| [l * k, l * k, l * k];
    match style {
        BarkStyle::Furrowed => {
            // Oak: long ridges between deep vertical furrows. Cells 3.5 times taller than
            // wide, their borders wandering with a low noise, are the ridges; the furrows are
            // the borders (F2 - F1 small), with small cross-cracks on the ridges.
            let (warp, ridges) = (Lattice::new(4, 3, 11), Cells::new(8, 2, 12));
            let (cracks, fibre) = (Cells::new(16, 6, 13), Fractal::new(64, 6, 2, 14));
            let light = grey(1.5);
            fill_bark(n, |v| {
                let (warp, fibre) = (warp.row(v), fibre.row(v));
                let (ridges, cracks) = (&ridges, &cracks);
                move |u| {
                    let wu = u + 0.05 * (warp.at(u) - 0.5);
                    let (f1, f2, id) = ridges.at(wu, v);
                    let ridge = smoothstep(0.02, 0.6, f2 - f1);
                    let (g1, g2, _) = cracks.at(u, v);
                    let crack = smoothstep(0.0, 0.1, g2 - g1);
                    let height =
                        (0.7 * ridge.sqrt() + 0.12 * unit(id) * ridge + 0.16 * fibre.at(u))
                            * (0.94 + 0.06 * crack);
                    let top = mix(c, light, 0.35 * smoothstep(0.6, 0.95, height));
                    Sample {
                        height,
                        shade: mix([0.0; 3], top, 0.28 + 0.9 * height),
                        roughness: 0.97 - 0.12 * height,
                    }
                }
            })
        }
        BarkStyle::Plated => {
            // Pine: irregular flat plates split by narrow dark cracks, each plate its own
            // tint and tilt, flaking into smaller scales.
            let (warp_u, warp_v) = (Lattice::new(5, 5, 21), Lattice::new(5, 5, 22));
            let (plates, scales) = (Cells::new(5, 4, 23), Cells::new(12, 9, 24));
            let grain = Fractal::new(32, 32, 2, 25);
            let warm = [c[0] * 1.35, c[1] * 1.05, c[2] * 0.85];
            let light = grey(1.3);
            fill_bark(n, |v| {
                let (warp_u, warp_v, grain) = (warp_u.row(v), warp_v.row(v), grain.row(v));
                let (plates, scales) = (&plates, &scales);
                move |u| {
                    let wu = u + 0.04 * (warp_u.at(u) - 0.5);
                    let wv = v + 0.04 * (warp_v.at(u) - 0.5);
                    let (f1, f2, id) = plates.at(wu, wv);
                    let crack = smoothstep(0.0, 0.14, f2 - f1);
                    let (g1, g2, sub) = scales.at(wu, wv);
                    let scale = smoothstep(0.0, 0.08, g2 - g1);
                    let tilt = 0.15 * (1.0 - f1);
                    let grain = grain.at(u);
                    let height = crack
                        * (0.5
                            + 0.2 * unit(id)
                            + tilt
                            + 0.12 * scale
                            + 0.06 * unit(sub)
                            + 0.06 * grain);
                    let plate = mix(c, warm, unit(id.rotate_left(7)));
                    let plate = mix(plate, light, 0.25 * unit(sub));
                    Sample {
                        height,
                        shade: mix(
                            [0.0; 3],
                            plate,
                            0.15 + 0.85 * crack * (0.8 + 0.2 * scale) + 0.1 * grain,
                        ),
                        roughness: 0.9 - 0.15 * crack,
                    }
                }
            })
        }
        BarkStyle::Smooth => {
            // Beech, birch: smooth mottled bark with lenticels, short dark horizontal marks,
            // one per cell at a random place and length.
            let mottle = Fractal::new(6, 6, 3, 31);
            let light = grey(1.25);
            let dark = [c[0] * 0.18, c[1] * 0.15, c[2] * 0.13];
            fill_bark(n, |v| {
                let mottle = mottle.row(v);
                let gy = v * 22.0;
                let cy = floor(gy) as f32;
                move |u| {
                    let mottle = mottle.at(u);
                    let gx = u * 7.0;
                    let cx = floor(gx) as f32;
                    let h = hash(wrap(cx as i64, 7), wrap(cy as i64, 22), 32);
                    let (px, py) = (0.3 + 0.4 * unit(h), 0.3 + 0.4 * unit(h.rotate_left(11)));
                    let half = 0.15 + 0.3 * unit(h.rotate_left(22));
                    let dx = ((gx - cx) - px) / half;
                    let dy = ((gy - cy) - py) / 0.09;
                    let mark = if unit(h.rotate_left(5)) < 0.75 {
                        1.0 - smoothstep(0.6, 1.0, dx * dx + dy * dy)
                    } else {
                        0.0
                    };
                    let skin = mix(c, light, 0.3 * mottle);
                    Sample {
                        height: 0.55 + 0.25 * mottle - 0.35 * mark,
                        shade: mix(skin, dark, mark),
                        roughness: 0.55 + 0.3 * mark + 0.1 * mottle,
                    }
                }
            })
        }
        BarkStyle::Fibrous => {
            // Willow: interlaced fibrous ridges, long diamond-shaped furrows and fine
            // vertical fibres.
            let (warp, ridges) = (Lattice::new(3, 2, 41), Cells::new(11, 2, 42));
            let fibres = Fractal::new(96, 4, 3, 43);
            let light = grey(1.4);
            fill_bark(n, |v| {
                let (warp, fibres, ridges) = (warp.row(v), fibres.row(v), &ridges);
                let sway = 0.03 * (v * TAU * 2.0).sin();
                let wave = 0.01 * (v * 40.0).sin();
                move |u| {
                    let wu = u + 0.06 * (warp.at(u) - 0.5) + sway;
                    let (f1, f2, id) = ridges.at(wu, v);
                    let ridge = smoothstep(0.0, 0.35, f2 - f1);
                    let fibres = fibres.at(u + wave);
                    let height =
                        0.55 * ridge + 0.35 * fibres * (0.4 + 0.6 * ridge) + 0.1 * unit(id);
                    Sample {
                        height,
                        shade: mix([0.0; 3], mix(c, light, 0.25 * fibres), 0.3 + 0.8 * height),
                        roughness: 0.93 - 0.1 * height,
                    }
                }
            })
        }
    }
}

/// Normal-map strength of each style at relief 1: the height change across one texel of a
/// 512 px map is multiplied by this (and scaled with the map size).
fn relief(style: BarkStyle) -> f32 {
    match style {
        BarkStyle::Furrowed => 7.0,
        BarkStyle::Plated => 6.0,
        BarkStyle::Smooth => 2.0,
        BarkStyle::Fibrous => 5.0,
    }
}

/// The three maps of one material as raw pixels, before PNG encoding.
#[derive(Clone, Debug, PartialEq)]
pub struct Maps {
    /// Side of every map in pixels.
    pub size: u32,
    /// Base colour pixels, `channels` bytes each (sRGB).
    pub color: Vec<u8>,
    /// Bytes per base-colour pixel: 3 (RGB) or 4 (RGBA).
    pub channels: u8,
    /// Tangent-space normal map, RGB.
    pub normal: Vec<u8>,
    /// Metallic-roughness map, RGB: roughness in G, R and B zero.
    pub roughness: Vec<u8>,
}

/// The bark set of `params`: its maps generated ([`bark_maps`]) and PNG-encoded.
pub fn bark_set(params: &BarkParams) -> Result<TextureSet, TreeError> {
    encode_maps("bark", bark_maps(params))
}

/// The bark maps of `params`: every pixel's sample in parallel rows, the normal map from
/// the height field (wrapping, as the texture tiles).
pub fn bark_maps(params: &BarkParams) -> Maps {
    let n = params.size.clamp(16, 4096) as usize;
    let (heights, color, rough) = bark_pixels(params.style, params.color, n);
    let strength = relief(params.style) * params.depth * n as f32 / 512.0;
    let normal = normal_map(&heights, n, strength, true);
    Maps {
        size: n as u32,
        color,
        channels: 3,
        normal,
        roughness: rough,
    }
}

/// A tangent-space normal map of an `n x n` height field: central differences (wrapping
/// around the edges when `wrap`, else clamped), `strength` times the height change per texel.
fn normal_map(h: &[f32], n: usize, strength: f32, wrap: bool) -> Vec<u8> {
    let mut out = vec![0u8; n * n * 3];
    // The neighbour before and after index `i` of a row or column.
    let before = |i: usize| match (i, wrap) {
        (0, true) => n - 1,
        (0, false) => 0,
        _ => i - 1,
    };
    let after = |i: usize| match (i + 1 == n, wrap) {
        (true, true) => 0,
        (true, false) => i,
        _ => i + 1,
    };
    let k = 0.5 * strength;
    out.par_chunks_mut(n * 3).enumerate().for_each(|(y, row)| {
        let here = &h[y * n..][..n];
        let up = &h[before(y) * n..][..n];
        let down = &h[after(y) * n..][..n];
        for (x, px) in row.chunks_exact_mut(3).enumerate() {
            let dx = (here[after(x)] - here[before(x)]) * k;
            // Image rows grow downwards; +Y of the normal map points up the image.
            let dy = (up[x] - down[x]) * k;
            let inv = 1.0 / (dx * dx + dy * dy + 1.0).sqrt();
            let nrm = [-dx * inv, -dy * inv, inv];
            for i in 0..3 {
                px[i] = ((nrm[i] * 0.5 + 0.5) * 255.0 + 0.5) as u8;
            }
        }
    });
    out
}

/// Encodes the three maps of a set in parallel as PNG, named `<what> color`, `<what> normal`
/// and `<what> roughness`.
pub fn encode_maps(what: &str, maps: Maps) -> Result<TextureSet, TreeError> {
    let n = maps.size;
    let jobs = [
        (format!("{what} color"), maps.channels, maps.color),
        (format!("{what} normal"), 3, maps.normal),
        (format!("{what} roughness"), 3, maps.roughness),
    ];
    let mut maps = jobs
        .into_par_iter()
        .map(|(name, channels, px)| {
            Texture::from_pixels_fast(name, n, n, channels, &px).map(Arc::new)
        })
        .collect::<Result<Vec<_>, _>>()?
        .into_iter();
    let mut next = || {
        maps.next()
            .ok_or_else(|| TreeError::Generated("a map is missing".into()))
    };
    Ok(TextureSet {
        color: next()?,
        normal: next()?,
        roughness: next()?,
    })
}

// ---------------------------------------------------------------------------------------
// Leaves.

/// What a leaf texture holds at one pixel: inside the silhouette or not, a height (veins
/// sunk, the blade domed) and a shade (veins lighter).
struct LeafPixel {
    inside: bool,
    height: f32,
    shade: f32,
    roughness: f32,
}

/// Half-width of an ovate blade at `t` along it (0 at the stalk end, 1 at the tip).
fn ovate(t: f32) -> f32 {
    if !(0.0..=1.0).contains(&t) {
        return 0.0;
    }
    0.44 * (PI * t.powf(0.8)).sin().max(0.0).powf(0.85) * (1.0 - 0.25 * t)
}

/// Half-width of a blade of `shape` at `t` along it, for the shapes with a midrib.
fn blade_half_width(shape: LeafShape, t: f32) -> f32 {
    if !(0.0..=1.0).contains(&t) {
        return 0.0;
    }
    match shape {
        LeafShape::Lobed => {
            // Oak: four to five rounded lobes a side, deep sinuses between them.
            let outline = 0.42 * (PI * t.powf(0.85)).sin().max(0.0).powf(0.6) * (1.0 - 0.15 * t);
            let lobes = 0.5 + 0.5 * (TAU * 4.5 * t - 0.6).cos();
            outline * (0.55 + 0.45 * lobes.sqrt())
        }
        LeafShape::Lanceolate => 0.14 * (PI * t.powf(0.75)).sin().max(0.0).powf(0.9),
        _ => ovate(t),
    }
}

/// The leaf pixel at `(x, v)`: `x` across the card in `[-0.5, 0.5]`, `v` from the stalk (0)
/// to the far edge (1); `w` is the blade's half-width in this row (shapes with a midrib:
/// [`blade_half_width`] at `(v - 0.12) / 0.86`), `needles` the spray's needles.
fn leaf_pixel(shape: LeafShape, x: f32, v: f32, w: f32, needles: &Needles) -> LeafPixel {
    let outside = LeafPixel {
        inside: false,
        height: 0.0,
        shade: 1.0,
        roughness: 0.6,
    };
    let stalk = v < 0.13 && x.abs() < 0.014;
    match shape {
        LeafShape::Needles => needles.pixel(x, v),
        LeafShape::Palmate => {
            // Maple: five pointed lobes around the top of the stalk, main veins radiating
            // to their tips.
            let (cx, cy) = (0.0, 0.4);
            let (dx, dy) = (x, v - cy);
            let r = (dx * dx + dy * dy).sqrt();
            let phi = dy.atan2(dx); // pi/2 is up the card.
            let lobe_axes = [PI / 2.0, PI / 2.0 - 0.95, PI / 2.0 + 0.95, -0.25, PI + 0.25];
            let lobe_len = [0.58, 0.5, 0.5, 0.36, 0.36];
            let (mut reach, mut vein) = (0.0f32, f32::MAX);
            for (axis, len) in lobe_axes.iter().zip(lobe_len) {
                let off = angle_diff(phi, *axis);
                // Only the lobes within 0.62 rad reach this far round (the others are 0).
                if off.abs() < 0.62 {
                    let lobe = len * (1.0 - off.abs() / 0.62).powf(0.8);
                    let teeth = 1.0 - 0.06 * (0.5 + 0.5 * (off * 28.0).cos());
                    reach = reach.max(lobe * teeth);
                }
                vein = vein.min(off.abs() * r);
            }
            let reach = reach.max(0.12);
            let _ = cx;
            let inside = stalk || (r < reach && v > 0.12);
            if !inside {
                return outside;
            }
            let veins = 1.0 - smoothstep(0.004, 0.012, vein);
            let side = side_veins(dx.abs() + 0.3 * r, r, 0.09);
            let edge = r / reach;
            LeafPixel {
                inside,
                height: 0.6 * (1.0 - edge * edge) - 0.5 * veins - 0.2 * side,
                shade: if stalk {
                    1.0
                } else {
                    0.82 + 0.16 * veins + 0.05 * side - 0.1 * edge
                },
                roughness: 0.5 + 0.2 * veins,
            }
        }
        _ => {
            let inside = stalk || x.abs() < w;
            if !inside {
                return outside;
            }
            let across = x.abs() / w.max(1e-3);
            let midrib = 1.0 - smoothstep(0.006, 0.014, x.abs());
            let slope = if shape == LeafShape::Lanceolate {
                3.0
            } else {
                0.9
            };
            let spacing = if shape == LeafShape::Lanceolate {
                0.06
            } else {
                0.1
            };
            let side =
                side_veins(v - x.abs() * slope, x.abs(), spacing) * smoothstep(1.0, 0.8, across);
            let veins = midrib.max(side);
            LeafPixel {
                inside,
                height: 0.5 * (1.0 - across * across) - 0.5 * midrib - 0.3 * side,
                shade: if stalk {
                    1.0
                } else {
                    0.8 + 0.18 * veins - 0.1 * across
                },
                roughness: 0.5 + 0.2 * veins,
            }
        }
    }
}

/// Secondary veins: thin lines where `along` is a multiple of `spacing`, fading with
/// distance `out` from the midrib.
fn side_veins(along: f32, out: f32, spacing: f32) -> f32 {
    let f = along / spacing;
    let f = f - floor(f) as f32;
    let d = f.min(1.0 - f) * spacing;
    (1.0 - smoothstep(0.002, 0.006, d)) * (1.0 - smoothstep(0.25, 0.5, out))
}

/// `a - b` wrapped to `[-pi, pi]`.
fn angle_diff(a: f32, b: f32) -> f32 {
    let d = (a - b + PI) / TAU;
    (d - floor(d) as f32) * TAU - PI
}

/// One needle of a spray: its direction `(sin, cos)` of its angle from the twig, where it
/// leaves the twig, its length and its hash.
#[derive(Clone, Copy)]
struct Needle {
    dir: (f32, f32),
    t0: f32,
    len: f32,
    h: u32,
}

/// A needle spray: a twig up the middle of the card with needles leaving it on both sides
/// at about 50 degrees towards the tip, each a little different in angle and length (the
/// needles of both sides made once, not per pixel).
struct Needles {
    sides: [Vec<Needle>; 2],
}

const NEEDLE_SPACING: f32 = 0.018;
const NEEDLE_COUNT: i64 = 52;

impl Needles {
    fn new() -> Needles {
        let base = 50f32.to_radians();
        let side = |side: u32| {
            (0..=NEEDLE_COUNT as u32)
                .map(|i| {
                    let h = hash(i, side, 51);
                    let angle = base + (unit(h) - 0.5) * 0.35;
                    let t0 = i as f32 * NEEDLE_SPACING;
                    let taper = 1.0 - t0;
                    let len =
                        (0.34 + 0.12 * unit(h.rotate_left(9))) * (0.45 + 0.55 * taper.max(0.0));
                    Needle {
                        dir: angle.sin_cos(),
                        t0,
                        len,
                        h,
                    }
                })
                .collect()
        };
        Needles {
            sides: [side(0), side(1)],
        }
    }

    fn pixel(&self, x: f32, v: f32) -> LeafPixel {
        let twig = x.abs() < 0.012 * (1.2 - v) && v < 0.97;
        if twig {
            return LeafPixel {
                inside: true,
                height: 0.8,
                shade: 0.75,
                roughness: 0.8,
            };
        }
        let needles = &self.sides[usize::from(x < 0.0)];
        let ax = x.abs();
        // The needle through this pixel starts at t0 = v - |x| cot(angle); look at the
        // nearest starts (cot 50 degrees = 0.8391).
        let guess = ((v - ax * 0.839_099_6) / NEEDLE_SPACING).round() as i64;
        for i in (guess - 2).max(1)..=(guess + 2).min(NEEDLE_COUNT) {
            let nd = needles[i as usize];
            let (dx, dy) = nd.dir;
            let (px, py) = (ax, v - nd.t0);
            let along = px * dx + py * dy;
            if along < 0.0 || along > nd.len {
                continue;
            }
            let across = (px * dy - py * dx).abs();
            let half = 0.0055 * (1.0 - 0.7 * along / nd.len);
            if across < half {
                let k = across / half;
                return LeafPixel {
                    inside: true,
                    height: 0.6 * (1.0 - k * k),
                    shade: 0.85 + 0.12 * (1.0 - k) + 0.03 * unit(nd.h),
                    roughness: 0.45,
                };
            }
        }
        LeafPixel {
            inside: false,
            height: 0.0,
            shade: 1.0,
            roughness: 0.6,
        }
    }
}

/// The leaf set of `params`: its maps generated ([`leaf_maps`]) and PNG-encoded.
pub fn leaf_set(params: &LeafParams) -> Result<TextureSet, TreeError> {
    encode_maps("leaf", leaf_maps(params))
}

/// The leaf maps of `params`: a near-white silhouette (each leaf's vertex colour gives the
/// hue) with lighter veins, alpha 255 inside and 0 outside for masking; the normal map of
/// the domed blade and its sunken veins; roughness.
pub fn leaf_maps(params: &LeafParams) -> Maps {
    let n = params.size.clamp(16, 4096) as usize;
    let mottle = Fractal::new(8, 8, 2, 61);
    let needles = Needles::new();
    let mut heights = vec![0.0f32; n * n];
    let mut color = vec![0u8; n * n * 4];
    let mut rough = vec![0u8; n * n * 3];
    heights
        .par_chunks_mut(n)
        .zip(color.par_chunks_mut(n * 4))
        .zip(rough.par_chunks_mut(n * 3))
        .enumerate()
        .for_each(|(y, ((h, c), r))| {
            let v = (y as f32 + 0.5) / n as f32;
            let w = blade_half_width(params.shape, (v - 0.12) / 0.86);
            let mottle = mottle.row(v);
            for xi in 0..n {
                let u = (xi as f32 + 0.5) / n as f32;
                let p = leaf_pixel(params.shape, u - 0.5, v, w, &needles);
                let mottle = 0.05 * (mottle.at(u) - 0.5);
                let g = linear_to_srgb8(p.shade + mottle);
                c[xi * 4..xi * 4 + 4].copy_from_slice(&[g, g, g, if p.inside { 255 } else { 0 }]);
                h[xi] = p.height;
                r[xi * 3 + 1] = (p.roughness.clamp(0.0, 1.0) * 255.0 + 0.5) as u8;
            }
        });
    let normal = normal_map(&heights, n, 3.0 * n as f32 / 512.0, false);
    Maps {
        size: n as u32,
        color,
        channels: 4,
        normal,
        roughness: rough,
    }
}

// ---------------------------------------------------------------------------------------
// Files.

/// Reads an image file (PNG, or anything `image` decodes) as a texture called `name`.
pub fn load_png(path: &Path, name: &str) -> Result<Arc<Texture>, TreeError> {
    let bytes = std::fs::read(path).map_err(|e| TreeError::Texture {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    Texture::from_image_bytes(name, &bytes)
        .map(Arc::new)
        .map_err(|e| TreeError::Texture {
            path: path.to_path_buf(),
            message: e.to_string(),
        })
}

/// Linear [0, 1] to an sRGB byte, from a table of 4096 steps (a `powf` per channel and
/// pixel would cost more than the noise).
fn linear_to_srgb8(c: f32) -> u8 {
    static TABLE: OnceLock<Vec<u8>> = OnceLock::new();
    let table = TABLE.get_or_init(|| {
        (0..=4096)
            .map(|i| {
                let c = i as f32 / 4096.0;
                let s = if c <= 0.003_130_8 {
                    c * 12.92
                } else {
                    1.055 * c.powf(1.0 / 2.4) - 0.055
                };
                (s * 255.0 + 0.5) as u8
            })
            .collect()
    });
    table[(c.clamp(0.0, 1.0) * 4096.0 + 0.5) as usize]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn decode(t: &Texture) -> image::RgbaImage {
        image::load_from_memory(&t.png).expect("decodes").to_rgba8()
    }

    fn bark(style: BarkStyle, size: u32) -> BarkParams {
        BarkParams {
            style,
            color: [0.2, 0.12, 0.07, 1.0],
            size,
            depth: 1.0,
        }
    }

    #[test]
    fn sets_are_made_once_per_parameter_set_across_threads() {
        let cache = TextureCache::default();
        let params = [
            bark(BarkStyle::Furrowed, 32),
            bark(BarkStyle::Plated, 32),
            BarkParams {
                color: [0.3, 0.3, 0.3, 1.0],
                ..bark(BarkStyle::Furrowed, 32)
            },
        ];
        let leaf = LeafParams {
            shape: LeafShape::Lobed,
            size: 32,
        };
        // 24 variants, as a forest builds them: in parallel, asking for the same sets.
        let sets: Vec<Vec<Arc<TextureSet>>> = (0..24)
            .into_par_iter()
            .map(|i| {
                vec![
                    cache.bark(&params[i % 3]).expect("bark"),
                    cache.leaf(&leaf).expect("leaf"),
                ]
            })
            .collect();
        assert_eq!(cache.generated(), 4, "three bark sets and one leaf set");
        for (i, s) in sets.iter().enumerate() {
            assert!(
                Arc::ptr_eq(&s[0], &sets[i % 3][0]),
                "variant {i} shares its bark"
            );
            assert!(Arc::ptr_eq(&s[1], &sets[0][1]));
        }
        assert!(
            !Arc::ptr_eq(&sets[0][0], &sets[2][0]),
            "another colour, another set"
        );
        // A new cache makes the same bytes: the sets depend on their parameters only.
        let again = TextureCache::default().bark(&params[1]).expect("bark");
        assert_eq!(again.color.png, sets[1][0].color.png);
        assert_eq!(again.normal.png, sets[1][0].normal.png);
    }

    #[test]
    fn every_bark_style_has_relief_and_tiles() {
        let mut colors = Vec::new();
        for style in [
            BarkStyle::Furrowed,
            BarkStyle::Plated,
            BarkStyle::Smooth,
            BarkStyle::Fibrous,
        ] {
            let set = bark_set(&bark(style, 64)).expect("bark");
            for t in [&set.color, &set.normal, &set.roughness] {
                assert_eq!((t.width, t.height), (64, 64));
            }
            let relief = bark_set(&BarkParams {
                depth: 4.0,
                ..bark(style, 64)
            })
            .expect("bark");
            let normal = decode(&relief.normal);
            // The normal map is not flat, and it points out of the surface everywhere.
            let tilted = normal
                .pixels()
                .filter(|p| (p[0] as i32 - 128).abs() > 12 || (p[1] as i32 - 128).abs() > 12)
                .count();
            assert!(tilted > 64 * 64 / 25, "{style:?}: {tilted} tilted texels");
            assert!(normal.pixels().all(|p| p[2] >= 128), "{style:?}");
            // Tiling: the last column (row) continues into the first as any column does into
            // the next.
            let img = decode(&set.color);
            let g = |x: u32, y: u32| i32::from(img.get_pixel(x % 64, y % 64)[1]);
            for (name, step) in [("around", (1, 0)), ("along", (0, 1))] {
                let diff = |x: u32, y: u32| (g(x, y) - g(x + step.0, y + step.1)).abs();
                let seam: i32 = (0..64)
                    .map(|k| {
                        if step.0 == 1 {
                            diff(63, k)
                        } else {
                            diff(k, 63)
                        }
                    })
                    .sum();
                let inner: i32 = (0..63)
                    .map(|i| {
                        (0..64)
                            .map(|k| if step.0 == 1 { diff(i, k) } else { diff(k, i) })
                            .sum::<i32>()
                    })
                    .sum::<i32>()
                    / 63;
                assert!(
                    seam <= 2 * inner + 64,
                    "{style:?} {name}: seam {seam}, inside {inner}"
                );
            }
            let rough = decode(&set.roughness);
            assert!(
                rough.pixels().all(|p| p[1] > 100 && p[2] == 0),
                "{style:?}: rough, not metal"
            );
            colors.push(set.color.png.clone());
        }
        colors.dedup();
        assert_eq!(colors.len(), 4, "four different patterns");
    }

    #[test]
    fn furrows_run_along_the_branch() {
        // Oak furrows are vertical: heights change faster around the branch (x) than along
        // it (y).
        let set = bark_set(&bark(BarkStyle::Furrowed, 128)).expect("bark");
        let img = decode(&set.color);
        let (mut dx, mut dy) = (0i64, 0i64);
        for y in 0..127 {
            for x in 0..127 {
                let g = |x, y| i64::from(img.get_pixel(x, y)[1]);
                dx += (g(x + 1, y) - g(x, y)).abs();
                dy += (g(x, y + 1) - g(x, y)).abs();
            }
        }
        assert!(dx > dy * 3 / 2, "around {dx}, along {dy}");
    }

    #[test]
    fn leaf_silhouettes_are_masks_of_their_shape() {
        let mut opaque = Vec::new();
        for shape in [
            LeafShape::Ovate,
            LeafShape::Lobed,
            LeafShape::Lanceolate,
            LeafShape::Palmate,
            LeafShape::Needles,
        ] {
            let set = leaf_set(&LeafParams { shape, size: 128 }).expect("leaf");
            let img = decode(&set.color);
            assert!(
                img.pixels().all(|p| p[3] == 0 || p[3] == 255),
                "{shape:?}: a binary mask"
            );
            assert_eq!(
                img.get_pixel(64, 4)[3],
                255,
                "{shape:?}: the stalk is opaque"
            );
            assert_eq!(img.get_pixel(1, 1)[3], 0, "{shape:?}: the corner is clear");
            let n = img.pixels().filter(|p| p[3] == 255).count();
            opaque.push(n);
            let normal = decode(&set.normal);
            assert!(
                normal.pixels().any(|p| (p[0] as i32 - 128).abs() > 20),
                "{shape:?}: veins and dome in the normal map"
            );
        }
        // Willow leaves are narrow, oak leaves lobed (less than the ovate blade), needles thin.
        assert!(opaque[2] * 2 < opaque[0], "{opaque:?}");
        assert!(opaque[1] < opaque[0], "{opaque:?}");
        assert!(opaque[4] < opaque[0], "{opaque:?}");
        // The oak outline goes in and out: the half-width along the blade has several
        // local minima (the sinuses).
        let w: Vec<f32> = (1..100)
            .map(|i| blade_half_width(LeafShape::Lobed, i as f32 / 100.0))
            .collect();
        let sinuses = w.windows(3).filter(|s| s[1] < s[0] && s[1] < s[2]).count();
        assert!(sinuses >= 3, "{sinuses} sinuses");
        assert_eq!(blade_half_width(LeafShape::Ovate, -0.1), 0.0);
        assert!(blade_half_width(LeafShape::Ovate, 1.0) < 0.01);
    }

    #[test]
    fn veins_are_lighter_in_colour() {
        let set = leaf_set(&LeafParams {
            shape: LeafShape::Ovate,
            size: 256,
        })
        .expect("leaf");
        let img = decode(&set.color);
        // Along the midrib vs a little beside it.
        let (mut rib, mut blade) = (0u32, 0u32);
        for y in 100..200 {
            rib += u32::from(img.get_pixel(128, y)[0]);
            blade += u32::from(img.get_pixel(140, y)[0]);
        }
        assert!(rib > blade, "midrib {rib} vs blade {blade}");
    }

    /// Cellular noise by definition: hash every neighbouring cell at each lookup.
    fn cellular_reference(u: f32, v: f32, nx: u32, ny: u32, seed: u32) -> (f32, f32, u32) {
        let (x, y) = (u * nx as f32, v * ny as f32);
        let (cx, cy) = (x.floor() as i64, y.floor() as i64);
        let (mut f1, mut f2, mut id) = (f32::MAX, f32::MAX, 0);
        for gy in cy - 1..=cy + 1 {
            for gx in cx - 1..=cx + 1 {
                let h = hash(wrap(gx, nx), wrap(gy, ny), seed);
                let fx = gx as f32 + 0.1 + 0.8 * unit(h);
                let fy = gy as f32 + 0.1 + 0.8 * unit(h.rotate_left(16));
                let d = (fx - x).powi(2) + (fy - y).powi(2);
                if d < f1 {
                    (f2, f1, id) = (f1, d, h);
                } else if d < f2 {
                    f2 = d;
                }
            }
        }
        (f1.sqrt(), f2.sqrt(), id)
    }

    #[test]
    fn cell_tables_give_the_cellular_noise_of_the_hashes() {
        for (nx, ny, seed) in [(8, 2, 12), (5, 4, 23), (16, 6, 13), (1, 1, 3)] {
            let cells = Cells::new(nx, ny, seed);
            for i in 0..200 {
                // Inside the tile, and a little outside it (warped lookups).
                let u = i as f32 / 173.0 - 0.07;
                let v = (i * 37 % 200) as f32 / 190.0 - 0.03;
                let (f1, f2, id) = cells.at(u, v);
                let (r1, r2, rid) =
                    cellular_reference(u.rem_euclid(1.0), v.rem_euclid(1.0), nx, ny, seed);
                assert!((f1 - r1).abs() < 1e-4 && (f2 - r2).abs() < 1e-4, "{u} {v}");
                assert_eq!(id, rid, "{u} {v}");
                assert!(f1 <= f2);
            }
        }
    }

    #[test]
    fn lattice_noise_interpolates_its_hashes_and_tiles() {
        let lattice = Lattice::new(4, 3, 11);
        for (x, y) in [(0u32, 0u32), (3, 2), (1, 2)] {
            let at = lattice.row(y as f32 / 3.0).at(x as f32 / 4.0);
            assert!((at - unit(hash(x, y, 11))).abs() < 1e-6, "{x} {y}");
        }
        for i in 0..50 {
            let (u, v) = (i as f32 / 47.0, (i * 7 % 50) as f32 / 53.0);
            let (a, b) = (lattice.row(v).at(u), lattice.row(v - 1.0).at(u + 1.0));
            assert!((a - b).abs() < 1e-4, "periodic at {u} {v}");
            assert!((0.0..=1.0).contains(&a));
        }
        let fractal = Fractal::new(6, 6, 3, 31);
        let row = fractal.row(0.3);
        assert!((0..100).all(|i| (0.0..=1.0).contains(&row.at(i as f32 / 99.0))));
    }

    #[test]
    fn floor_is_the_floor() {
        for x in [-2.5f32, -1.0, -0.25, 0.0, 0.25, 1.0, 3.75, 511.5] {
            assert_eq!(floor(x), x.floor() as i64, "{x}");
        }
    }

    #[test]
    fn wrap_is_the_euclidean_remainder() {
        for n in [1u32, 2, 7, 22] {
            for i in -100i64..100 {
                assert_eq!(wrap(i, n), i.rem_euclid(i64::from(n)) as u32, "{i} mod {n}");
            }
        }
    }

    #[test]
    fn srgb_bytes() {
        assert_eq!(linear_to_srgb8(0.0), 0);
        assert_eq!(linear_to_srgb8(1.0), 255);
        assert_eq!(linear_to_srgb8(0.214_041_14), 128);
    }

    #[test]
    fn missing_files_name_the_path() {
        let e = load_png(Path::new("/nonexistent/leaf.png"), "leaf").expect_err("missing");
        assert!(e.to_string().contains("/nonexistent/leaf.png"), "{e}");
    }
}
