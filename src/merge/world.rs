//! The merged model: the tiles' terrain patches and placements added one by one, every
//! variant written once.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::{Context, bail};
use glam::Mat4;
use pge_engine::geometry::{
    ForestPart, ForestStats, InstanceGroup, InstanceTransform, Mesh, MeshLod, Model,
    PlacementLeaves, SpeciesCount,
};
use pge_engine::import::{
    check_bounds, leaf_counts, open, read_instances, read_mesh, relative_file, split_lod,
};
use serde_json::{Map, Value};

/// The model being merged.
#[derive(Default)]
pub(super) struct World {
    model: Model,
    /// Variants written so far: the group's name and its meshes, for sharing them.
    variants: Vec<(String, Vec<Mesh>)>,
    /// The forest of the first tile that has one, with the counts of every tile summed.
    forest: Option<ForestStats>,
    tiles: Vec<[u64; 2]>,
    /// External buffers read so far (shared variants), by their absolute path.
    pub(super) external: HashMap<PathBuf, Arc<Vec<u8>>>,
    /// The group of each shared variant mesh placed so far: (its buffer's path, its glTF
    /// mesh index) -> group.
    shared_groups: HashMap<(PathBuf, usize), usize>,
    /// Per shared binary file, the `extras.pge` of each mesh of its description.
    pub(super) shared_extras: HashMap<PathBuf, Vec<Map<String, Value>>>,
}

impl World {
    /// Adds the terrain patch and the placements of one tile's glb (the file `tile`, against
    /// whose folder the URIs of its external buffers resolve, read by `reader`).
    pub(super) fn add_tile(
        &mut self,
        bytes: &[u8],
        index: (u64, u64),
        reader: &mut super::Files,
        tile: &Path,
    ) -> anyhow::Result<()> {
        let folder = tile.parent().unwrap_or(Path::new("."));
        let gltf = open(bytes).context("not a readable .glb")?;
        let blob = gltf.blob.as_deref();
        // Buffer 0 is the binary chunk; the others are files beside the tile.
        let mut files: Vec<Option<(PathBuf, Arc<Vec<u8>>)>> = vec![None];
        for buffer in gltf.document.buffers().skip(1) {
            let gltf::buffer::Source::Uri(uri) = buffer.source() else {
                bail!("buffer {} has no URI", buffer.index());
            };
            let named = folder.join(relative_file(uri)?);
            let resolved = std::fs::canonicalize(&named).ok();
            let data = match resolved.as_ref().and_then(|p| self.external.get(p)) {
                Some(d) => d.clone(),
                None => {
                    let (_, d) = reader
                        .read(&named)
                        .with_context(|| format!("buffer {} ('{uri}')", buffer.index()))?;
                    let d = Arc::new(d);
                    if let Some(p) = &resolved {
                        self.external.insert(p.clone(), d.clone());
                    }
                    d
                }
            };
            let path = resolved.unwrap_or(named);
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
                        (first.extras, first.lod) = split_lod(extras.clone());
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
                    .and_then(|p| p.lod.as_deref())
                    .map_or(0, MeshLod::roots);
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
        let stats = &mut self.model.stats;
        stats.nodes = stats.nodes.saturating_add(count("/stats/nodes"));
        stats.leaves = stats.leaves.saturating_add(count("/stats/leaves"));
        stats.modules = stats.modules.saturating_add(count("/stats/modules"));
        self.tiles.push([i, j]);
        let Some(value) = pge.get("forest") else {
            return Ok(());
        };
        let tile = forest_stats(value)
            .with_context(|| format!("tile {i},{j}: extras.pge.forest is not a forest's"))?;
        match &mut self.forest {
            Some(forest) => forest.add_tile(&tile),
            None => self.forest = Some(tile),
        }
        Ok(())
    }

    /// The merged model, its `extras.pge.forest` naming the tiles it holds.
    pub(super) fn finish(mut self) -> Model {
        if let Some(mut forest) = self.forest.take() {
            forest.part = ForestPart::Merged(self.tiles);
            self.model.forest = Some(forest);
        }
        self.model
    }
}

/// A tile's `extras.pge.forest` as the glTF writer writes it (`{size, seed, tile,
/// tileIndex, instances, species = [{name, variants, count}]}`), `None` when it is not one.
fn forest_stats(value: &Value) -> Option<ForestStats> {
    let number = |v: &Value, key: &str| v.get(key)?.as_u64();
    let pair = |v: &Value| -> Option<[Value; 2]> {
        match v.as_array()?.as_slice() {
            [a, b] => Some([a.clone(), b.clone()]),
            _ => None,
        }
    };
    let [x, z] = pair(value.get("size")?)?;
    let tile = match value.get("tile")? {
        Value::Null => None,
        t => Some(t.as_f64()?),
    };
    let index = match value.get("tileIndex") {
        None | Some(Value::Null) => None,
        Some(v) => {
            let [i, j] = pair(v)?;
            Some([i.as_u64()?, j.as_u64()?])
        }
    };
    let species = value
        .get("species")?
        .as_array()?
        .iter()
        .map(|s| {
            Some(SpeciesCount {
                name: s.get("name")?.as_str()?.to_string(),
                variants: number(s, "variants")?,
                count: number(s, "count")?,
            })
        })
        .collect::<Option<_>>()?;
    Some(ForestStats {
        size: [x.as_f64()?, z.as_f64()?],
        seed: number(value, "seed")?,
        tile,
        part: ForestPart::Tile(index),
        instances: number(value, "instances")?,
        species,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;
    use pge_engine::export::ExportMeta;

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
    fn a_tiles_forest_reads_back_as_written_and_tiles_add_up() {
        let mesh =
            Mesh::from_triangles(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![0, 1, 2]).expect("mesh");
        let mut model = Model::from_mesh(mesh);
        let stats = ForestStats {
            size: [60.0, 0.1],
            seed: 9,
            tile: Some(30.0),
            part: ForestPart::Tile(Some([1, 0])),
            instances: 5,
            species: vec![SpeciesCount {
                name: "oak".into(),
                variants: 2,
                count: 5,
            }],
        };
        model.forest = Some(stats.clone());
        let bytes = pge_engine::export::glb_bytes(&model, &ExportMeta::default()).expect("glb");
        let file = gltf::binary::Glb::from_slice(&bytes).expect("glb");
        let json: Value = serde_json::from_slice(&file.json).expect("json");
        let written = json.pointer("/extras/pge/forest").expect("a forest");
        assert_eq!(forest_stats(written), Some(stats));
        let mut world = World::default();
        let here = Path::new("tile.glb");
        let mut files = super::super::Files::new(Path::new("."), 60.0, 64).expect("files");
        world
            .add_tile(&bytes, (1, 0), &mut files, here)
            .expect("reads");
        world
            .add_tile(&bytes, (0, 0), &mut files, here)
            .expect("reads");
        let merged = world.finish().forest.expect("a forest");
        assert_eq!(merged.instances, 10);
        assert_eq!(merged.species[0].count, 10);
        assert_eq!(merged.part, ForestPart::Merged(vec![[1, 0], [0, 0]]));
        // Not a forest's: an error naming the tile.
        let mut bad = json.clone();
        bad["extras"]["pge"]["forest"]["species"] = Value::Null;
        let bin = file.bin.expect("bin").to_vec();
        let err = World::default()
            .add_tile(&glb(&bad, &bin), (2, 3), &mut files, here)
            .expect_err("refused");
        assert!(format!("{err:#}").contains("tile 2,3"), "{err:#}");
    }

    #[test]
    fn a_tile_whose_accessors_overrun_their_data_is_an_error_not_a_panic() {
        let mesh =
            Mesh::from_triangles(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![0, 1, 2]).expect("mesh");
        let bytes = pge_engine::export::glb_bytes(&Model::from_mesh(mesh), &ExportMeta::default())
            .expect("glb");
        let mut world = World::default();
        let here = Path::new("tile.glb");
        let mut files = super::super::Files::new(Path::new("."), 60.0, 64).expect("files");
        world
            .add_tile(&bytes, (0, 0), &mut files, here)
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
                .add_tile(&bad, (0, 0), &mut files, here)
                .expect_err("refused");
            assert!(format!("{err:#}").contains(needle), "{err:#}");
        }
    }
}
