//! The variant cache (`pge run --variant-cache DIR`): a species variant grown once is kept as
//! a file, so the tiles of a world (each a `pge run --tile` of its own) stop regrowing the
//! same trees.
//!
//! An entry is named by a 128-bit hash of everything a species session starts from: this
//! program's bytes, the species script's shown path and bytes, its `params` overrides, the
//! variant seed and the module cap. It holds that key in full (compared byte for byte), the
//! files the session read (modules, images: path, length and hash, checked again on every
//! hit), the grown [`Model`] in the engine's binary form ([`binary`]: exact, floats as their
//! bits, shared meshes, materials and textures kept shared) and a checksum. Entries are written to a
//! temporary file and renamed, so tiles running at once on one machine or one shared volume
//! never see half an entry. A damaged or foreign entry is a warning and the variant is grown
//! again; a write that fails is a warning too: the cache never changes the output.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use pge_engine::geometry::{Model, binary};

use pge_engine::random::{GOLDEN_GAMMA, splitmix64};

/// The first bytes of every entry; the last byte is the format's version.
const MAGIC: &[u8; 8] = b"PGEVAR\x00\x07";

/// Appends the numbers and strings of a key or an entry's head.
#[derive(Default)]
struct Writer(Vec<u8>);

impl Writer {
    fn u64(&mut self, x: u64) {
        self.0.extend_from_slice(&x.to_le_bytes());
    }
    fn len(&mut self, n: usize) {
        self.u64(n as u64);
    }
    fn bytes(&mut self, b: &[u8]) {
        self.len(b.len());
        self.0.extend_from_slice(b);
    }
    fn str(&mut self, s: &str) {
        self.bytes(s.as_bytes());
    }
}

/// Reads them back, `None` past the end.
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
    fn u64(&mut self) -> Option<u64> {
        Some(u64::from_le_bytes(self.take(8)?.try_into().ok()?))
    }
    /// A count of items of at least `size` bytes each, no more than the bytes left hold.
    fn len(&mut self, size: usize) -> Option<usize> {
        let n = usize::try_from(self.u64()?).ok()?;
        (n.checked_mul(size.max(1))? <= self.b.len() - self.at).then_some(n)
    }
    fn bytes(&mut self) -> Option<Vec<u8>> {
        let n = self.len(1)?;
        Some(self.take(n)?.to_vec())
    }
    fn str(&mut self) -> Option<String> {
        String::from_utf8(self.bytes()?).ok()
    }
}

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
            match read_regular(file) {
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
            && let Err(e) = entry(material, &files, &model)
                .map_err(std::io::Error::other)
                .and_then(|bytes| self.write(file, &bytes))
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

    /// Writes `bytes` to `file` through a temporary file renamed over it, created anew
    /// under a random name (`O_CREAT | O_EXCL`: a link planted in the folder is never
    /// followed); the rename replaces whatever `file` was, a link included, not its target.
    fn write(&self, file: &Path, bytes: &[u8]) -> std::io::Result<()> {
        use std::io::Write;
        std::fs::create_dir_all(&self.dir)?;
        let mut tmp = tempfile::Builder::new()
            .prefix(".pgevariant-")
            .suffix(".tmp")
            .tempfile_in(&self.dir)?;
        tmp.write_all(bytes)?;
        tmp.persist(file).map_err(|e| e.error)?;
        Ok(())
    }
}

/// The bytes of `file` when it is a regular file (not a link, a FIFO or a device: a link to
/// `/dev/zero` would never end, a FIFO would wait forever); `NotFound` when there is none.
fn read_regular(file: &Path) -> std::io::Result<Vec<u8>> {
    let meta = std::fs::symlink_metadata(file)?;
    if !meta.is_file() {
        return Err(std::io::Error::other(
            "not a regular file; it is skipped and the variant grown again",
        ));
    }
    std::fs::read(file)
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
        a = (a ^ w).wrapping_mul(GOLDEN_GAMMA).rotate_left(29);
        b = (b.rotate_left(17) ^ w).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    }
    let mut tail = [0u8; 8];
    tail[..chunks.remainder().len()].copy_from_slice(chunks.remainder());
    let w = u64::from_le_bytes(tail) ^ (bytes.len() as u64).rotate_left(56);
    let a = splitmix64(a ^ w);
    let b = splitmix64(b ^ splitmix64(w ^ a));
    [splitmix64(a ^ b.rotate_left(32)), b]
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
fn entry(key: &[u8], files: &[PathBuf], model: &Model) -> Result<Vec<u8>, binary::BinaryError> {
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
    w.0.extend_from_slice(&binary::encode(model)?);
    let [a, b] = digest(&w.0);
    w.u64(a);
    w.u64(b);
    Ok(w.0)
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
        // Only a regular file of the recorded length is read (an entry may name anything).
        if !std::fs::metadata(&path).is_ok_and(|m| m.is_file() && m.len() == len) {
            return Ok(None);
        }
        match std::fs::read(&path) {
            Ok(now) if now.len() as u64 == len && digest(&now) == [a, b] => {}
            _ => return Ok(None),
        }
    }
    // The model is the rest of the body.
    let model = binary::decode(&body[r.at..]).map_err(|_| damaged)?;
    Ok(Some(model))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Arc;

    use glam::{Mat4, Vec2, Vec3, Vec4};
    use pge_engine::geometry::{
        AlphaMode, ForestPart, ForestStats, GroupLod, InstanceGroup, InstanceTransform, LeafPoint,
        LodLevel, LodSector, LodTable, Material, Mesh, MeshLod, PlacementLeaves, Primitive,
        PrimitiveLod, Skeleton, SpeciesCount, Texture, VariantCounts,
    };

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
            "mine".into(),
            serde_json::json!([1, -2, 0.1, "x", null, {"a": true}]),
        );
        let level = |a, b, c| LodLevel { a, b, c };
        let sector = |offset| {
            let rows = vec![level(0, 4, 1), level(1, 3, 1), level(3, 5, 0)];
            LodSector::new(offset, 3, 1, rows).expect("sector")
        };
        let table = LodTable::new(vec![sector(0), sector(5)]).expect("table");
        mesh.lod = Some(Arc::new(MeshLod::Leaves(table.clone())));
        let mesh = Arc::new(mesh);
        let mut lines = (*mesh).clone();
        lines.primitive = Primitive::Lines;
        lines.skeleton = None;
        let group = GroupLod::new(vec![PrimitiveLod {
            primitive: 1,
            table,
        }]);
        lines.lod = Some(Arc::new(MeshLod::Group(group.expect("group"))));
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
            leaves: Some(PlacementLeaves {
                roots: 3,
                counts: vec![7],
            }),
        });
        model
            .extras
            .insert("seed".into(), serde_json::json!(u64::MAX));
        model.forest = Some(ForestStats {
            size: [60.0, 0.1],
            seed: u64::MAX,
            tile: Some(f64::MIN_POSITIVE),
            part: ForestPart::Merged(vec![[0, 1], [2, 3]]),
            instances: 4,
            species: vec![SpeciesCount {
                name: "oak".into(),
                variants: 2,
                count: 4,
            }],
        });
        model.variant_counts = vec![VariantCounts {
            nodes: 2,
            leaves: 1,
        }];
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
        assert_eq!(a.forest, b.forest);
        assert_eq!(a.variant_counts, b.variant_counts);
        assert_eq!(a.extras, b.extras);
        assert_eq!(a.stats, b.stats);
        assert_eq!(a.environment, b.environment);
    }

    #[test]
    fn an_entry_gives_back_the_model_bit_for_bit_with_its_sharing() {
        let model = sample();
        let bytes = entry(b"key", &[], &model).expect("entry");
        let back = read_entry(&bytes, b"key").expect("reads").expect("hit");
        same(&model, &back);
        assert!(Arc::ptr_eq(
            &back.meshes[0].material,
            &back.meshes[1].material
        ));
        assert_eq!(back.meshes[0].positions[2].z.to_bits(), (-0.0f32).to_bits());
        // The same model always makes the same entry.
        assert_eq!(entry(b"key", &[], &back).expect("entry"), bytes);
    }

    #[test]
    fn damaged_foreign_and_stale_entries_are_not_used() {
        let model = sample();
        let bytes = entry(b"key", &[], &model).expect("entry");
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
        let bytes = entry(b"key", std::slice::from_ref(&module), &model).expect("entry");
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

    #[cfg(unix)]
    #[test]
    fn planted_links_and_fifos_are_neither_followed_nor_read() {
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
        let grow = || -> Result<GrownVariant, ()> { Ok((sample(), vec![script.clone()])) };
        cache.variant(&key, "f.lua:2", grow).expect("grows");
        let entry = std::fs::read_dir(cache.dir())
            .expect("entries")
            .next()
            .expect("one entry")
            .expect("entry")
            .path();
        // The entry is a link to an endless device, then a FIFO: skipped with a warning
        // (reading either would never end), then replaced by a regular entry.
        std::fs::remove_file(&entry).expect("unlink");
        std::os::unix::fs::symlink("/dev/zero", &entry).expect("link");
        let model = cache.variant(&key, "f.lua:2", grow).expect("grows");
        let warning = model.stats.warnings.last().expect("a warning");
        assert!(warning.contains("not a regular file"), "{warning}");
        assert!(std::fs::symlink_metadata(&entry).expect("entry").is_file());
        std::fs::remove_file(&entry).expect("unlink");
        let made = std::process::Command::new("mkfifo").arg(&entry).status();
        assert!(made.expect("mkfifo").success());
        let model = cache.variant(&key, "f.lua:2", grow).expect("grows");
        assert!(
            model
                .stats
                .warnings
                .last()
                .expect("warns")
                .contains("not a regular file")
        );
        // A dangling link planted at the entry's name is replaced, its target never made.
        let outside = dir.path().join("outside");
        std::fs::remove_file(&entry).expect("unlink");
        std::os::unix::fs::symlink(&outside, &entry).expect("link");
        cache.variant(&key, "f.lua:2", grow).expect("grows");
        assert!(!outside.exists(), "the cache wrote through a planted link");
        assert!(std::fs::symlink_metadata(&entry).expect("entry").is_file());
        // No temporary file is left in the folder.
        assert_eq!(std::fs::read_dir(cache.dir()).expect("entries").count(), 1);
    }
}
