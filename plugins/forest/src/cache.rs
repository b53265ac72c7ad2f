//! The variant cache (`pge run --variant-cache DIR`): a species variant grown once is kept as
//! a file, so the tiles of a world (each a `pge run --tile` of its own) stop regrowing the
//! same trees.
//!
//! An entry is named by a 128-bit hash of everything a species session starts from: this
//! program's bytes, the species script's shown path and bytes, its `params` overrides, the
//! variant seed and the module cap. It holds that key in full (compared byte for byte), the
//! files the session read (modules, images: path, length and hash, checked again on every
//! hit), the grown [`Model`] in a small exact binary form (floats as their bits, shared
//! meshes, materials and textures kept shared) and a checksum. Entries are written to a
//! temporary file and renamed, so tiles running at once on one machine or one shared volume
//! never see half an entry. A damaged or foreign entry is a warning and the variant is grown
//! again; a write that fails is a warning too: the cache never changes the output.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, OnceLock};

use glam::{Mat4, Vec2, Vec3, Vec4};
use pge_engine::geometry::{
    AlphaMode, DiffuseTransmission, Instance, InstanceGroup, InstanceTransform, LeafPoint,
    Material, Mesh, Model, Primitive, Skeleton, Stats, Texture,
};
use serde_json::{Map, Number, Value};

use crate::rng::splitmix;

/// The first bytes of every entry; the last byte is the format's version.
const MAGIC: &[u8; 8] = b"PGEVAR\x00\x03";

/// A folder of grown variants shared by runs (and by processes: entries appear atomically).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct VariantCache {
    dir: PathBuf,
}

/// What determines a script species' variant, besides the files its session reads.
#[derive(Clone, Debug)]
pub struct VariantKey<'a> {
    /// The species script as the session is given it (relative to the working directory).
    pub shown: &'a str,
    /// `params` overrides as `--set` strings, sorted.
    pub params: &'a [(String, String)],
    /// The variant's seed.
    pub seed: u64,
    /// The module cap of the run.
    pub max_modules: usize,
}

/// A variant grown by its script, with the files its session read.
pub type GrownVariant = (Model, Vec<PathBuf>);

impl VariantCache {
    /// A cache in `dir` (created when the first entry is written).
    #[must_use]
    pub fn new(dir: impl Into<PathBuf>) -> VariantCache {
        VariantCache { dir: dir.into() }
    }

    /// The folder.
    #[must_use]
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The variant of `key`: read from the cache when an entry for it exists and every file
    /// it read is unchanged, else grown by `grow` and stored. Problems with the cache become
    /// warnings on the returned model (`where_: warning: ...`); errors of `grow` are returned.
    pub fn variant<E>(
        &self,
        key: &VariantKey,
        where_: &str,
        grow: impl FnOnce() -> Result<GrownVariant, E>,
    ) -> Result<Model, E> {
        let mut warnings = Vec::new();
        let material = match std::fs::read(key.shown) {
            Ok(script) => Some(key_bytes(key, &script)),
            Err(e) => {
                // The session reports an unreadable script itself; nothing to cache.
                warnings.push(format!("cannot read {} ({e})", key.shown));
                None
            }
        };
        let file = material.as_ref().map(|m| {
            let [a, b] = digest(m);
            self.dir.join(format!("{a:016x}{b:016x}.pgevariant"))
        });
        if let (Some(material), Some(file)) = (&material, &file) {
            match std::fs::read(file) {
                Ok(bytes) => match read_entry(&bytes, material) {
                    Ok(Some(model)) => return Ok(model),
                    Ok(None) => {} // a file it read has changed: grow again
                    Err(why) => warnings.push(format!(
                        "variant cache entry {} is {why}; growing the variant again",
                        file.display()
                    )),
                },
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
                Err(e) => warnings.push(format!("cannot read {} ({e})", file.display())),
            }
        }
        let (mut model, files) = grow()?;
        if let (Some(material), Some(file)) = (&material, &file)
            && let Err(e) = self.write(file, &entry(material, &files, &model))
        {
            warnings.push(format!(
                "cannot write the variant cache entry {} ({e})",
                file.display()
            ));
        }
        model.stats.warnings.extend(
            warnings
                .into_iter()
                .map(|w| format!("{where_}: warning: {w}")),
        );
        Ok(model)
    }

    /// Writes `bytes` to `file` through a temporary file renamed over it.
    fn write(&self, file: &Path, bytes: &[u8]) -> std::io::Result<()> {
        static COUNTER: AtomicU64 = AtomicU64::new(0);
        std::fs::create_dir_all(&self.dir)?;
        let name = file.file_name().map(|n| n.to_string_lossy().to_string());
        let tmp = self.dir.join(format!(
            ".{}.{}.{}.tmp",
            name.unwrap_or_default(),
            std::process::id(),
            COUNTER.fetch_add(1, Ordering::Relaxed)
        ));
        let written = std::fs::write(&tmp, bytes).and_then(|()| std::fs::rename(&tmp, file));
        if written.is_err() {
            let _ = std::fs::remove_file(&tmp);
        }
        written
    }
}

/// 128 bits of a well-mixed hash of `bytes` (not cryptographic: it names and checks entries
/// against accidents, and the key itself is compared in full).
fn digest(bytes: &[u8]) -> [u64; 2] {
    let (mut a, mut b) = (0x6a09_e667_f3bc_c908u64, 0xbb67_ae85_84ca_a73bu64);
    let mut chunks = bytes.chunks_exact(8);
    for c in &mut chunks {
        let mut w = [0u8; 8];
        w.copy_from_slice(c);
        let w = u64::from_le_bytes(w);
        a = (a ^ w).wrapping_mul(0x9e37_79b9_7f4a_7c15).rotate_left(29);
        b = (b.rotate_left(17) ^ w).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    }
    let mut tail = [0u8; 8];
    tail[..chunks.remainder().len()].copy_from_slice(chunks.remainder());
    let w = u64::from_le_bytes(tail) ^ (bytes.len() as u64).rotate_left(56);
    let a = splitmix(a ^ w);
    let b = splitmix(b ^ splitmix(w ^ a));
    [splitmix(a ^ b.rotate_left(32)), b]
}

/// The digest of this program (a rebuilt `pge` never reads another build's variants).
fn program() -> [u64; 2] {
    static PROGRAM: OnceLock<[u64; 2]> = OnceLock::new();
    *PROGRAM.get_or_init(|| {
        std::env::current_exe()
            .and_then(std::fs::read)
            .map_or([0, 0], |bytes| digest(&bytes))
    })
}

/// The key in full: program, version, script, parameters, seed, module cap.
fn key_bytes(key: &VariantKey, script: &[u8]) -> Vec<u8> {
    let mut w = Writer::default();
    let [a, b] = program();
    w.u64(a);
    w.u64(b);
    w.str(env!("CARGO_PKG_VERSION"));
    w.str(key.shown);
    w.bytes(script);
    w.len(key.params.len());
    for (k, v) in key.params {
        w.str(k);
        w.str(v);
    }
    w.u64(key.seed);
    w.u64(key.max_modules as u64);
    w.0
}

/// An entry: magic, key, the files read, the model, checksum.
fn entry(key: &[u8], files: &[PathBuf], model: &Model) -> Vec<u8> {
    let mut w = Writer::default();
    w.0.extend_from_slice(MAGIC);
    w.bytes(key);
    let read: Vec<(String, Vec<u8>)> = files
        .iter()
        .filter_map(|f| Some((f.to_string_lossy().to_string(), std::fs::read(f).ok()?)))
        .collect();
    w.len(read.len());
    for (path, bytes) in &read {
        w.str(path);
        w.u64(bytes.len() as u64);
        let [a, b] = digest(bytes);
        w.u64(a);
        w.u64(b);
    }
    write_model(&mut w, model);
    let [a, b] = digest(&w.0);
    w.u64(a);
    w.u64(b);
    w.0
}

/// The model of an entry for `key`: `Ok(None)` when a file the variant read has changed,
/// `Err` (why) when the entry is damaged or belongs to another key.
fn read_entry(bytes: &[u8], key: &[u8]) -> Result<Option<Model>, &'static str> {
    let damaged = "damaged";
    if bytes.len() < MAGIC.len() + 16 || &bytes[..MAGIC.len()] != MAGIC {
        return Err("not a variant of this version of pge");
    }
    let (body, sum) = bytes.split_at(bytes.len() - 16);
    let mut r = Reader { b: sum, at: 0 };
    if [r.u64().ok_or(damaged)?, r.u64().ok_or(damaged)?] != digest(body) {
        return Err(damaged);
    }
    let mut r = Reader {
        b: body,
        at: MAGIC.len(),
    };
    if r.bytes().ok_or(damaged)? != key {
        return Err("another variant's (a hash collision)");
    }
    for _ in 0..r.len(8).ok_or(damaged)? {
        let path = r.str().ok_or(damaged)?;
        let (len, a, b) = (
            r.u64().ok_or(damaged)?,
            r.u64().ok_or(damaged)?,
            r.u64().ok_or(damaged)?,
        );
        match std::fs::read(&path) {
            Ok(now) if now.len() as u64 == len && digest(&now) == [a, b] => {}
            _ => return Ok(None),
        }
    }
    let model = read_model(&mut r).ok_or(damaged)?;
    if r.at != body.len() {
        return Err(damaged);
    }
    Ok(Some(model))
}

#[derive(Default)]
struct Writer(Vec<u8>);

impl Writer {
    fn u8(&mut self, x: u8) {
        self.0.push(x);
    }
    fn u32(&mut self, x: u32) {
        self.0.extend_from_slice(&x.to_le_bytes());
    }
    fn u64(&mut self, x: u64) {
        self.0.extend_from_slice(&x.to_le_bytes());
    }
    fn len(&mut self, n: usize) {
        self.u64(n as u64);
    }
    fn f32(&mut self, x: f32) {
        self.u32(x.to_bits());
    }
    fn f32s(&mut self, xs: &[f32]) {
        for &x in xs {
            self.f32(x);
        }
    }
    fn bytes(&mut self, b: &[u8]) {
        self.len(b.len());
        self.0.extend_from_slice(b);
    }
    fn str(&mut self, s: &str) {
        self.bytes(s.as_bytes());
    }
    fn json(&mut self, v: &Value) {
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
    fn map(&mut self, m: &Map<String, Value>) {
        self.len(m.len());
        for (k, v) in m {
            self.str(k);
            self.json(v);
        }
    }
}

struct Reader<'a> {
    b: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn take(&mut self, n: usize) -> Option<&[u8]> {
        let end = self.at.checked_add(n)?;
        let s = self.b.get(self.at..end)?;
        self.at = end;
        Some(s)
    }
    fn u8(&mut self) -> Option<u8> {
        Some(self.take(1)?[0])
    }
    fn u32(&mut self) -> Option<u32> {
        Some(u32::from_le_bytes(self.take(4)?.try_into().ok()?))
    }
    fn u64(&mut self) -> Option<u64> {
        Some(u64::from_le_bytes(self.take(8)?.try_into().ok()?))
    }
    /// A count of items of at least `size` bytes each, no more than the bytes left hold.
    fn len(&mut self, size: usize) -> Option<usize> {
        let n = usize::try_from(self.u64()?).ok()?;
        (n.checked_mul(size.max(1))? <= self.b.len() - self.at).then_some(n)
    }
    fn f32(&mut self) -> Option<f32> {
        Some(f32::from_bits(self.u32()?))
    }
    fn bytes(&mut self) -> Option<Vec<u8>> {
        let n = self.len(1)?;
        Some(self.take(n)?.to_vec())
    }
    fn str(&mut self) -> Option<String> {
        String::from_utf8(self.bytes()?).ok()
    }
    fn index(&mut self, below: usize) -> Option<usize> {
        let i = self.u32()? as usize;
        (i < below).then_some(i)
    }
    fn vec2s(&mut self) -> Option<Vec<Vec2>> {
        (0..self.len(8)?)
            .map(|_| Some(Vec2::new(self.f32()?, self.f32()?)))
            .collect()
    }
    fn vec3(&mut self) -> Option<Vec3> {
        Some(Vec3::new(self.f32()?, self.f32()?, self.f32()?))
    }
    fn vec3s(&mut self) -> Option<Vec<Vec3>> {
        (0..self.len(12)?).map(|_| self.vec3()).collect()
    }
    fn vec4s(&mut self) -> Option<Vec<Vec4>> {
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
    fn json(&mut self, depth: u32) -> Option<Value> {
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
    fn map(&mut self, depth: u32) -> Option<Map<String, Value>> {
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

fn write_model(w: &mut Writer, model: &Model) {
    let Model {
        meshes,
        instances,
        groups,
        extras,
        stats,
        environment,
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

fn read_model(r: &mut Reader) -> Option<Model> {
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
            Some(InstanceGroup {
                name,
                meshes: members,
                transforms,
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
        extras,
        stats,
        environment,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Model {
        let texture = Arc::new(Texture::from_rgba("bark", 1, 1, &[10, 20, 30, 255]).expect("png"));
        let material = Arc::new(Material {
            texture: Some(texture.clone()),
            alpha: AlphaMode::Mask(0.25),
            ..Material::default()
        });
        let mut skeleton = Skeleton::new();
        let root = skeleton.push(Vec3::ZERO, None, 0.5, 0);
        skeleton.push(Vec3::Y, Some(root), 0.25, 1);
        skeleton.leaves.push(LeafPoint {
            node: 1,
            position: Vec3::Y,
            direction: Vec3::X,
            side: Vec3::Z,
            size: 0.1,
        });
        let mut mesh = Mesh::from_triangles(
            vec![Vec3::ZERO, Vec3::X, Vec3::new(0.0, f32::MIN_POSITIVE, -0.0)],
            vec![0, 1, 2],
        )
        .expect("mesh");
        mesh.name = "trunk".into();
        mesh.uvs = vec![Vec2::ZERO, Vec2::X, Vec2::Y];
        mesh.colors = vec![Vec4::ONE; 3];
        mesh.material = material.clone();
        mesh.skeleton = Some(Arc::new(skeleton));
        mesh.extras.insert(
            "lod".into(),
            serde_json::json!([1, -2, 0.1, "x", null, {"a": true}]),
        );
        let mesh = Arc::new(mesh);
        let mut lines = (*mesh).clone();
        lines.primitive = Primitive::Lines;
        lines.skeleton = None;
        let mut model = Model::from_mesh(mesh.clone());
        model.add_mesh(lines, Mat4::from_translation(Vec3::new(1.0, 2.0, 3.0)));
        model.groups.push(InstanceGroup {
            name: "g".into(),
            meshes: vec![0, 1],
            transforms: vec![InstanceTransform {
                translation: [1.0, 2.0, 3.0],
                rotation: [0.0, 0.0, 0.0, 1.0],
                scale: 2.0,
            }],
        });
        model
            .extras
            .insert("seed".into(), serde_json::json!(u64::MAX));
        model.stats.nodes = 2;
        model.stats.leaves = 1;
        model.stats.warnings.push("oak.lua:3: warning: thin".into());
        model.environment = Some(texture);
        model
    }

    fn same(a: &Model, b: &Model) {
        assert_eq!(a.meshes, b.meshes);
        assert_eq!(a.instances, b.instances);
        assert_eq!(a.groups, b.groups);
        assert_eq!(a.extras, b.extras);
        assert_eq!(a.stats, b.stats);
        assert_eq!(a.environment, b.environment);
    }

    #[test]
    fn an_entry_gives_back_the_model_bit_for_bit_with_its_sharing() {
        let model = sample();
        let bytes = entry(b"key", &[], &model);
        let back = read_entry(&bytes, b"key").expect("reads").expect("hit");
        same(&model, &back);
        assert!(Arc::ptr_eq(
            &back.meshes[0].material,
            &back.meshes[1].material
        ));
        assert_eq!(back.meshes[0].positions[2].z.to_bits(), (-0.0f32).to_bits());
        // The same model always makes the same entry.
        assert_eq!(entry(b"key", &[], &back), bytes);
    }

    #[test]
    fn damaged_foreign_and_stale_entries_are_not_used() {
        let model = sample();
        let bytes = entry(b"key", &[], &model);
        assert!(read_entry(&bytes, b"other").is_err());
        for cut in [0, 7, 20, bytes.len() / 2, bytes.len() - 1] {
            assert!(read_entry(&bytes[..cut], b"key").is_err(), "cut at {cut}");
        }
        let mut flipped = bytes.clone();
        flipped[bytes.len() / 2] ^= 1;
        assert!(read_entry(&flipped, b"key").is_err());
        let dir = tempfile::tempdir().expect("tempdir");
        let module = dir.path().join("module.lua");
        std::fs::write(&module, "return 1").expect("write");
        let bytes = entry(b"key", std::slice::from_ref(&module), &model);
        assert!(read_entry(&bytes, b"key").expect("reads").is_some());
        std::fs::write(&module, "return 2").expect("write");
        assert!(read_entry(&bytes, b"key").expect("reads").is_none());
    }

    #[test]
    fn a_cache_grows_once_and_warns_about_a_damaged_entry() {
        let dir = tempfile::tempdir().expect("tempdir");
        let script = dir.path().join("shrub.lua");
        std::fs::write(&script, "return nothing").expect("write");
        let shown = script.to_string_lossy().to_string();
        let key = VariantKey {
            shown: &shown,
            params: &[],
            seed: 5,
            max_modules: 100,
        };
        let cache = VariantCache::new(dir.path().join("cache"));
        let grown = std::cell::Cell::new(0);
        let grow = || -> Result<GrownVariant, ()> {
            grown.set(grown.get() + 1);
            Ok((sample(), vec![script.clone()]))
        };
        let first = cache.variant(&key, "f.lua:2", grow).expect("grows");
        let second = cache.variant(&key, "f.lua:2", grow).expect("reads");
        assert_eq!(grown.get(), 1);
        same(&first, &second);
        let other = VariantKey {
            seed: 6,
            ..key.clone()
        };
        cache.variant(&other, "f.lua:2", grow).expect("grows");
        assert_eq!(grown.get(), 2);
        for e in std::fs::read_dir(cache.dir()).expect("entries") {
            let path = e.expect("entry").path();
            std::fs::write(&path, [&MAGIC[..], b" not an entry at all"].concat()).expect("damage");
        }
        let again = cache.variant(&key, "f.lua:2", grow).expect("grows");
        assert_eq!(grown.get(), 3);
        let warning = again.stats.warnings.last().expect("a warning");
        assert!(
            warning.starts_with("f.lua:2: warning: variant cache entry"),
            "{warning}"
        );
        assert!(warning.contains("damaged"), "{warning}");
        // The damaged entry was replaced: the next run reads it.
        cache.variant(&key, "f.lua:2", grow).expect("reads");
        assert_eq!(grown.get(), 3);
        // A changed script is another key.
        std::fs::write(&script, "return something").expect("write");
        cache.variant(&key, "f.lua:2", grow).expect("grows");
        assert_eq!(grown.get(), 4);
    }
}
