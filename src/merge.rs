//! `pge merge`: the tiles of a world directory (written by `pge-world`) as one glb, every
//! variant mesh written once and instanced across the tiles. Tiles may be standalone glbs or
//! refer to the world's shared variants (`variants.bin`, by a relative URI): those are read
//! once, however many tiles place them.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::{Context, bail};
use clap::Args;
use glam::{Mat4, Vec2, Vec3, Vec4};
use gltf::Gltf;
use pge_engine::export::{ExportMeta, Instancing};
use pge_engine::geometry::{
    AlphaMode, DiffuseTransmission, InstanceGroup, InstanceTransform, Material, Mesh, Model,
    PlacementLeaves, Primitive, Texture,
};
use serde_json::{Map, Value};

use crate::output::write_atomically;
use crate::run::InstancingArg;

/// Arguments of `pge merge`.
#[derive(Args, Debug)]
pub struct MergeArgs {
    /// The world directory: `DIR/world.json` and `DIR/tiles/I_J.glb`.
    pub dir: PathBuf,
    /// The .glb to write (default: DIR/world.glb).
    #[arg(short, long, value_name = "OUT")]
    pub output: Option<PathBuf>,
    /// Only the tiles of this rectangle, corners included: I0,J0 to I1,J1.
    #[arg(long, value_name = "I0,J0,I1,J1", value_parser = parse_rect)]
    pub rect: Option<[u64; 4]>,
    /// How the trees are written: gpu (EXT_mesh_gpu_instancing) or nodes.
    #[arg(long, value_enum, default_value_t = InstancingArg::Gpu)]
    pub instancing: InstancingArg,
}

fn parse_rect(s: &str) -> Result<[u64; 4], String> {
    let bad = || format!("'{s}' is not I0,J0,I1,J1 (four integers >= 0, I0 <= I1, J0 <= J1)");
    let v: Vec<u64> = s
        .split(',')
        .map(|x| x.trim().parse().map_err(|_| bad()))
        .collect::<Result<_, _>>()?;
    match v[..] {
        [i0, j0, i1, j1] if i0 <= i1 && j0 <= j1 => Ok([i0, j0, i1, j1]),
        _ => Err(bad()),
    }
}

/// A tile as the manifest lists it.
struct TileEntry {
    i: u64,
    j: u64,
    file: String,
    sha256: String,
}

/// What `pge merge` reads from `world.json`.
struct Manifest {
    seed: u64,
    params: Vec<(String, Value)>,
    tiles: Vec<TileEntry>,
    /// The shared variants' binary file, its SHA-256 and their description, when the tiles
    /// refer to them.
    variants: Option<(String, String, Option<String>)>,
}

/// The manifest of `dir`; an error saying what to do when it is not a complete world.
fn read_manifest(dir: &Path) -> anyhow::Result<Manifest> {
    let path = dir.join("world.json");
    let text = std::fs::read_to_string(&path)
        .with_context(|| format!("{}: no world here (run pge-world first)", path.display()))?;
    let world: Value = serde_json::from_str(&text)
        .with_context(|| format!("{}: not a world manifest", path.display()))?;
    let bad = |what: &str| anyhow::anyhow!("{}: {what}", path.display());
    if world.get("format").and_then(Value::as_str) != Some("pge-world/1") {
        return Err(bad("not a pge-world/1 manifest"));
    }
    if world.get("complete").and_then(Value::as_bool) != Some(true) {
        return Err(bad(
            "the world is not complete: run pge-world again on this directory to finish it",
        ));
    }
    let seed = world
        .get("seed")
        .and_then(Value::as_u64)
        .ok_or_else(|| bad("no seed"))?;
    let params = match world.get("params") {
        Some(Value::Object(m)) => m.iter().map(|(k, v)| (k.clone(), v.clone())).collect(),
        _ => Vec::new(),
    };
    let mut tiles = Vec::new();
    for t in world
        .get("tiles")
        .and_then(Value::as_array)
        .ok_or_else(|| bad("no tiles"))?
    {
        let field = |k: &str| t.get(k).ok_or_else(|| bad(&format!("a tile without {k}")));
        let number = |k: &str| {
            field(k)?
                .as_u64()
                .ok_or_else(|| bad(&format!("a tile's {k} is not an integer")))
        };
        let text = |k: &str| {
            field(k)?
                .as_str()
                .map(str::to_string)
                .ok_or_else(|| bad(&format!("a tile's {k} is not a string")))
        };
        tiles.push(TileEntry {
            i: number("i")?,
            j: number("j")?,
            file: text("file")?,
            sha256: text("sha256")?,
        });
    }
    let variants = match world.get("variants") {
        None | Some(Value::Null) => None,
        Some(v) => {
            let text = |k: &str| {
                v.get(k)
                    .and_then(Value::as_str)
                    .map(str::to_string)
                    .ok_or_else(|| bad(&format!("the variants' {k} is not a string")))
            };
            Some((text("file")?, text("sha256")?, text("description").ok()))
        }
    };
    Ok(Manifest {
        seed,
        params,
        tiles,
        variants,
    })
}

/// The SHA-256 (FIPS 180-4) of `data` as 64 hex digits, as `pge-world` records it. Written
/// here rather than taken from a crate: a check of a few files, not a hot path.
pub(crate) fn sha256_hex(data: &[u8]) -> String {
    const K: [u32; 64] = [
        0x428a2f98, 0x71374491, 0xb5c0fbcf, 0xe9b5dba5, 0x3956c25b, 0x59f111f1, 0x923f82a4,
        0xab1c5ed5, 0xd807aa98, 0x12835b01, 0x243185be, 0x550c7dc3, 0x72be5d74, 0x80deb1fe,
        0x9bdc06a7, 0xc19bf174, 0xe49b69c1, 0xefbe4786, 0x0fc19dc6, 0x240ca1cc, 0x2de92c6f,
        0x4a7484aa, 0x5cb0a9dc, 0x76f988da, 0x983e5152, 0xa831c66d, 0xb00327c8, 0xbf597fc7,
        0xc6e00bf3, 0xd5a79147, 0x06ca6351, 0x14292967, 0x27b70a85, 0x2e1b2138, 0x4d2c6dfc,
        0x53380d13, 0x650a7354, 0x766a0abb, 0x81c2c92e, 0x92722c85, 0xa2bfe8a1, 0xa81a664b,
        0xc24b8b70, 0xc76c51a3, 0xd192e819, 0xd6990624, 0xf40e3585, 0x106aa070, 0x19a4c116,
        0x1e376c08, 0x2748774c, 0x34b0bcb5, 0x391c0cb3, 0x4ed8aa4a, 0x5b9cca4f, 0x682e6ff3,
        0x748f82ee, 0x78a5636f, 0x84c87814, 0x8cc70208, 0x90befffa, 0xa4506ceb, 0xbef9a3f7,
        0xc67178f2,
    ];
    let mut h: [u32; 8] = [
        0x6a09e667, 0xbb67ae85, 0x3c6ef372, 0xa54ff53a, 0x510e527f, 0x9b05688c, 0x1f83d9ab,
        0x5be0cd19,
    ];
    let mut message = data.to_vec();
    message.push(0x80);
    while message.len() % 64 != 56 {
        message.push(0);
    }
    message.extend_from_slice(&((data.len() as u64).wrapping_mul(8)).to_be_bytes());
    for block in message.chunks_exact(64) {
        let mut w = [0u32; 64];
        for (t, word) in block.chunks_exact(4).enumerate() {
            w[t] = u32::from_be_bytes([word[0], word[1], word[2], word[3]]);
        }
        for t in 16..64 {
            let s0 = w[t - 15].rotate_right(7) ^ w[t - 15].rotate_right(18) ^ (w[t - 15] >> 3);
            let s1 = w[t - 2].rotate_right(17) ^ w[t - 2].rotate_right(19) ^ (w[t - 2] >> 10);
            w[t] = w[t - 16]
                .wrapping_add(s0)
                .wrapping_add(w[t - 7])
                .wrapping_add(s1);
        }
        let [mut a, mut b, mut c, mut d, mut e, mut f, mut g, mut k] = h;
        for t in 0..64 {
            let s1 = e.rotate_right(6) ^ e.rotate_right(11) ^ e.rotate_right(25);
            let choice = (e & f) ^ (!e & g);
            let t1 = k
                .wrapping_add(s1)
                .wrapping_add(choice)
                .wrapping_add(K[t])
                .wrapping_add(w[t]);
            let s0 = a.rotate_right(2) ^ a.rotate_right(13) ^ a.rotate_right(22);
            let majority = (a & b) ^ (a & c) ^ (b & c);
            let t2 = s0.wrapping_add(majority);
            k = g;
            g = f;
            f = e;
            e = d.wrapping_add(t1);
            d = c;
            c = b;
            b = a;
            a = t1.wrapping_add(t2);
        }
        for (x, y) in h.iter_mut().zip([a, b, c, d, e, f, g, k]) {
            *x = x.wrapping_add(y);
        }
    }
    h.iter().map(|x| format!("{x:08x}")).collect()
}

/// Runs `pge merge`.
pub fn merge(args: &MergeArgs) -> anyhow::Result<()> {
    let Manifest {
        seed,
        params,
        tiles,
        variants,
    } = read_manifest(&args.dir)?;
    let chosen: Vec<&TileEntry> = tiles
        .iter()
        .filter(|t| match args.rect {
            Some([i0, j0, i1, j1]) => (i0..=i1).contains(&t.i) && (j0..=j1).contains(&t.j),
            None => true,
        })
        .collect();
    if chosen.is_empty() {
        bail!(
            "{}: no tile of the world is in the rectangle",
            args.dir.display()
        );
    }
    let mut world = World::default();
    if let Some((file, sha256, description)) = &variants {
        let path = args.dir.join(file);
        let bytes =
            std::fs::read(&path).with_context(|| format!("cannot read {}", path.display()))?;
        if sha256_hex(&bytes) != *sha256 {
            bail!(
                "{}: the file does not match world.json (run pge-world again to rewrite it)",
                path.display()
            );
        }
        let key = normal_path(&path)?;
        world.external.insert(key.clone(), Arc::new(bytes));
        // The variant meshes' extras (skeletons) are in the description, not in the tiles.
        if let Some(description) = description {
            let path = args.dir.join(description);
            let text =
                std::fs::read(&path).with_context(|| format!("cannot read {}", path.display()))?;
            let json: Value = serde_json::from_slice(&text)
                .with_context(|| format!("{}: not a variants description", path.display()))?;
            let extras = json
                .get("meshes")
                .and_then(Value::as_array)
                .map(|meshes| {
                    meshes
                        .iter()
                        .map(|m| match m.pointer("/extras/pge") {
                            Some(Value::Object(e)) => e.clone(),
                            _ => Map::new(),
                        })
                        .collect()
                })
                .unwrap_or_default();
            world.shared_extras.insert(key, extras);
        }
    }
    for t in &chosen {
        let path = args.dir.join(&t.file);
        let bytes =
            std::fs::read(&path).with_context(|| format!("cannot read {}", path.display()))?;
        if sha256_hex(&bytes) != t.sha256 {
            bail!(
                "{}: the file does not match world.json (run pge-world again to regrow it)",
                path.display()
            );
        }
        let folder = path.parent().unwrap_or(Path::new("."));
        world
            .add_tile(&bytes, (t.i, t.j), folder)
            .with_context(|| path.display().to_string())?;
    }
    let model = world.finish();
    let output = args
        .output
        .clone()
        .unwrap_or_else(|| args.dir.join("world.glb"));
    let instancing = match args.instancing {
        InstancingArg::Gpu => Instancing::Gpu,
        InstancingArg::Nodes => Instancing::Nodes,
    };
    let meta = ExportMeta { seed, params };
    let bytes = pge_engine::export::glb_bytes_with(&model, &meta, instancing)?;
    write_atomically(&output, &bytes)
}

/// The model being merged.
#[derive(Default)]
struct World {
    model: Model,
    /// Variants written so far: the group's name and its meshes, for sharing them.
    variants: Vec<(String, Vec<Mesh>)>,
    /// Extras of the first tile, summed counts of every tile.
    forest: Option<Map<String, Value>>,
    tiles: Vec<[u64; 2]>,
    /// External buffers read so far (shared variants), by their absolute path.
    external: HashMap<PathBuf, Arc<Vec<u8>>>,
    /// The group of each shared variant mesh placed so far: (its buffer's path, its glTF
    /// mesh index) -> group.
    shared_groups: HashMap<(PathBuf, usize), usize>,
    /// Per shared binary file, the `extras.pge` of each mesh of its description.
    shared_extras: HashMap<PathBuf, Vec<Map<String, Value>>>,
}

impl World {
    /// Adds the terrain patch and the placements of one tile's glb (in `folder`, against
    /// which the URIs of its external buffers resolve).
    fn add_tile(&mut self, bytes: &[u8], index: (u64, u64), folder: &Path) -> anyhow::Result<()> {
        let gltf = Gltf::from_slice(bytes).context("not a readable .glb")?;
        let blob = gltf.blob.as_deref();
        // Buffer 0 is the binary chunk; the others are files beside the tile.
        let mut files: Vec<Option<(PathBuf, Arc<Vec<u8>>)>> = vec![None];
        for buffer in gltf.document.buffers().skip(1) {
            let gltf::buffer::Source::Uri(uri) = buffer.source() else {
                bail!("buffer {} has no URI", buffer.index());
            };
            let path = normal_path(&folder.join(relative_file(uri)?))?;
            let data = match self.external.get(&path) {
                Some(d) => d.clone(),
                None => {
                    let d = std::fs::read(&path).with_context(|| {
                        format!("cannot read {} (buffer {})", path.display(), buffer.index())
                    })?;
                    let d = Arc::new(d);
                    self.external.insert(path.clone(), d.clone());
                    d
                }
            };
            files.push(Some((path, data)));
        }
        let data: Vec<Option<&[u8]>> = files
            .iter()
            .enumerate()
            .map(|(k, f)| match f {
                _ if k == 0 => blob,
                Some((_, d)) => Some(d.as_slice()),
                None => None,
            })
            .collect();
        check_bounds(&gltf.document, &data)?;
        let buffer = |b: gltf::Buffer| data.get(b.index()).copied().flatten();
        let json: Value = serde_json::from_slice(&gltf::binary::Glb::from_slice(bytes)?.json)?;
        let scene = gltf
            .document
            .default_scene()
            .or_else(|| gltf.document.scenes().next());
        // A mesh whose data is in an external buffer is the shared variant of that file: read
        // once for the whole world.
        let shared_key = |mesh: &gltf::Mesh| -> Option<(PathBuf, usize)> {
            let prim = mesh.primitives().next()?;
            let view = prim.get(&gltf::Semantic::Positions)?.view()?;
            let (path, _) = files.get(view.buffer().index())?.as_ref()?;
            Some((path.clone(), mesh.index()))
        };
        let mut meshes = Vec::new();
        for mesh in gltf.document.meshes() {
            let key = shared_key(&mesh);
            meshes.push(match key {
                Some(key) if self.shared_groups.contains_key(&key) => (String::new(), Vec::new()),
                Some((path, k)) => {
                    let (name, mut parts) = read_mesh(&mesh, &buffer, &json)?;
                    let extras = self.shared_extras.get(&path).and_then(|e| e.get(k));
                    if let (Some(first), Some(extras)) = (parts.first_mut(), extras) {
                        first.extras = extras.clone();
                    }
                    (name, parts)
                }
                None => read_mesh(&mesh, &buffer, &json)?,
            });
        }
        for node in scene.iter().flat_map(|s| s.nodes()) {
            let Some(mesh) = node.mesh() else { continue };
            let (name, parts) = &meshes[mesh.index()];
            let instancing = json
                .get("nodes")
                .and_then(|n| n.get(node.index()))
                .and_then(|n| n.pointer("/extensions/EXT_mesh_gpu_instancing/attributes"));
            // Each placement's leaves for the forest's camera, when the tile has them.
            let leaves = json
                .get("nodes")
                .and_then(|n| n.get(node.index()))
                .and_then(|n| n.pointer("/extras/pge/lod/leaves"));
            let transforms = match instancing {
                Some(attributes) => read_instances(&gltf, attributes, &buffer)?,
                None if parts.len() == 1 && leaves.is_none() => {
                    let m = Mat4::from_cols_array_2d(&node.transform().matrix());
                    self.model.add_mesh(parts[0].clone(), m);
                    continue;
                }
                None => {
                    let (t, r, s) = node.transform().decomposed();
                    vec![InstanceTransform {
                        translation: t,
                        rotation: r,
                        scale: s[0].max(s[1]).max(s[2]),
                    }]
                }
            };
            let counts = leaf_counts(leaves, transforms.len())?;
            match shared_key(&mesh) {
                Some(key) => {
                    let group = match self.shared_groups.get(&key) {
                        Some(&g) => g,
                        None => {
                            let none = counts.as_ref().map(|_| Vec::new());
                            let g = self.place(name, parts, Vec::new(), none);
                            self.shared_groups.insert(key, g);
                            g
                        }
                    };
                    self.extend(group, transforms, counts);
                }
                None => {
                    self.place(name, parts, transforms, counts);
                }
            }
        }
        self.add_extras(&json, index)
    }

    /// Adds placements of the variant `name` made of `parts`, sharing an equal variant
    /// already written, with their leaf counts: the group keeps counts only while every
    /// batch of its placements has them. Returns the group.
    fn place(
        &mut self,
        name: &str,
        parts: &[Mesh],
        transforms: Vec<InstanceTransform>,
        counts: Option<Vec<u32>>,
    ) -> usize {
        let found = self
            .variants
            .iter()
            .position(|(n, m)| n == name && m.as_slice() == parts);
        let group = match found {
            Some(g) => g,
            None => {
                let first = self.model.meshes.len();
                for m in parts {
                    self.model.meshes.push(Arc::new(m.clone()));
                }
                let roots = parts
                    .first()
                    .and_then(|p| p.extras.get("lod")?.get("roots")?.as_u64())
                    .and_then(|r| u32::try_from(r).ok())
                    .unwrap_or(0);
                self.model.groups.push(InstanceGroup {
                    name: name.to_string(),
                    meshes: (first..first + parts.len()).collect(),
                    transforms: Vec::new(),
                    leaves: counts.is_some().then(|| PlacementLeaves {
                        roots,
                        counts: Vec::new(),
                    }),
                });
                self.variants.push((name.to_string(), parts.to_vec()));
                self.model.groups.len() - 1
            }
        };
        self.extend(group, transforms, counts);
        group
    }

    /// Adds placements (and their leaf counts) to group `group`.
    fn extend(
        &mut self,
        group: usize,
        transforms: Vec<InstanceTransform>,
        counts: Option<Vec<u32>>,
    ) {
        let group = &mut self.model.groups[group];
        match (&mut group.leaves, counts) {
            (Some(leaves), Some(counts)) => leaves.counts.extend(counts),
            (leaves, _) => *leaves = None,
        }
        group.transforms.extend(transforms);
    }

    /// Sums the tile's stats and forest counts into the world's.
    fn add_extras(&mut self, json: &Value, (i, j): (u64, u64)) -> anyhow::Result<()> {
        let pge = json.pointer("/extras/pge").cloned().unwrap_or(Value::Null);
        let count = |p: &str| pge.pointer(p).and_then(Value::as_u64).unwrap_or(0);
        self.model.stats.nodes += count("/stats/nodes");
        self.model.stats.leaves += count("/stats/leaves");
        self.model.stats.modules += count("/stats/modules");
        self.tiles.push([i, j]);
        let Some(Value::Object(tile)) = pge.get("forest") else {
            return Ok(());
        };
        let Some(forest) = &mut self.forest else {
            self.forest = Some(tile.clone());
            return Ok(());
        };
        let sum = |a: Option<&Value>, b: Option<&Value>| {
            a.and_then(Value::as_u64).unwrap_or(0) + b.and_then(Value::as_u64).unwrap_or(0)
        };
        let total = sum(forest.get("instances"), tile.get("instances"));
        forest.insert("instances".into(), total.into());
        if let (Some(Value::Array(all)), Some(Value::Array(these))) =
            (forest.get_mut("species"), tile.get("species"))
        {
            for (a, b) in all.iter_mut().zip(these) {
                let n = sum(a.get("count"), b.get("count"));
                if let Some(a) = a.as_object_mut() {
                    a.insert("count".into(), n.into());
                }
            }
        }
        Ok(())
    }

    /// The merged model, its `extras.pge.forest` naming the tiles it holds.
    fn finish(mut self) -> Model {
        if let Some(mut forest) = self.forest.take() {
            forest.remove("tileIndex");
            forest.insert("tiles".into(), serde_json::json!(self.tiles));
            self.model
                .extras
                .insert("forest".into(), Value::Object(forest));
        }
        self.model
    }
}

/// Checks that every accessor lies inside its buffer view, every view inside its buffer and
/// the buffer inside its data (the binary chunk, or the file it names), so that reading them
/// cannot go out of bounds (the gltf crate's validation does not compare them with the bytes
/// actually present).
fn check_bounds(doc: &gltf::Document, data: &[Option<&[u8]>]) -> anyhow::Result<()> {
    for buffer in doc.buffers() {
        let present = data
            .get(buffer.index())
            .copied()
            .flatten()
            .map_or(0, <[u8]>::len);
        if buffer.length() > present {
            let what = if buffer.index() == 0 {
                "the binary chunk"
            } else {
                "the file it names"
            };
            bail!("buffer {} is not in {what}", buffer.index());
        }
    }
    for view in doc.views() {
        if view.offset().saturating_add(view.length()) > view.buffer().length() {
            bail!("buffer view {} goes past its buffer", view.index());
        }
    }
    for a in doc.accessors() {
        if a.sparse().is_some() {
            bail!("accessor {} is sparse, which PGE never writes", a.index());
        }
        let Some(view) = a.view() else {
            bail!("accessor {} has no buffer view", a.index());
        };
        let stride = view.stride().unwrap_or(a.size());
        let end = match a.count() {
            0 => a.offset(),
            n => (n - 1)
                .checked_mul(stride)
                .and_then(|x| x.checked_add(a.offset()))
                .and_then(|x| x.checked_add(a.size()))
                .unwrap_or(usize::MAX),
        };
        if end > view.length() {
            bail!("accessor {} goes past its buffer view", a.index());
        }
    }
    Ok(())
}

/// A node's leaf counts (`extras.pge.lod.leaves`: an array for an instancing node, a number
/// for a node per placement), checked against its `placements`.
fn leaf_counts(leaves: Option<&Value>, placements: usize) -> anyhow::Result<Option<Vec<u32>>> {
    let count = |v: &Value| v.as_u64().and_then(|n| u32::try_from(n).ok());
    let counts: Option<Vec<u32>> = match leaves {
        None => return Ok(None),
        Some(Value::Array(list)) => list.iter().map(count).collect(),
        Some(one) => count(one).map(|n| vec![n]),
    };
    match counts {
        Some(c) if c.len() == placements => Ok(Some(c)),
        _ => bail!("a node's extras.pge.lod.leaves do not match its {placements} placements"),
    }
}

/// The placements of an `EXT_mesh_gpu_instancing` node.
fn read_instances<'a>(
    gltf: &'a Gltf,
    attributes: &Value,
    buffer: &dyn Fn(gltf::Buffer<'a>) -> Option<&'a [u8]>,
) -> anyhow::Result<Vec<InstanceTransform>> {
    let accessor = |name: &str| {
        attributes
            .get(name)
            .and_then(Value::as_u64)
            .and_then(|i| gltf.document.accessors().nth(i as usize))
            .filter(|a| a.data_type() == gltf::accessor::DataType::F32)
            .with_context(|| format!("an instancing node without a float {name} accessor"))
    };
    let vec3 = |name: &str| -> anyhow::Result<Vec<[f32; 3]>> {
        let a = accessor(name)?;
        if a.dimensions() != gltf::accessor::Dimensions::Vec3 {
            bail!("the instancing {name} accessor is not VEC3");
        }
        Ok(gltf::accessor::Iter::<[f32; 3]>::new(a, buffer)
            .with_context(|| format!("the instancing {name} data is missing"))?
            .collect())
    };
    let translation = vec3("TRANSLATION")?;
    let scale = vec3("SCALE")?;
    let a = accessor("ROTATION")?;
    if a.dimensions() != gltf::accessor::Dimensions::Vec4 {
        bail!("the instancing ROTATION accessor is not VEC4");
    }
    let rotation: Vec<[f32; 4]> = gltf::accessor::Iter::<[f32; 4]>::new(a, buffer)
        .context("the instancing ROTATION data is missing")?
        .collect();
    if translation.len() != rotation.len() || translation.len() != scale.len() {
        bail!("the instancing accessors differ in length");
    }
    Ok(translation
        .into_iter()
        .zip(rotation)
        .zip(scale)
        .map(|((t, r), s)| InstanceTransform {
            translation: t,
            rotation: r,
            scale: s[0].max(s[1]).max(s[2]),
        })
        .collect())
}

/// A glTF mesh as its name and one [`Mesh`] per primitive; the mesh's `extras.pge` goes to
/// the first (where the exporter, which lets the first member's keys win, puts it back).
fn read_mesh<'s>(
    mesh: &gltf::Mesh,
    buffer: &dyn for<'b> Fn(gltf::Buffer<'b>) -> Option<&'s [u8]>,
    json: &Value,
) -> anyhow::Result<(String, Vec<Mesh>)> {
    let name = mesh.name().unwrap_or_default().to_string();
    let extras: Map<String, Value> = match mesh.extras() {
        Some(raw) => match serde_json::from_str::<Value>(raw.get())?.get("pge") {
            Some(Value::Object(m)) => m.clone(),
            _ => Map::new(),
        },
        None => Map::new(),
    };
    let mut parts = Vec::new();
    for prim in mesh.primitives() {
        let reader = prim.reader(buffer);
        let primitive = match prim.mode() {
            gltf::mesh::Mode::Triangles => Primitive::Triangles,
            gltf::mesh::Mode::Lines => Primitive::Lines,
            other => bail!("mesh {name}: {other:?} primitives are not PGE's"),
        };
        let mut m = Mesh {
            name: name.clone(),
            primitive,
            positions: reader
                .read_positions()
                .with_context(|| format!("mesh {name}: no positions"))?
                .map(Vec3::from_array)
                .collect(),
            normals: reader
                .read_normals()
                .map(|n| n.map(Vec3::from_array).collect())
                .unwrap_or_default(),
            uvs: reader
                .read_tex_coords(0)
                .map(|t| t.into_f32().map(Vec2::from_array).collect())
                .unwrap_or_default(),
            colors: reader
                .read_colors(0)
                .map(|c| c.into_rgba_f32().map(Vec4::from_array).collect())
                .unwrap_or_default(),
            indices: reader
                .read_indices()
                .with_context(|| format!("mesh {name}: no indices"))?
                .into_u32()
                .collect(),
            material: Arc::new(read_material(&prim.material(), buffer, json)?),
            ..Mesh::default()
        };
        if parts.is_empty() {
            m.extras = extras.clone();
        }
        parts.push(m);
    }
    Ok((name, parts))
}

/// A glTF material as PGE's, its textures (base colour, normal, metallic-roughness) read
/// back from their buffers, its `KHR_materials_diffuse_transmission` from the file's JSON
/// (`json`: the gltf crate reads no such extension).
fn read_material<'s>(
    m: &gltf::Material,
    buffer: &dyn for<'b> Fn(gltf::Buffer<'b>) -> Option<&'s [u8]>,
    json: &Value,
) -> anyhow::Result<Material> {
    let pbr = m.pbr_metallic_roughness();
    let read = |texture: Option<gltf::Texture>| -> anyhow::Result<Option<Arc<Texture>>> {
        texture.map(|t| read_texture(&t, buffer)).transpose()
    };
    Ok(Material {
        name: m.name().unwrap_or_default().to_string(),
        base_color: pbr.base_color_factor(),
        texture: read(pbr.base_color_texture().map(|i| i.texture()))?,
        normal_texture: read(m.normal_texture().map(|i| i.texture()))?,
        metallic_roughness_texture: read(pbr.metallic_roughness_texture().map(|i| i.texture()))?,
        alpha: match m.alpha_mode() {
            gltf::material::AlphaMode::Opaque => AlphaMode::Opaque,
            gltf::material::AlphaMode::Mask => AlphaMode::Mask(m.alpha_cutoff().unwrap_or(0.5)),
            gltf::material::AlphaMode::Blend => AlphaMode::Blend,
        },
        double_sided: m.double_sided(),
        metallic: pbr.metallic_factor(),
        roughness: pbr.roughness_factor(),
        transmission: m.index().and_then(|i| read_transmission(json, i)),
    })
}

/// The `KHR_materials_diffuse_transmission` of material `index` in a glTF JSON, with the
/// extension's defaults (factor 0, white) for what it leaves out.
fn read_transmission(json: &Value, index: usize) -> Option<DiffuseTransmission> {
    let ext = json.pointer(&format!(
        "/materials/{index}/extensions/KHR_materials_diffuse_transmission"
    ))?;
    let number =
        |v: Option<&Value>, default: f32| v.and_then(Value::as_f64).map_or(default, |x| x as f32);
    let color = ext.get("diffuseTransmissionColorFactor");
    Some(DiffuseTransmission {
        factor: number(ext.get("diffuseTransmissionFactor"), 0.0),
        color: [0, 1, 2].map(|i| number(color.and_then(|c| c.get(i)), 1.0)),
    })
}

/// A texture's PNG image, read back from its buffer.
fn read_texture<'s>(
    texture: &gltf::Texture,
    buffer: &dyn for<'b> Fn(gltf::Buffer<'b>) -> Option<&'s [u8]>,
) -> anyhow::Result<Arc<Texture>> {
    let image = texture.source();
    let gltf::image::Source::View { view, .. } = image.source() else {
        bail!("an image outside the .glb");
    };
    let png = buffer(view.buffer())
        .and_then(|b| b.get(view.offset()..view.offset() + view.length()))
        .context("an image outside its buffer")?;
    let (width, height) = png_size(png).context("an image that is not a PNG")?;
    Ok(Arc::new(Texture {
        name: image.name().unwrap_or_default().to_string(),
        width,
        height,
        png: png.to_vec(),
    }))
}

/// The file a buffer's URI names, relative to the tile: percent-decoded; absolute paths,
/// schemes (`data:`, `http:`) and `..` past nothing are refused.
fn relative_file(uri: &str) -> anyhow::Result<PathBuf> {
    let refuse = || anyhow::anyhow!("buffer URI '{uri}' is not a relative file");
    if uri.starts_with('/') || uri.contains(':') || uri.contains('\\') || uri.is_empty() {
        return Err(refuse());
    }
    let bytes = uri.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut k = 0;
    while k < bytes.len() {
        if bytes[k] == b'%' {
            let hex = uri.get(k + 1..k + 3).ok_or_else(refuse)?;
            out.push(u8::from_str_radix(hex, 16).map_err(|_| refuse())?);
            k += 3;
        } else {
            out.push(bytes[k]);
            k += 1;
        }
    }
    let text = String::from_utf8(out).map_err(|_| refuse())?;
    Ok(PathBuf::from(text))
}

/// `path` made absolute, `.` and `..` folded (lexically), so one file has one key.
fn normal_path(path: &Path) -> anyhow::Result<PathBuf> {
    let absolute =
        std::path::absolute(path).with_context(|| format!("cannot resolve {}", path.display()))?;
    let mut out = PathBuf::new();
    for c in absolute.components() {
        match c {
            std::path::Component::CurDir => {}
            std::path::Component::ParentDir => {
                out.pop();
            }
            other => out.push(other),
        }
    }
    Ok(out)
}

/// Width and height from a PNG's header.
fn png_size(png: &[u8]) -> Option<(u32, u32)> {
    if png.get(..8)? != b"\x89PNG\r\n\x1a\n" || png.get(12..16)? != b"IHDR" {
        return None;
    }
    let word = |at: usize| Some(u32::from_be_bytes(png.get(at..at + 4)?.try_into().ok()?));
    Some((word(16)?, word(20)?))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_rectangle_is_four_ordered_integers() {
        assert_eq!(parse_rect("0,1,2,3"), Ok([0, 1, 2, 3]));
        assert!(parse_rect("2,0,1,3").is_err());
        assert!(parse_rect("0,0,1").is_err());
        assert!(parse_rect("a,0,1,1").is_err());
    }

    #[test]
    fn sha256_matches_the_standard_vectors() {
        assert_eq!(
            sha256_hex(b""),
            "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855"
        );
        assert_eq!(
            sha256_hex(b"abc"),
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
        );
        let long = b"abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq";
        assert_eq!(
            sha256_hex(long),
            "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1"
        );
    }

    /// A glb of `json` and `bin`, chunks padded as the format asks.
    fn glb(json: &Value, bin: &[u8]) -> Vec<u8> {
        let mut text = serde_json::to_vec(json).expect("json");
        while !text.len().is_multiple_of(4) {
            text.push(b' ');
        }
        let total = 12 + 8 + text.len() + 8 + bin.len();
        let mut out = Vec::new();
        out.extend_from_slice(b"glTF");
        out.extend_from_slice(&2u32.to_le_bytes());
        out.extend_from_slice(&(total as u32).to_le_bytes());
        out.extend_from_slice(&(text.len() as u32).to_le_bytes());
        out.extend_from_slice(b"JSON");
        out.extend_from_slice(&text);
        out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        out.extend_from_slice(bin);
        out
    }

    #[test]
    fn a_tile_whose_accessors_overrun_their_data_is_an_error_not_a_panic() {
        let mesh =
            Mesh::from_triangles(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![0, 1, 2]).expect("mesh");
        let bytes = pge_engine::export::glb_bytes(&Model::from_mesh(mesh), &ExportMeta::default())
            .expect("glb");
        let mut world = World::default();
        let here = Path::new(".");
        world
            .add_tile(&bytes, (0, 0), here)
            .expect("a valid tile reads");
        assert_eq!(world.model.meshes.len(), 1);

        let file = gltf::binary::Glb::from_slice(&bytes).expect("glb");
        let json: Value = serde_json::from_slice(&file.json).expect("json");
        let bin = file.bin.expect("bin").to_vec();
        let mut more = json.clone();
        more["accessors"][0]["count"] = 1000.into();
        let mut shorter = json.clone();
        shorter["buffers"][0]["byteLength"] = (bin.len() as u64 + 64).into();
        let mut sparse = json;
        sparse["accessors"][0]["sparse"] = serde_json::json!({"count": 1,
            "indices": {"bufferView": 0, "componentType": 5125},
            "values": {"bufferView": 0}});
        for (bad, needle) in [
            (glb(&more, &bin), "goes past"),
            (glb(&shorter, &bin), "not in the binary chunk"),
            (glb(&sparse, &bin), "sparse"),
        ] {
            let err = World::default()
                .add_tile(&bad, (0, 0), here)
                .expect_err("refused");
            assert!(format!("{err:#}").contains(needle), "{err:#}");
        }
    }

    #[test]
    fn a_png_header_gives_its_size() {
        let tex = Texture::from_rgba("t", 3, 2, &[0; 24]).expect("png");
        assert_eq!(png_size(&tex.png), Some((3, 2)));
        assert_eq!(png_size(b"glTF"), None);
    }
}
