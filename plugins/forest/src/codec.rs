//! The variant cache's binary form of a [`Model`]: exact (floats as their bits), with shared
//! meshes, materials and textures kept shared. [`write_model`] and [`read_model`] are each
//! other's inverse; the cache (`cache.rs`) frames them with its key, files and checksum.

use std::sync::Arc;

use glam::{Mat4, Vec2, Vec3, Vec4};
use pge_engine::geometry::{
    AlphaMode, DiffuseTransmission, ForestPart, ForestStats, GroupLod, Instance, InstanceGroup,
    InstanceTransform, LeafPoint, LodLevel, LodSector, LodTable, Material, Mesh, MeshLod, Model,
    PlacementLeaves, Primitive, PrimitiveLod, Skeleton, SpeciesCount, Stats, Texture,
    VariantCounts,
};
use serde_json::{Map, Number, Value};

/// Appends values to an entry's bytes.
#[derive(Default)]
pub(crate) struct Writer(pub(crate) Vec<u8>);

impl Writer {
    pub(crate) fn u8(&mut self, x: u8) {
        self.0.push(x);
    }
    pub(crate) fn u32(&mut self, x: u32) {
        self.0.extend_from_slice(&x.to_le_bytes());
    }
    pub(crate) fn u64(&mut self, x: u64) {
        self.0.extend_from_slice(&x.to_le_bytes());
    }
    pub(crate) fn len(&mut self, n: usize) {
        self.u64(n as u64);
    }
    pub(crate) fn f32(&mut self, x: f32) {
        self.u32(x.to_bits());
    }
    pub(crate) fn f32s(&mut self, xs: &[f32]) {
        for &x in xs {
            self.f32(x);
        }
    }
    pub(crate) fn bytes(&mut self, b: &[u8]) {
        self.len(b.len());
        self.0.extend_from_slice(b);
    }
    pub(crate) fn str(&mut self, s: &str) {
        self.bytes(s.as_bytes());
    }
    pub(crate) fn json(&mut self, v: &Value) {
        match v {
            Value::Null => self.u8(0),
            Value::Bool(b) => self.u8(1 + u8::from(*b)),
            Value::Number(n) => match (n.as_u64(), n.as_i64(), n.as_f64()) {
                (Some(u), _, _) => {
                    self.u8(3);
                    self.u64(u);
                }
                (None, Some(i), _) => {
                    self.u8(4);
                    self.u64(i as u64);
                }
                (None, None, f) => {
                    self.u8(5);
                    self.u64(f.unwrap_or(0.0).to_bits());
                }
            },
            Value::String(s) => {
                self.u8(6);
                self.str(s);
            }
            Value::Array(a) => {
                self.u8(7);
                self.len(a.len());
                for x in a {
                    self.json(x);
                }
            }
            Value::Object(m) => {
                self.u8(8);
                self.map(m);
            }
        }
    }
    pub(crate) fn map(&mut self, m: &Map<String, Value>) {
        self.len(m.len());
        for (k, v) in m {
            self.str(k);
            self.json(v);
        }
    }
}

/// Reads values back from an entry's bytes, `None` past the end or on a bad value.
pub(crate) struct Reader<'a> {
    pub(crate) b: &'a [u8],
    pub(crate) at: usize,
}

impl Reader<'_> {
    pub(crate) fn take(&mut self, n: usize) -> Option<&[u8]> {
        let end = self.at.checked_add(n)?;
        let s = self.b.get(self.at..end)?;
        self.at = end;
        Some(s)
    }
    pub(crate) fn u8(&mut self) -> Option<u8> {
        Some(self.take(1)?[0])
    }
    pub(crate) fn u32(&mut self) -> Option<u32> {
        Some(u32::from_le_bytes(self.take(4)?.try_into().ok()?))
    }
    pub(crate) fn u64(&mut self) -> Option<u64> {
        Some(u64::from_le_bytes(self.take(8)?.try_into().ok()?))
    }
    /// A count of items of at least `size` bytes each, no more than the bytes left hold.
    pub(crate) fn len(&mut self, size: usize) -> Option<usize> {
        let n = usize::try_from(self.u64()?).ok()?;
        (n.checked_mul(size.max(1))? <= self.b.len() - self.at).then_some(n)
    }
    pub(crate) fn f32(&mut self) -> Option<f32> {
        Some(f32::from_bits(self.u32()?))
    }
    pub(crate) fn bytes(&mut self) -> Option<Vec<u8>> {
        let n = self.len(1)?;
        Some(self.take(n)?.to_vec())
    }
    pub(crate) fn str(&mut self) -> Option<String> {
        String::from_utf8(self.bytes()?).ok()
    }
    pub(crate) fn index(&mut self, below: usize) -> Option<usize> {
        let i = self.u32()? as usize;
        (i < below).then_some(i)
    }
    pub(crate) fn vec2s(&mut self) -> Option<Vec<Vec2>> {
        (0..self.len(8)?)
            .map(|_| Some(Vec2::new(self.f32()?, self.f32()?)))
            .collect()
    }
    pub(crate) fn vec3(&mut self) -> Option<Vec3> {
        Some(Vec3::new(self.f32()?, self.f32()?, self.f32()?))
    }
    pub(crate) fn vec3s(&mut self) -> Option<Vec<Vec3>> {
        (0..self.len(12)?).map(|_| self.vec3()).collect()
    }
    pub(crate) fn vec4s(&mut self) -> Option<Vec<Vec4>> {
        (0..self.len(16)?)
            .map(|_| {
                Some(Vec4::new(
                    self.f32()?,
                    self.f32()?,
                    self.f32()?,
                    self.f32()?,
                ))
            })
            .collect()
    }
    pub(crate) fn json(&mut self, depth: u32) -> Option<Value> {
        if depth > 256 {
            return None;
        }
        Some(match self.u8()? {
            0 => Value::Null,
            1 => Value::Bool(false),
            2 => Value::Bool(true),
            3 => Value::Number(Number::from(self.u64()?)),
            4 => Value::Number(Number::from(self.u64()? as i64)),
            5 => Value::Number(Number::from_f64(f64::from_bits(self.u64()?))?),
            6 => Value::String(self.str()?),
            7 => Value::Array(
                (0..self.len(1)?)
                    .map(|_| self.json(depth + 1))
                    .collect::<Option<_>>()?,
            ),
            8 => Value::Object(self.map(depth + 1)?),
            _ => return None,
        })
    }
    pub(crate) fn map(&mut self, depth: u32) -> Option<Map<String, Value>> {
        (0..self.len(9)?)
            .map(|_| Some((self.str()?, self.json(depth)?)))
            .collect()
    }
}

/// The position of `item` in `list` by pointer, appended if new.
fn shared<T>(list: &mut Vec<Arc<T>>, item: &Arc<T>) -> u32 {
    match list.iter().position(|x| Arc::ptr_eq(x, item)) {
        Some(i) => i as u32,
        None => {
            list.push(item.clone());
            (list.len() - 1) as u32
        }
    }
}

pub(crate) fn write_model(w: &mut Writer, model: &Model) {
    let Model {
        meshes,
        instances,
        groups,
        forest,
        variant_counts,
        extras,
        stats,
        environment,
        clean: _,
        skeleton_texts: _,
    } = model;
    // Shared parts once, in tables: textures, materials, skeletons. The materials are
    // written first into a buffer of their own, which collects the textures they use; the
    // table of textures goes before them.
    let mut materials = Vec::new();
    let mut skeletons = Vec::new();
    for m in meshes {
        shared(&mut materials, &m.material);
        if let Some(s) = &m.skeleton {
            shared(&mut skeletons, s);
        }
    }
    let mut textures = Vec::new();
    let mut table = Writer::default();
    table.len(materials.len());
    for m in &materials {
        let Material {
            name,
            base_color,
            texture,
            normal_texture,
            metallic_roughness_texture,
            alpha,
            double_sided,
            metallic,
            roughness,
            transmission,
        } = &**m;
        table.str(name);
        table.f32s(base_color);
        write_texture_ref(&mut table, &mut textures, texture.as_ref());
        write_texture_ref(&mut table, &mut textures, normal_texture.as_ref());
        write_texture_ref(
            &mut table,
            &mut textures,
            metallic_roughness_texture.as_ref(),
        );
        match alpha {
            AlphaMode::Opaque => table.u8(0),
            AlphaMode::Mask(cutoff) => {
                table.u8(1);
                table.f32(*cutoff);
            }
            AlphaMode::Blend => table.u8(2),
        }
        table.u8(u8::from(*double_sided));
        table.f32(*metallic);
        table.f32(*roughness);
        match transmission {
            None => table.u8(0),
            Some(t) => {
                table.u8(1);
                table.f32(t.factor);
                table.f32s(&t.color);
            }
        }
    }
    if let Some(t) = environment {
        shared(&mut textures, t);
    }
    w.len(textures.len());
    for t in &textures {
        let Texture {
            name,
            width,
            height,
            png,
        } = &**t;
        w.str(name);
        w.u32(*width);
        w.u32(*height);
        w.bytes(png);
    }
    w.0.extend_from_slice(&table.0);
    w.len(skeletons.len());
    for s in &skeletons {
        let Skeleton {
            positions,
            parents,
            radii,
            orders,
            leaves,
        } = &**s;
        w.len(positions.len());
        for p in positions {
            w.f32s(&p.to_array());
        }
        // A root as u32::MAX, a parent as itself (u32::MAX is never a node: the
        // skeleton's indices are u32 and count from 0).
        w.len(parents.len());
        for p in parents {
            w.u32(p.unwrap_or(u32::MAX));
        }
        w.len(radii.len());
        w.f32s(radii);
        w.len(orders.len());
        for &o in orders {
            w.u32(o);
        }
        w.len(leaves.len());
        for l in leaves {
            let LeafPoint {
                node,
                position,
                direction,
                side,
                size,
            } = l;
            w.u32(*node);
            w.f32s(&position.to_array());
            w.f32s(&direction.to_array());
            w.f32s(&side.to_array());
            w.f32(*size);
        }
    }
    w.len(meshes.len());
    for m in meshes {
        let Mesh {
            name,
            primitive,
            positions,
            normals,
            uvs,
            colors,
            indices,
            material,
            skeleton,
            lod,
            extras,
        } = &**m;
        w.str(name);
        w.u8(match primitive {
            Primitive::Triangles => 0,
            Primitive::Lines => 1,
        });
        for list in [positions, normals] {
            w.len(list.len());
            for p in list {
                w.f32s(&p.to_array());
            }
        }
        w.len(uvs.len());
        for p in uvs {
            w.f32s(&p.to_array());
        }
        w.len(colors.len());
        for p in colors {
            w.f32s(&p.to_array());
        }
        w.len(indices.len());
        for &i in indices {
            w.u32(i);
        }
        let material = shared(&mut materials, material);
        w.u32(material);
        match skeleton {
            Some(s) => {
                w.u8(1);
                let s = shared(&mut skeletons, s);
                w.u32(s);
            }
            None => w.u8(0),
        }
        write_lod(w, lod.as_deref());
        w.map(extras);
    }
    w.len(instances.len());
    for Instance { mesh, transform } in instances {
        w.u32(*mesh as u32);
        w.f32s(&transform.to_cols_array());
    }
    w.len(groups.len());
    for InstanceGroup {
        name,
        meshes,
        transforms,
        leaves,
    } in groups
    {
        w.str(name);
        w.len(meshes.len());
        for &m in meshes {
            w.u32(m as u32);
        }
        w.len(transforms.len());
        for t in transforms {
            w.f32s(&t.translation);
            w.f32s(&t.rotation);
            w.f32(t.scale);
        }
        match leaves {
            None => w.u8(0),
            Some(PlacementLeaves { roots, counts }) => {
                w.u8(1);
                w.u32(*roots);
                w.len(counts.len());
                for &c in counts {
                    w.u32(c);
                }
            }
        }
    }
    write_forest(w, forest.as_ref());
    w.len(variant_counts.len());
    for c in variant_counts {
        w.u64(c.nodes);
        w.u64(c.leaves);
    }
    w.map(extras);
    // Phases are timings of this run, not part of the variant.
    let Stats {
        nodes,
        leaves,
        modules,
        phases: _,
        warnings,
    } = stats;
    w.u64(*nodes);
    w.u64(*leaves);
    w.u64(*modules);
    w.len(warnings.len());
    for s in warnings {
        w.str(s);
    }
    write_texture_ref(w, &mut textures, environment.as_ref());
}

fn write_table(w: &mut Writer, table: &LodTable) {
    w.len(table.sectors().len());
    for s in table.sectors() {
        w.u32(s.offset());
        w.u32(s.leaves());
        w.u32(s.roots());
        w.len(s.levels().len());
        for l in s.levels() {
            w.u32(l.a);
            w.u32(l.b);
            w.u32(l.c);
        }
    }
}

fn write_lod(w: &mut Writer, lod: Option<&MeshLod>) {
    match lod {
        None => w.u8(0),
        Some(MeshLod::Leaves(table)) => {
            w.u8(1);
            write_table(w, table);
        }
        Some(MeshLod::Group(group)) => {
            w.u8(2);
            w.len(group.primitives().len());
            for p in group.primitives() {
                w.u32(p.primitive);
                write_table(w, &p.table);
            }
        }
    }
}

fn write_forest(w: &mut Writer, forest: Option<&ForestStats>) {
    let Some(f) = forest else {
        w.u8(0);
        return;
    };
    w.u8(1);
    w.u64(f.size[0].to_bits());
    w.u64(f.size[1].to_bits());
    w.u64(f.seed);
    match f.tile {
        None => w.u8(0),
        Some(t) => {
            w.u8(1);
            w.u64(t.to_bits());
        }
    }
    match &f.part {
        ForestPart::Tile(None) => w.u8(0),
        ForestPart::Tile(Some([i, j])) => {
            w.u8(1);
            w.u64(*i);
            w.u64(*j);
        }
        ForestPart::Merged(tiles) => {
            w.u8(2);
            w.len(tiles.len());
            for [i, j] in tiles {
                w.u64(*i);
                w.u64(*j);
            }
        }
    }
    w.u64(f.instances);
    w.len(f.species.len());
    for s in &f.species {
        w.str(&s.name);
        w.u64(s.variants);
        w.u64(s.count);
    }
}

fn read_table(r: &mut Reader) -> Option<LodTable> {
    let sectors = (0..r.len(20)?)
        .map(|_| {
            let (offset, leaves, roots) = (r.u32()?, r.u32()?, r.u32()?);
            let levels = (0..r.len(12)?)
                .map(|_| {
                    Some(LodLevel {
                        a: r.u32()?,
                        b: r.u32()?,
                        c: r.u32()?,
                    })
                })
                .collect::<Option<_>>()?;
            LodSector::new(offset, leaves, roots, levels).ok()
        })
        .collect::<Option<_>>()?;
    LodTable::new(sectors).ok()
}

fn read_lod(r: &mut Reader) -> Option<Option<MeshLod>> {
    Some(match r.u8()? {
        0 => None,
        1 => Some(MeshLod::Leaves(read_table(r)?)),
        2 => {
            let primitives = (0..r.len(12)?)
                .map(|_| {
                    Some(PrimitiveLod {
                        primitive: r.u32()?,
                        table: read_table(r)?,
                    })
                })
                .collect::<Option<_>>()?;
            Some(MeshLod::Group(GroupLod::new(primitives).ok()?))
        }
        _ => return None,
    })
}

fn read_forest(r: &mut Reader) -> Option<Option<ForestStats>> {
    if r.u8()? == 0 {
        return Some(None);
    }
    let size = [f64::from_bits(r.u64()?), f64::from_bits(r.u64()?)];
    let seed = r.u64()?;
    let tile = match r.u8()? {
        0 => None,
        1 => Some(f64::from_bits(r.u64()?)),
        _ => return None,
    };
    let part = match r.u8()? {
        0 => ForestPart::Tile(None),
        1 => ForestPart::Tile(Some([r.u64()?, r.u64()?])),
        2 => ForestPart::Merged(
            (0..r.len(16)?)
                .map(|_| Some([r.u64()?, r.u64()?]))
                .collect::<Option<_>>()?,
        ),
        _ => return None,
    };
    let instances = r.u64()?;
    let species = (0..r.len(24)?)
        .map(|_| {
            Some(SpeciesCount {
                name: r.str()?,
                variants: r.u64()?,
                count: r.u64()?,
            })
        })
        .collect::<Option<_>>()?;
    Some(Some(ForestStats {
        size,
        seed,
        tile,
        part,
        instances,
        species,
    }))
}

fn write_texture_ref(w: &mut Writer, textures: &mut Vec<Arc<Texture>>, t: Option<&Arc<Texture>>) {
    match t {
        Some(t) => {
            w.u8(1);
            let i = shared(textures, t);
            w.u32(i);
        }
        None => w.u8(0),
    }
}

fn read_texture_ref(r: &mut Reader, textures: &[Arc<Texture>]) -> Option<Option<Arc<Texture>>> {
    Some(match r.u8()? {
        0 => None,
        1 => Some(textures[r.index(textures.len())?].clone()),
        _ => return None,
    })
}

pub(crate) fn read_model(r: &mut Reader) -> Option<Model> {
    let textures: Vec<Arc<Texture>> = (0..r.len(16)?)
        .map(|_| {
            Some(Arc::new(Texture {
                name: r.str()?,
                width: r.u32()?,
                height: r.u32()?,
                png: r.bytes()?,
            }))
        })
        .collect::<Option<_>>()?;
    let materials: Vec<Arc<Material>> = (0..r.len(16)?)
        .map(|_| {
            let name = r.str()?;
            let base_color = [r.f32()?, r.f32()?, r.f32()?, r.f32()?];
            let texture = read_texture_ref(r, &textures)?;
            let normal_texture = read_texture_ref(r, &textures)?;
            let metallic_roughness_texture = read_texture_ref(r, &textures)?;
            let alpha = match r.u8()? {
                0 => AlphaMode::Opaque,
                1 => AlphaMode::Mask(r.f32()?),
                2 => AlphaMode::Blend,
                _ => return None,
            };
            Some(Arc::new(Material {
                name,
                base_color,
                texture,
                normal_texture,
                metallic_roughness_texture,
                alpha,
                double_sided: r.u8()? != 0,
                metallic: r.f32()?,
                roughness: r.f32()?,
                transmission: match r.u8()? {
                    0 => None,
                    1 => Some(DiffuseTransmission {
                        factor: r.f32()?,
                        color: [r.f32()?, r.f32()?, r.f32()?],
                    }),
                    _ => return None,
                },
            }))
        })
        .collect::<Option<_>>()?;
    let skeletons: Vec<Arc<Skeleton>> = (0..r.len(16)?)
        .map(|_| {
            let mut s = Skeleton::new();
            s.positions = r.vec3s()?;
            s.parents = (0..r.len(4)?)
                .map(|_| r.u32().map(|p| (p != u32::MAX).then_some(p)))
                .collect::<Option<_>>()?;
            s.radii = (0..r.len(4)?).map(|_| r.f32()).collect::<Option<_>>()?;
            s.orders = (0..r.len(4)?).map(|_| r.u32()).collect::<Option<_>>()?;
            for _ in 0..r.len(44)? {
                s.leaves.push(LeafPoint {
                    node: r.u32()?,
                    position: r.vec3()?,
                    direction: r.vec3()?,
                    side: r.vec3()?,
                    size: r.f32()?,
                });
            }
            Some(Arc::new(s))
        })
        .collect::<Option<_>>()?;
    let meshes: Vec<Arc<Mesh>> = (0..r.len(16)?)
        .map(|_| {
            let name = r.str()?;
            let primitive = match r.u8()? {
                0 => Primitive::Triangles,
                1 => Primitive::Lines,
                _ => return None,
            };
            let positions = r.vec3s()?;
            let normals = r.vec3s()?;
            let uvs = r.vec2s()?;
            let colors = r.vec4s()?;
            let indices = (0..r.len(4)?).map(|_| r.u32()).collect::<Option<_>>()?;
            let material = materials[r.index(materials.len())?].clone();
            let skeleton = match r.u8()? {
                0 => None,
                1 => Some(skeletons[r.index(skeletons.len())?].clone()),
                _ => return None,
            };
            let lod = read_lod(r)?.map(Arc::new);
            Some(Arc::new(Mesh {
                name,
                primitive,
                positions,
                normals,
                uvs,
                colors,
                indices,
                material,
                skeleton,
                lod,
                extras: r.map(0)?,
            }))
        })
        .collect::<Option<_>>()?;
    let instances = (0..r.len(68)?)
        .map(|_| {
            let mesh = r.index(meshes.len())?;
            let mut m = [0.0f32; 16];
            for x in &mut m {
                *x = r.f32()?;
            }
            Some(Instance {
                mesh,
                transform: Mat4::from_cols_array(&m),
            })
        })
        .collect::<Option<_>>()?;
    let groups = (0..r.len(24)?)
        .map(|_| {
            let name = r.str()?;
            let members = (0..r.len(4)?)
                .map(|_| r.index(meshes.len()))
                .collect::<Option<_>>()?;
            let transforms = (0..r.len(32)?)
                .map(|_| {
                    Some(InstanceTransform {
                        translation: [r.f32()?, r.f32()?, r.f32()?],
                        rotation: [r.f32()?, r.f32()?, r.f32()?, r.f32()?],
                        scale: r.f32()?,
                    })
                })
                .collect::<Option<_>>()?;
            let leaves = match r.u8()? {
                0 => None,
                1 => Some(PlacementLeaves {
                    roots: r.u32()?,
                    counts: (0..r.len(4)?).map(|_| r.u32()).collect::<Option<_>>()?,
                }),
                _ => return None,
            };
            Some(InstanceGroup {
                name,
                meshes: members,
                transforms,
                leaves,
            })
        })
        .collect::<Option<_>>()?;
    let forest = read_forest(r)?;
    let variant_counts = (0..r.len(16)?)
        .map(|_| {
            Some(VariantCounts {
                nodes: r.u64()?,
                leaves: r.u64()?,
            })
        })
        .collect::<Option<_>>()?;
    let extras = r.map(0)?;
    let stats = Stats {
        nodes: r.u64()?,
        leaves: r.u64()?,
        modules: r.u64()?,
        phases: Vec::new(),
        warnings: (0..r.len(8)?).map(|_| r.str()).collect::<Option<_>>()?,
    };
    let environment = read_texture_ref(r, &textures)?;
    Some(Model {
        meshes,
        instances,
        groups,
        forest,
        variant_counts,
        extras,
        stats,
        environment,
        clean: Vec::new(),
        skeleton_texts: Vec::new(),
    })
}
